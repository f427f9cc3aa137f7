// The four CCD methods behind vertex_face_ccd / edge_edge_ccd. ccd-notes.md sections 1-3.
#include <algorithm>
#include <cmath>

#include "drape/ccd/cubic_solver.h"
#include "problem.h"

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

using detail::Problem;

// How close the features must come to touch: the thickness plus the contact tolerance.
Scalar contact_distance(const Problem& p) { return detail::contact_distance(p.options, p.cubic); }

// The inside test of the root-finding methods at a candidate time: the closest points of the
// features there (the standard formulas) and their distance against the tolerance.
bool touching_at(const Problem& p, Scalar t, Result& result) {
  const auto x = detail::positions_at<Scalar>(p.query, t);
  Scalar distance_squared = 0;
  Vec2 params;
  if (p.kind == QueryKind::VertexFace) {
    const auto c = closest_point_triangle<Scalar>(x[0], x[1], x[2], x[3]);
    distance_squared = c.distance_squared;
    params = Vec2(c.weight_b, c.weight_c);
  } else {
    const auto c = closest_segment_segment<Scalar>(x[0], x[1], x[2], x[3]);
    distance_squared = c.distance_squared;
    params = Vec2(c.s, c.u);
  }
  const Scalar tolerance = contact_distance(p);
  if (!(distance_squared <= tolerance * tolerance)) return false;
  result.hit = true;
  result.toc = t;
  result.params = params;
  return true;
}

Result degenerate_path(const Problem& p) {
  Result r = detail::conservative_search(p, /*use_cubic=*/false);
  r.path = Path::Degenerate;
  return r;
}

// ---------------------------------------------------------------------------------------------
// Cubic: all real roots by the closed form, inside test at each in increasing order.

bool root_possible_at_start(const Problem& p) { return detail::root_possible_at_start(p.cubic); }
bool root_possible_at_end(const Problem& p) { return detail::root_possible_at_end(p.cubic); }

Result cubic_method(const Problem& p) {
  if (cubic_poorly_resolved(p.cubic)) return degenerate_path(p);
  Result result;
  result.path = Path::Solved;
  result.root_solves = 1;
  if (root_possible_at_start(p) && touching_at(p, 0.0, result)) return result;
  std::array<Scalar, 3> roots{};
  const int count = solve_cubic(to_power(p.cubic.b), roots);
  for (int i = 0; i < count; ++i) {
    if (roots[i] < 0 || roots[i] > 1) continue;
    if (touching_at(p, roots[i], result)) return result;
  }
  if (root_possible_at_end(p)) touching_at(p, 1.0, result);
  return result;
}

Result dnf_method(const Problem& p) {
  // Unreliable roots first, as cubic does: the filter must not cull what cubic would find.
  // (The sign cull of a resolved cubic came first, in one_query or elementary_ccd.)
  if (cubic_poorly_resolved(p.cubic)) return degenerate_path(p);
  return cubic_method(p);
}

// ---------------------------------------------------------------------------------------------
// Vincent: sign variations V of the Bernstein coefficients on an interval. V = 0: no root;
// V = 1: exactly one, refined inside its bracket; V >= 2: split at the midpoint (Vincent's
// theorem: splitting ends with V <= 1 unless there is a multiple root).

Result vincent_method(const Problem& p) {
  const Bernstein3& b = p.cubic.b;
  switch (detail::vincent_entry(p.cubic)) {
    case detail::VincentEntry::Degenerate: return degenerate_path(p);
    case detail::VincentEntry::Culled: return Result{};
    case detail::VincentEntry::Stage: break;
  }
  const int variations = sign_variations(b);
  // The separation stage: wherever the cubic may vanish, the features are apart. That covers
  // the ends too: a root within rounding of t = 0 or t = 1 lies in the first or last kept
  // interval, so the inside tests below would fail there as well.
  if (detail::stage_separates(p, contact_distance(p))) {
    Result apart;
    apart.path = Path::Separated;
    return apart;
  }
  Result result;
  if (root_possible_at_start(p)) {  // the features may start coplanar
    result.path = Path::Solved;
    if (touching_at(p, 0.0, result)) return result;
  }
  if (variations == 0 && !root_possible_at_end(p)) return result;
  result.path = Path::Solved;
  if (variations == 1) {
    // The common case after the cull: one root, bracketed by the ends of the step.
    result.root_solves = 1;
    if (touching_at(p, detail::refine_single_root<Scalar>(b, p.options.root_tolerance), result)) return result;
    if (root_possible_at_end(p)) touching_at(p, 1.0, result);
    return result;
  }

  struct Interval {
    Scalar lo, hi;
    Bernstein3 b;
    int depth;
  };
  constexpr int STACK_SIZE = 64;
  Interval stack[STACK_SIZE];
  int top = 0;
  stack[top++] = {0.0, 1.0, b, 0};
  result.path = Path::Solved;
  int solves = 0;
  const int max_depth = std::min(p.options.max_subdivision_depth, STACK_SIZE - 2);
  while (top > 0) {
    const Interval I = stack[--top];
    const int variations = sign_variations(I.b);
    const Scalar width = I.hi - I.lo;
    if (variations == 1) {
      ++solves;
      const Scalar s = detail::refine_single_root<Scalar>(I.b, p.options.root_tolerance / width);
      if (touching_at(p, I.lo + s * width, result)) break;
    } else if (variations >= 2) {
      if (I.depth >= max_depth) {
        // A tangential (multiple) root does not separate: test where it sits.
        result.path = Path::Degenerate;
        if (touching_at(p, I.lo + 0.5 * width, result)) break;
      } else {
        ++solves;
        Bernstein3 left, right;
        split_half(I.b, left, right);
        const Scalar mid = I.lo + 0.5 * width;
        stack[top++] = {mid, I.hi, right, I.depth + 1};
        stack[top++] = {I.lo, mid, left, I.depth + 1};
        continue;
      }
    }
    if (I.b[3] == 0 && touching_at(p, I.hi, result)) break;  // a root exactly at the end
  }
  if (!result.hit && root_possible_at_end(p)) touching_at(p, 1.0, result);
  result.root_solves = static_cast<std::uint16_t>(std::min(solves, 65535));
  return result;
}

bool filters(const Options& options) { return options.method == Method::Vincent || options.method == Method::Dnf; }

}  // namespace

Result detail::run_unculled(QueryKind kind, const Query& query, const Options& options,
                            const CoplanarityCubic& cubic, detail::StageAsked stage) {
  const Problem p{kind, query, options, cubic, stage};
  switch (options.method) {
    case Method::Cubic: return cubic_method(p);
    case Method::Dnf: return dnf_method(p);
    case Method::Vincent: return vincent_method(p);
    case Method::Conservative: return detail::conservative_search(p, /*use_cubic=*/true);
  }
  return Result{};
}

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
