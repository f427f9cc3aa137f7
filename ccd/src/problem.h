#pragma once
// Internal to ccd/: what every method needs about one elementary query.

#include <algorithm>
#include <cmath>

#include "drape/ccd/coplanarity.h"
#include "drape/ccd/distance.h"
#include "drape/ccd/query.h"
#include "avx2.h"

namespace drape::ccd::detail {

/// How much of the separation stage (roots_apart) the caller asked already: the batch asks it
/// four tests at a time. Nothing; its first question, the whole step's boxes, which were not
/// apart (need: the gap plus the rounding margin computed there, for the intervals below); or
/// all of it, which did not separate the features.
struct StageAsked {
  enum class Part { Nothing, WholeStep, All } part = Part::Nothing;
  Scalar need = 0;
};

struct Problem {
  QueryKind kind;
  const Query& query;
  const Options& options;
  CoplanarityCubic cubic;
  /// Vincent and conservative: what the caller asked of the separation stage.
  StageAsked stage = {};
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

// Rounding of a projected extent, in units of u times the largest coordinate times the axis's
// 1-norm: the position at a time (about 4 roundings of values up to twice the coordinate
// bound), the dot product (3 more), the subtraction of two projections, and the rounding of
// the distance the root-finding methods compute at a root (DISTANCE_ERROR_FACTOR of the
// conservative search, 32). 64 covers them with a factor of two to spare.
inline constexpr Scalar PROJECTION_ERROR_FACTOR = 64.0;

/// The separation stage widens each sub-interval's time range by this much on both sides before
/// the axis tests: the root-finding methods report a root within their tolerance (1e-13 of the
/// step) of where their computed cubic changes sign, which may lie just across a sub-interval's
/// end.
inline constexpr Scalar TIME_WIDENING = 0x1p-30;

/// The deepest tree of halvings of the separation stage (64 sub-intervals).
inline constexpr int MAX_SEPARATION_DEPTH = 6;

inline Scalar max_abs_coordinate(const Query& q) {
  Scalar m = 0;
  for (int i = 0; i < 4; ++i)
    m = std::max({m, q.start[i].lpNorm<Eigen::Infinity>(), q.end[i].lpNorm<Eigen::Infinity>()});
  return m;
}

/// Whether the features stay more than gap apart at every time in [lo, hi] (widened by 2^-30 of
/// the step on each side), shown by a separating axis: the coordinate axes, and axes from the
/// features' shape at the interval's midpoint (the in-plane normal of the triangle edge the
/// vertex lies farthest outside of; the two edges' normals in the plane of both). A linearly
/// moving point's projection on a fixed axis is linear in t, so its range over [lo, hi] is
/// spanned by its projections at lo and hi. Rounding is covered by a margin of 64 u times the largest
/// coordinate. separation.cpp.
bool apart_over(QueryKind kind, const Query& q, Scalar lo, Scalar hi, Scalar gap);

/// apart_over's first part, the coordinate axes over exactly [lo, hi]; need receives the gap
/// plus the rounding margin. AVX2 where avx2_enabled(), else portable: the same answers and
/// need for finite coordinates. separation.cpp.
bool coordinate_axes_apart(QueryKind kind, const Query& q, Scalar lo, Scalar hi, Scalar gap, Scalar& need);

/// The tree of halvings below b, depth levels deep (clamped to 1..6): bit i set when the
/// coefficients of sub-interval i (left to right, de Casteljau split_half at each level) are not
/// all beyond margin in one sign (certainly_nonzero fails). separation.cpp.
std::uint64_t kept_sub_intervals(const Bernstein3& b, Scalar margin, int depth);

/// The filter's separation stage. First the features' coordinate boxes over the whole step
/// (coordinate_axes_apart over [0, 1]): apart there, they are apart at every root. Otherwise the
/// step is halved depth times (de Casteljau, 2^depth sub-intervals, depth at most 6); a
/// sub-interval is dropped when the cubic certainly has no root on it (its coefficients exceed
/// twice their error bound and the rounding of any root finder's evaluation, in one sign), and
/// each run of adjacent kept sub-intervals (at most three) must be apart (apart_over). True
/// when they all are: at every root of the cubic in the step, computed or exact, the features
/// are more than gap apart. depth 0 (or less) returns false (no stage), and so does a run
/// covering the whole step.
/// With cubic_margin > 0 a sub-interval is dropped only where |cubic| certainly exceeds it too:
/// then the features are more than gap apart wherever |cubic| may be at most cubic_margin
/// (conservative with a thickness: cubic_margin = thickness |e1| |e2|, gap = thickness).
bool roots_apart(QueryKind kind, const Query& q, const CoplanarityCubic& cubic, Scalar gap, int depth,
                 Scalar cubic_margin = 0);

/// roots_apart after the whole step's boxes were found not apart (stage_runs held): the tree of
/// halvings and the runs' axis tests, with need the gap plus the rounding margin that
/// coordinate_axes_apart returned for the whole step. separation.cpp.
bool roots_apart_within(QueryKind kind, const Query& q, const CoplanarityCubic& cubic, Scalar need, int depth,
                        Scalar cubic_margin = 0);

/// Whether roots_apart goes past its first checks to the whole step's boxes: depth > 0 and a
/// finite cubic (a NaN or infinite coordinate makes b0 or b3 NaN or infinite, so every
/// coordinate of a query that passes is finite). A NaN coordinate would otherwise reach the
/// box tests, which the portable and AVX2 code read differently (std::min skips a NaN, minpd
/// may keep it), and nothing is apart where positions are unknown.
inline bool stage_runs(const CoplanarityCubic& cubic, int depth) {
  return depth > 0 && std::isfinite(cubic.b[0]) && std::isfinite(cubic.b[1]) && std::isfinite(cubic.b[2]) &&
         std::isfinite(cubic.b[3]);
}

/// The separation stage's gap for vincent (and the root finders' inside test): the thickness
/// plus the contact tolerance times the query's extent.
inline Scalar contact_distance(const Options& options, const CoplanarityCubic& cubic) {
  return options.thickness + options.contact_tolerance * cubic.extent;
}

/// coplanarity_cubic(kind, query) bit for bit, computed with AVX2: only where cpu_has_avx2
/// (elsewhere an illegal instruction). coplanarity.cpp.
CoplanarityCubic vertex_face_cubic_avx2(const Query& query);
CoplanarityCubic edge_edge_cubic_avx2(const Query& query);

/// filter_culls(coplanarity_cubic(kind, query)), computed with AVX2 (only where cpu_has_avx2);
/// when false, cubic receives the cubic, bit for bit (when true it is not written).
/// coplanarity.cpp.
bool vertex_face_culled_avx2(const Query& query, CoplanarityCubic& cubic);
bool edge_edge_culled_avx2(const Query& query, CoplanarityCubic& cubic);

/// coplanarity_cubic(kind, query) bit for bit, with AVX2 where the machine has it.
inline CoplanarityCubic query_cubic(QueryKind kind, const Query& query) {
#if DRAPE_X86_KERNELS
  if (avx2_enabled())
    return kind == QueryKind::VertexFace ? vertex_face_cubic_avx2(query) : edge_edge_cubic_avx2(query);
#endif
  return coplanarity_cubic(kind, query);
}

/// Whether the filter culls the query (filter_culls of its cubic); when not, cubic receives
/// the cubic (query_cubic's bits). With AVX2 where the machine has it: the one-query entry
/// points of dnf and vincent start here.
inline bool query_culled(QueryKind kind, const Query& query, CoplanarityCubic& cubic) {
#if DRAPE_X86_KERNELS
  if (avx2_enabled())
    return kind == QueryKind::VertexFace ? vertex_face_culled_avx2(query, cubic) : edge_edge_culled_avx2(query, cubic);
#endif
  cubic = coplanarity_cubic(kind, query);
  return filter_culls(cubic);
}

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

/// The separation stage for a problem (roots_apart), or what is left of it after what the
/// caller asked (p.stage): vincent with the contact distance as the gap, conservative with the
/// thickness and its share of the cubic.
inline bool stage_separates(const Problem& p, Scalar gap, Scalar cubic_margin = 0) {
  switch (p.stage.part) {
    case StageAsked::Part::Nothing:
      return roots_apart(p.kind, p.query, p.cubic, gap, p.options.separation_depth, cubic_margin);
    case StageAsked::Part::WholeStep:
      return roots_apart_within(p.kind, p.query, p.cubic, p.stage.need, p.options.separation_depth, cubic_margin);
    case StageAsked::Part::All: break;
  }
  return false;  // the caller's stage did not separate them
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
/// stage: see Problem.
Result run_unculled(QueryKind kind, const Query& query, const Options& options, const CoplanarityCubic& cubic,
                    StageAsked stage = {});

/// The conservative method, and the degenerate path of the others (use_cubic = false: the
/// cubic says nothing, decide by distance alone).
Result conservative_search(const Problem& p, bool use_cubic);

/// Root of a cubic with exactly one root on its interval (a sign change between the ends), in
/// the interval's local coordinate s in [0, 1]: safeguarded Newton (rtsafe, Numerical Recipes
/// section 9.4) inside the sign bracket, to within tolerance.
template <class T>
T refine_single_root(const std::array<T, 4>& b, T tolerance) {
  constexpr int MAX_ITERATIONS = 100;  // bisection alone halves the bracket 100 times
  const std::array<T, 4> a{b[0], 3 * (b[1] - b[0]), 3 * (b[2] - 2 * b[1] + b[0]), b[3] - 3 * b[2] + 3 * b[1] - b[0]};
  // The sign just right of s = 0 is that of the first nonzero coefficient.
  const T first = b[0] != 0 ? b[0] : (b[1] != 0 ? b[1] : b[2]);
  const bool negative_at_lo = first < 0;
  // Start at the midpoint: a secant start lands next to an end whose value is tiny, where the
  // computed sign may be wrong and the bracket would lose the root (found by the agreement test).
  T lo = 0, hi = 1, s = T(0.5);
  for (int iteration = 0; iteration < MAX_ITERATIONS; ++iteration) {
    const T f = ((a[3] * s + a[2]) * s + a[1]) * s + a[0];
    if (f == 0) return s;
    if ((f < 0) == negative_at_lo) lo = s; else hi = s;
    if (hi - lo <= tolerance) break;
    const T slope = (3 * a[3] * s + 2 * a[2]) * s + a[1];
    const T next = slope != 0 ? s - f / slope : lo;
    if (!(next > lo && next < hi)) {
      // Newton left the bracket: bisect. Where the midpoint rounds to s (a bound now), lo and
      // hi are adjacent numbers and every further iteration repeats this one, with the same
      // answer at the end: return it now (a tolerance below the spacing of the numbers near
      // the root, as the conservative search's monotone windows ask, would take all
      // MAX_ITERATIONS).
      const T mid = T(0.5) * (lo + hi);
      if (mid == s) break;
      s = mid;
    } else if (std::abs(next - s) <= tolerance) {
      return next;  // Newton converged
    } else {
      s = next;
    }
  }
  return T(0.5) * (lo + hi);
}

}  // namespace drape::ccd::detail
