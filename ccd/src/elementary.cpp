// The entry points of the four CCD methods (vertex_face_ccd, edge_edge_ccd, elementary_ccd) and
// what the methods share: the inside test and the degenerate path. The methods themselves:
// cubic_method.cpp, vincent_method.cpp, conservative.cpp.
#include <algorithm>
#include <cmath>

#include "methods.h"

namespace drape::ccd {

std::string_view method_name(Method method) {
  switch (method) {
    case Method::Cubic: return "cubic";
    case Method::Dnf: return "dnf";
    case Method::Vincent: return "vincent";
    case Method::Conservative: return "conservative";
  }
  return "?";
}

std::string_view kind_name(QueryKind kind) {
  return kind == QueryKind::VertexFace ? "vertex-face" : "edge-edge";
}

std::optional<Method> parse_method(std::string_view name) {
  for (Method m : ALL_METHODS)
    if (method_name(m) == name) return m;
  return std::nullopt;
}


namespace {

bool filters(const Options& options) { return options.method == Method::Vincent || options.method == Method::Dnf; }

}  // namespace

namespace detail {

// The inside test of the root-finding methods at a candidate time: the closest points of the
// features there (the standard formulas) and their distance against the tolerance.
ClosestAt closest_at(QueryKind kind, const Query& query, Scalar t) {
  const auto x = positions_at<Scalar>(query, t);
  if (kind == QueryKind::VertexFace) {
    const auto c = closest_point_triangle<Scalar>(x[0], x[1], x[2], x[3]);
    return {c.distance_squared, Vec2(c.weight_b, c.weight_c)};
  }
  const auto c = closest_segment_segment<Scalar>(x[0], x[1], x[2], x[3]);
  return {c.distance_squared, Vec2(c.s, c.u)};
}

bool touching_at(const Problem& p, Scalar t, Result& result) {
  const ClosestAt closest = closest_at(p.kind, p.query, t);
  const Scalar tolerance = contact_distance(p.options, p.cubic);
  if (!(closest.distance_squared <= tolerance * tolerance)) return false;
  result.hit = true;
  result.toc = t;
  result.params = closest.params;
  return true;
}

Result degenerate_path(const Problem& p) {
  Result r = conservative_search(p, /*use_cubic=*/false);
  r.path = Path::Degenerate;
  return r;
}

Result run_unculled(QueryKind kind, const Query& query, const Options& options, const CoplanarityCubic& cubic,
                    std::optional<bool> stage_separated) {
  const Problem p{kind, query, options, cubic, stage_separated};
  Result result;
  switch (options.method) {
    case Method::Cubic: result = cubic_method(p); break;
    case Method::Dnf: result = dnf_method(p); break;
    case Method::Vincent: result = vincent_method(p); break;
    case Method::Conservative: result = conservative_search(p, /*use_cubic=*/true); break;
  }
  // Every hit's parameters are the closest points' at its time of contact, whichever path
  // found it (the interval searches find theirs at a nearby time, by another distance
  // routine), so that a caller builds its contact from them; hits are few, and touching_at's
  // are these already.
  if (result.hit) result.params = closest_at(kind, query, result.toc).params;
  return result;
}

}  // namespace detail

namespace {

using detail::run_unculled;

// One query: the filter's cull first (dnf and vincent), decided with the cubic in one go; most
// tests of a cloth step end there, before anything else is set up.
Result one_query(QueryKind kind, const Query& query, const Options& options) {
  if (!filters(options)) return run_unculled(kind, query, options, detail::query_cubic(kind, query));
  CoplanarityCubic cubic;
  if (detail::query_culled(kind, query, cubic)) return Result{};
  return run_unculled(kind, query, options, cubic);
}

}  // namespace

Result vertex_face_ccd(const VertexFaceQuery& query, const Options& options) {
  return one_query(QueryKind::VertexFace, query, options);
}

Result edge_edge_ccd(const EdgeEdgeQuery& query, const Options& options) {
  return one_query(QueryKind::EdgeEdge, query, options);
}

Result elementary_ccd(QueryKind kind, const Query& query, const Options& options) {
  return one_query(kind, query, options);
}

Result elementary_ccd(QueryKind kind, const Query& query, const Options& options, const CoplanarityCubic& cubic) {
  if (filters(options) && filter_culls(cubic)) return Result{};
  return run_unculled(kind, query, options, cubic);
}

}  // namespace drape::ccd
