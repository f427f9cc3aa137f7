#pragma once
// Internal to ccd/: the filter's separation stage (separation.cpp, ccd.md "The separation
// stage"): where the coplanarity cubic may vanish in the step, separating axes show the
// features apart there.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "drape/ccd/coplanarity.h"
#include "drape/ccd/query.h"

namespace drape::ccd::detail {

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
/// plus the rounding margin. The same answers and need on every SIMD target for finite
/// coordinates (kernels.h). separation.cpp.
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
/// box tests, and nothing is apart where positions are unknown.
inline bool stage_runs(const CoplanarityCubic& cubic, int depth) {
  return depth > 0 && std::isfinite(cubic.b[0]) && std::isfinite(cubic.b[1]) && std::isfinite(cubic.b[2]) &&
         std::isfinite(cubic.b[3]);
}

/// The largest coordinate magnitude the stage answers for. A finite cubic bounds the
/// coordinates' differences, not the coordinates: beyond this the shape axes' projections (the
/// cube of a coordinate) could overflow, an infinity would answer for a position, and the
/// targets' minima and maxima of a NaN would differ. Nothing is apart there.
inline constexpr Scalar STAGE_COORDINATE_LIMIT = 1e100;

/// stage_runs, and every coordinate of the query within STAGE_COORDINATE_LIMIT.
inline bool stage_runs(const Query& q, const CoplanarityCubic& cubic, int depth) {
  return stage_runs(cubic, depth) && max_abs_coordinate(q) <= STAGE_COORDINATE_LIMIT;
}

/// coordinate_axes_apart's box test in portable code (separation.cpp), which
/// one_query_boxes_apart (kernels.h) runs on targets without four lanes of doubles.
bool boxes_apart_scalar(QueryKind kind, const Query& q, Scalar lo, Scalar hi, bool need_given, Scalar& need);

}  // namespace drape::ccd::detail
