#pragma once
// Internal to ccd/: the methods' entry: what every method needs about one elementary query, and
// where each method goes with its cubic. The methods: cubic and dnf (cubic_method.cpp), vincent
// (vincent_method.cpp), conservative (conservative.cpp); the entry points (elementary.cpp).

#include <algorithm>
#include <cmath>
#include <optional>

#include "drape/ccd/coplanarity.h"
#include "drape/ccd/distance.h"
#include "drape/ccd/query.h"
#include "separation.h"

namespace drape::ccd::detail {

struct Problem {
  QueryKind kind;
  const Query& query;
  const Options& options;
  CoplanarityCubic cubic;
  /// Vincent and conservative: the separation stage's answer when the caller computed it (the
  /// batch); empty, the method asks it.
  std::optional<bool> stage_separated = std::nullopt;
};

/// Positions of the four points at time t, in precision T.
template <class T>
std::array<Vector3<T>, 4> positions_at(const Query& q, T t) {
  std::array<Vector3<T>, 4> x;
  for (int i = 0; i < 4; ++i) {
    const Vector3<T> start = q.start[i].template cast<T>();
    x[i] = start + t * (q.end[i].template cast<T>() - start);
  }
  return x;
}

/// Distance between the two features at time t, with its conditioning error bound and the
/// contact parameters there.
template <class T>
struct Proximity {
  T distance = 0;
  T error = 0;
  Vec2 params = Vec2::Zero();
};

template <class T>
Proximity<T> proximity_at(QueryKind kind, const Query& q, T t) {
  const auto x = positions_at<T>(q, t);
  const auto d = kind == QueryKind::VertexFace ? point_triangle_distance<T>(x[0], x[1], x[2], x[3])
                                               : segment_segment_distance<T>(x[0], x[1], x[2], x[3]);
  return Proximity<T>{d.distance, d.error, Vec2(Scalar(d.param0), Scalar(d.param1))};
}

/// The separation stage's gap for vincent (and the root finders' inside test): the thickness
/// plus the contact tolerance times the query's extent.
inline Scalar contact_distance(const Options& options, const CoplanarityCubic& cubic) {
  return options.thickness + options.contact_tolerance * cubic.extent;
}

/// coplanarity_cubic(kind, query) bit for bit, by the SIMD kernel (kernels.h).
CoplanarityCubic query_cubic(QueryKind kind, const Query& query);

/// Whether the filter culls the query (filter_culls of its cubic); when not, cubic receives
/// the cubic (query_cubic's bits). The one-query entry points of dnf and vincent start here.
bool query_culled(QueryKind kind, const Query& query, CoplanarityCubic& cubic);

/// A root of the cubic within its rounding error of an end of the step: the features may touch
/// right at t = 0 or t = 1 (resting contact), whatever sign rounding gave the end coefficient.
inline bool root_possible_at_start(const CoplanarityCubic& c) { return std::abs(c.b[0]) <= c.error; }
inline bool root_possible_at_end(const CoplanarityCubic& c) { return std::abs(c.b[3]) <= c.error; }

/// Where vincent goes with a cubic the sign cull left: the degenerate path when the cubic is
/// poorly resolved (as cubic does), culled when no sign varies and no root is possible at
/// either end of the step, else the separation stage (roots_apart). Shared by vincent_method
/// (elementary.cpp) and the batch, which asks the stage's first question itself.
enum class VincentEntry { Degenerate, Culled, Stage };
inline VincentEntry vincent_entry(const CoplanarityCubic& cubic) {
  // Unreliable roots first, as cubic does: the filter must not cull what cubic would find.
  if (cubic_poorly_resolved(cubic)) return VincentEntry::Degenerate;
  // (The sign cull came first, in one_query, elementary_ccd or the batch.)
  if (sign_variations(cubic.b) == 0 && !root_possible_at_start(cubic) && !root_possible_at_end(cubic))
    return VincentEntry::Culled;
  return VincentEntry::Stage;
}

/// The separation stage for a problem: the caller's answer when it computed it (the batch's
/// kernel and roots_apart_within), else roots_apart; vincent with the contact distance as the
/// gap, conservative with the thickness and its share of the cubic.
inline bool stage_separates(const Problem& p, Scalar gap, Scalar cubic_margin = 0) {
  if (p.stage_separated) return *p.stage_separated;
  return roots_apart(p.kind, p.query, p.cubic, gap, p.options.separation_depth, cubic_margin);
}

/// Where conservative goes with its cubic (not the degenerate path of the other methods): its
/// first question ends the test (culled) when the cubic, off by at most its error plus
/// thickness_share (thickness_to_cubic in conservative.cpp, 0 at zero thickness), stays nonzero
/// over the step; else the separation stage when the cubic is resolved; else the search.
enum class ConservativeEntry { Culled, Stage, Search };
inline ConservativeEntry conservative_entry(const CoplanarityCubic& cubic, Scalar thickness_share) {
  if (certainly_nonzero(cubic.b, cubic.error + thickness_share)) return ConservativeEntry::Culled;
  return cubic_poorly_resolved(cubic) ? ConservativeEntry::Search : ConservativeEntry::Stage;
}

/// elementary_ccd with the cubic, for a test the filter does not cull (dnf and vincent: the
/// caller has checked filter_culls) or whose method has no filter: the batch, whose kernel
/// decided the cull already. elementary.cpp.
/// stage_separated: see Problem.
Result run_unculled(QueryKind kind, const Query& query, const Options& options, const CoplanarityCubic& cubic,
                    std::optional<bool> stage_separated = std::nullopt);

/// The conservative method, and the degenerate path of the others (use_cubic = false: the
/// cubic says nothing, decide by distance alone).
Result conservative_search(const Problem& p, bool use_cubic);

/// The inside test of the root-finding methods at time t: the features' closest points there
/// and their distance against the contact distance; on a hit, result gets the time and the
/// contact parameters. elementary.cpp.
bool touching_at(const Problem& p, Scalar t, Result& result);

/// The features' closest points at time t: their squared distance and the contact parameters
/// there (Result::params).
struct ClosestAt {
  Scalar distance_squared = 0;
  Vec2 params = Vec2::Zero();
};
ClosestAt closest_at(QueryKind kind, const Query& query, Scalar t);

/// The degenerate path of cubic, dnf and vincent: the conservative search by distance alone.
/// elementary.cpp.
Result degenerate_path(const Problem& p);

/// The methods (cubic_method.cpp, vincent_method.cpp; conservative_search above).
Result cubic_method(const Problem& p);
Result dnf_method(const Problem& p);
Result vincent_method(const Problem& p);

}  // namespace drape::ccd::detail
