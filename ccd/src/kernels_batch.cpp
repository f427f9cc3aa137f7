// The batch kernels: a chunk's cubics and the filter's decisions, and the separation stage, a
// test per lane, so the same source runs 1 (Highway's portable HWY_SCALAR), 2 (SSE4, or the
// portable EMU128 of newer compilers), 4 (AVX2) or 8 (AVX-512) tests at a time.
// Written once against Google Highway: foreach_target.h compiles this file once per instruction
// set, HWY_EXPORT tables the kernels and HWY_DYNAMIC_DISPATCH calls the best one the machine runs
// (kernels.h). The lane helpers and the rule that every target gives the scalar code's bits are in
// lanes-inl.h.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "kernels_batch.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <limits>

#include "kernels.h"
#include "lanes-inl.h"
#include "separation.h"

HWY_BEFORE_NAMESPACE();
namespace drape::ccd::detail::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// ---------------------------------------------------------------------------------------
// The cubics of a chunk (coplanarity_cubic_in and filter_culls, and with APART the
// conservative method's first question), N tests at a time.

template <QueryKind kind, Apart APART, class Pair>
HWY_INLINE void CubicsN(const BatchInput& input, const Pair* const (&pair)[N], Scalar thickness, ChunkCubics& c,
                        std::size_t i, std::uint64_t& culled_bits, std::uint64_t& apart_bits) {
  const D d;
  constexpr std::array<int, 4> order = coplanarity_order(kind);
  const Vec3 *start = input.start.data(), *end = input.end.data();
  const Lanes3 s1 = LoadPoint(start, pair, order[0]), e1 = LoadPoint(end, pair, order[0]);
  const Lanes3 A0 = LoadPoint(start, pair, order[1]) - s1, A1 = LoadPoint(end, pair, order[1]) - e1;
  const Lanes3 s3 = LoadPoint(start, pair, order[2]), e3 = LoadPoint(end, pair, order[2]);
  const Lanes3 s4 = LoadPoint(start, pair, order[3]), e4 = LoadPoint(end, pair, order[3]);
  const Lanes3 B0 = s3 - s1, B1 = e3 - e1;
  const Lanes3 C0 = s4 - s1, C1 = e4 - e1;
  const Lanes3 b0c0 = Cross(B0, C0), b1c0 = Cross(B1, C0), b0c1 = Cross(B0, C1), b1c1 = Cross(B1, C1);
  const V three = hn::Set(d, 3.0);
  const V k0 = Dot(A0, b0c0);
  const V k1 = ((Dot(A1, b0c0) + Dot(A0, b1c0)) + Dot(A0, b0c1)) / three;
  const V k2 = ((Dot(A1, b1c0) + Dot(A1, b0c1)) + Dot(A0, b1c1)) / three;
  const V k3 = Dot(A1, b1c1);
  const V a = LargerNorm1(A0, A1), b = LargerNorm1(B0, B1), cc = LargerNorm1(C0, C1);
  const V e = ((hn::Set(d, Scalar(COPLANARITY_ERROR_FACTOR) * UNIT_ROUNDOFF) * a) * b) * cc;
  hn::Store(k0, d, &c.coefficient[0][i]);
  hn::Store(k1, d, &c.coefficient[1][i]);
  hn::Store(k2, d, &c.coefficient[2][i]);
  hn::Store(k3, d, &c.coefficient[3][i]);
  hn::Store(e, d, &c.error[i]);
  hn::Store(StdMax(StdMax(a, b), cc), d, &c.extent[i]);
  M resolved;
  culled_bits |= Bits(d, FilterCulls(k0, k1, k2, k3, e, resolved)) << i;
  if constexpr (APART != Apart::No) {
    // The margin: the error, plus with a thickness conservative.cpp's thickness_to_cubic (the
    // longer of each of two edges at the two ends of the step: the vertex-face test's triangle
    // edges from its first vertex, A and B; the edge-edge test's edges, A and x4 - x3).
    V m = e;
    if constexpr (APART == Apart::WithThickness) {
      const V first = StdMax(Norm(A0), Norm(A1));
      const V second = kind == QueryKind::VertexFace ? StdMax(Norm(B0), Norm(B1)) : StdMax(Norm(s4 - s3), Norm(e4 - e3));
      const V share = (hn::Set(d, thickness) * (first * second)) * hn::Set(d, 1 + 16 * UNIT_ROUNDOFF);
      m = e + share;
    }
    apart_bits |= Bits(d, hn::And(resolved, CertainlyNonzero({k0, k1, k2, k3}, m))) << i;
  }
}

template <QueryKind kind, Apart APART, class Pair>
void CubicsChunk(const BatchInput& input, const Pair* pairs, std::size_t n, Scalar thickness, ChunkCubics& c) {
  std::uint64_t culled_bits = 0, apart_bits = 0;
  for (std::size_t i = 0; i < n; i += N) {
    const Pair* pair[N];  // a tail repeats the last test; its bits are dropped below
    for (std::size_t j = 0; j < N; ++j) pair[j] = pairs + std::min(i + j, n - 1);
    CubicsN<kind, APART>(input, pair, thickness, c, i, culled_bits, apart_bits);
  }
  c.culled = culled_bits & chunk_bits(n);
  c.certainly_apart = apart_bits & chunk_bits(n);
}

template <QueryKind kind, class Pair>
void Cubics(const BatchInput& input, const Pair* pairs, std::size_t n, Apart apart, Scalar thickness,
            ChunkCubics& c) {
  switch (apart) {
    case Apart::No: return CubicsChunk<kind, Apart::No>(input, pairs, n, thickness, c);
    case Apart::AtZeroThickness: return CubicsChunk<kind, Apart::AtZeroThickness>(input, pairs, n, thickness, c);
    case Apart::WithThickness: return CubicsChunk<kind, Apart::WithThickness>(input, pairs, n, thickness, c);
  }
}

void CubicsVertexFace(const BatchInput& input, const VertexFacePair* pairs, std::size_t n, Apart apart,
                      Scalar thickness, ChunkCubics& c) {
  Cubics<QueryKind::VertexFace>(input, pairs, n, apart, thickness, c);
}
void CubicsEdgeEdge(const BatchInput& input, const EdgeEdgePair* pairs, std::size_t n, Apart apart,
                    Scalar thickness, ChunkCubics& c) {
  Cubics<QueryKind::EdgeEdge>(input, pairs, n, apart, thickness, c);
}

// ---------------------------------------------------------------------------------------
// The separation stage (separation.cpp), a test per lane.

// Ranges [a_lo, a_hi] and [b_lo, b_hi] farther apart than need, lane by lane.
HWY_INLINE M ApartRanges(V a_lo, V a_hi, V b_lo, V b_hi, V need) {
  return hn::Or(hn::Gt(b_lo - a_hi, need), hn::Gt(a_lo - b_hi, need));
}

// [box_lo, box_hi] widened to hold [lo, hi].
HWY_INLINE void MergeBox(Lanes3& box_lo, Lanes3& box_hi, const Lanes3& lo, const Lanes3& hi) {
  box_lo = {StdMin(box_lo.x, lo.x), StdMin(box_lo.y, lo.y), StdMin(box_lo.z, lo.z)};
  box_hi = {StdMax(box_hi.x, hi.x), StdMax(box_hi.y, hi.y), StdMax(box_hi.z, hi.z)};
}

// Lane j of a value of N of the left tests.
template <class F>
HWY_INLINE V FromTests(const Left* const (&test)[N], F value) {
  HWY_ALIGN double lanes[N];
  for (std::size_t j = 0; j < N; ++j) lanes[j] = value(*test[j]);
  return hn::Load(D(), lanes);
}

// Whether each test goes on to the stage, from its cubic b and error: stage_runs (every
// coefficient finite) and the method's entry gives Stage: vincent's (vincent_entry: resolved,
// and the signs vary (a coefficient above zero and another below, as sign_variations skips
// zeros) or a root is possible at an end) or conservative's at zero thickness
// (conservative_entry: resolved, and not certainly nonzero). Only finite lanes need the others'
// bits: among finite coefficients the largest magnitude is the same in any order.
template <bool VINCENT>
HWY_INLINE M ReachesStage(const V (&b)[4], V error) {
  const D d;
  const V zero = hn::Zero(d), infinity = hn::Set(d, std::numeric_limits<Scalar>::infinity());
  V magnitude[4], largest = zero;
  M finite = hn::Lt(hn::Abs(b[0]), infinity), above = hn::Gt(b[0], zero), below = hn::Lt(b[0], zero);
  for (int k = 0; k < 4; ++k) {
    magnitude[k] = hn::Abs(b[k]);
    finite = hn::And(finite, hn::Lt(magnitude[k], infinity));
    largest = StdMax(largest, magnitude[k]);
    above = hn::Or(above, hn::Gt(b[k], zero));
    below = hn::Or(below, hn::Lt(b[k], zero));
  }
  const M poorly_resolved = hn::Le(largest, hn::Set(d, POORLY_RESOLVED_RATIO) * error);
  M onward;
  if constexpr (VINCENT) {
    const M at_an_end = hn::Or(hn::Le(magnitude[0], error), hn::Le(magnitude[3], error));
    onward = hn::Or(hn::And(above, below), at_an_end);
  } else {
    onward = hn::Not(CertainlyNonzero(b, error + zero));  // not certainly_nonzero(b, error + 0)
  }
  return hn::And(finite, hn::AndNot(poorly_resolved, onward));
}

// The box of point `point` of N tests over the whole step, and largest raised to its
// coordinates' magnitudes (as one_query_boxes_apart over [0, 1]: start + 1 * motion).
template <class Pair>
HWY_INLINE void PointBox(const BatchInput& input, const Pair* const (&pair)[N], int point, Lanes3& lo, Lanes3& hi,
                         V& largest) {
  const Lanes3 s = LoadPoint(input.start.data(), pair, point), e = LoadPoint(input.end.data(), pair, point);
  const Lanes3 x1 = {s.x + (e.x - s.x), s.y + (e.y - s.y), s.z + (e.z - s.z)};
  lo = {StdMin(s.x, x1.x), StdMin(s.y, x1.y), StdMin(s.z, x1.z)};
  hi = {StdMax(s.x, x1.x), StdMax(s.y, x1.y), StdMax(s.z, x1.z)};
  largest = StdMax(largest, StdMax(StdMax(StdMax(hn::Abs(s.x), hn::Abs(e.x)), StdMax(hn::Abs(s.y), hn::Abs(e.y))),
                                   StdMax(hn::Abs(s.z), hn::Abs(e.z))));
}

// The tree of halvings below b, DEPTH levels deep (kept_leaves in separation.cpp): lane l of
// kept (a 64-bit integer per lane) gets bit first + i when its sub-interval i may hold a root.
template <int DEPTH, class VU>
HWY_INLINE void KeptLeaves(const V (&b)[4], V margin, int first, VU& kept) {
  if constexpr (DEPTH == 0) {
    const hn::RebindToUnsigned<D> du;
    kept = hn::Or(kept, hn::IfThenZeroElse(hn::RebindMask(du, CertainlyNonzero(b, margin)),
                                           hn::Set(du, std::uint64_t(1) << first)));
  } else {
    const V half = hn::Set(D(), 0.5);  // split_half
    const V b01 = half * (b[0] + b[1]), b12 = half * (b[1] + b[2]), b23 = half * (b[2] + b[3]);
    const V b012 = half * (b01 + b12), b123 = half * (b12 + b23);
    const V mid = half * (b012 + b123);
    KeptLeaves<DEPTH - 1>({b[0], b01, b012, mid}, margin, first, kept);
    KeptLeaves<DEPTH - 1>({mid, b123, b23, b[3]}, margin, first + (1 << (DEPTH - 1)), kept);
  }
}

// Whether the projections on axis w of points [0, split) and [split, 4) over [lo, hi] (x0, x1)
// are farther apart than need scaled by w's 1-norm: apart_along.
HWY_INLINE M ApartAlong(const Lanes3 (&x0)[4], const Lanes3 (&x1)[4], int split, const Lanes3& w, V need) {
  const V infinity = hn::Set(D(), std::numeric_limits<Scalar>::infinity());
  V a_lo = infinity, a_hi = hn::Neg(infinity), b_lo = infinity, b_hi = hn::Neg(infinity);
  for (int i = 0; i < 4; ++i) {
    const V p0 = Dot(w, x0[i]), p1 = Dot(w, x1[i]);
    const V lo = StdMin(p0, p1), hi = StdMax(p0, p1);
    V& group_lo = i < split ? a_lo : b_lo;
    V& group_hi = i < split ? a_hi : b_hi;
    group_lo = StdMin(group_lo, lo);
    group_hi = StdMax(group_hi, hi);
  }
  return ApartRanges(a_lo, a_hi, b_lo, b_hi, need * Norm1(w));
}

HWY_INLINE Lanes3 Select(M m, const Lanes3& yes, const Lanes3& no) {
  return {hn::IfThenElse(m, yes.x, no.x), hn::IfThenElse(m, yes.y, no.y), hn::IfThenElse(m, yes.z, no.z)};
}

// roots_apart_within (no cubic margin) for N tests (they may repeat), need their whole step's
// gap and margin: the tree of halvings, then the one run of kept sub-intervals through
// apart_over's axes (the coordinate boxes, the shape's axes at the run's midpoint). Which
// sub-intervals are kept and which axis separates are random from one cloth test to the next,
// so the scalar code's branches cost more than its arithmetic: here every lane computes
// everything. A lane with two runs or more is left undecided. Bits: lane l decided, apart.
template <QueryKind kind, class Pair>
HWY_INLINE void StageWithin(const BatchInput& input, const Pair* pairs, const Left* const (&test)[N], V need,
                            int depth, unsigned& decided, unsigned& apart_lanes) {
  const D d;
  const hn::RebindToUnsigned<D> du;
  V b[4];
  for (int k = 0; k < 4; ++k) b[k] = FromTests(test, [k](const Left& l) { return l.cubic.b[k]; });
  const V error = FromTests(test, [](const Left& l) { return l.cubic.error; });
  // roots_apart_within's margin (max_abs: the largest of four finite magnitudes, in any order).
  const V largest = StdMax(StdMax(StdMax(hn::Abs(b[0]), hn::Abs(b[1])), hn::Abs(b[2])), hn::Abs(b[3]));
  const V margin = ((hn::Set(d, 2.0) * error) + (hn::Set(d, 256 * UNIT_ROUNDOFF) * largest)) + hn::Zero(d);
  auto kept_lanes = hn::Zero(du);
  switch (std::min(depth, MAX_SEPARATION_DEPTH)) {
    case 1: KeptLeaves<1>(b, margin, 0, kept_lanes); break;
    case 2: KeptLeaves<2>(b, margin, 0, kept_lanes); break;
    case 3: KeptLeaves<3>(b, margin, 0, kept_lanes); break;
    case 4: KeptLeaves<4>(b, margin, 0, kept_lanes); break;
    case 5: KeptLeaves<5>(b, margin, 0, kept_lanes); break;
    default: KeptLeaves<6>(b, margin, 0, kept_lanes); break;
  }
  HWY_ALIGN std::uint64_t kept_of[N];
  hn::Store(kept_lanes, du, kept_of);
  // Each lane's kept sub-intervals, and its run's time range (widened as apart_over widens it).
  const int leaves = 1 << std::clamp(depth, 1, MAX_SEPARATION_DEPTH);
  const std::uint64_t all = leaves == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << leaves) - 1;
  const Scalar width = Scalar(1) / Scalar(leaves);
  unsigned runs = 0;  // lanes with one run to test
  HWY_ALIGN Scalar lo[N], hi[N];
  for (std::size_t l = 0; l < N; ++l) {
    lo[l] = 0, hi[l] = 1;
    const std::uint64_t kept = kept_of[l];
    if (kept == 0 || kept == all) {  // no root anywhere: apart; roots anywhere: the whole step's boxes said no
      decided |= 1u << l;
      apart_lanes |= unsigned(kept == 0) << l;
      continue;
    }
    const int first = __builtin_ctzll(kept);
    const int past = first + __builtin_ctzll(~(kept >> first));
    if (past < 64 && (kept >> past) != 0) continue;  // another run after this one
    lo[l] = std::max(Scalar(0), first * width - TIME_WIDENING);
    hi[l] = std::min(Scalar(1), past * width + TIME_WIDENING);
    runs |= 1u << l;
  }
  if (runs == 0) return;
  // The points at the run's ends, as apart_over computes them: start + t * motion.
  const Pair* pair[N];
  for (std::size_t l = 0; l < N; ++l) pair[l] = pairs + test[l]->index;
  const V at_lo = hn::Load(d, lo), at_hi = hn::Load(d, hi);
  Lanes3 x0[4], x1[4];
  for (int i = 0; i < 4; ++i) {
    const Lanes3 s = LoadPoint(input.start.data(), pair, i), e = LoadPoint(input.end.data(), pair, i);
    const Lanes3 motion = e - s;
    x0[i] = {s.x + at_lo * motion.x, s.y + at_lo * motion.y, s.z + at_lo * motion.z};
    x1[i] = {s.x + at_hi * motion.x, s.y + at_hi * motion.y, s.z + at_hi * motion.z};
  }
  constexpr int split = kind == QueryKind::VertexFace ? 1 : 2;
  // The coordinate boxes: point 0 is always the first feature's, point 3 the second's.
  Lanes3 point_lo[4], point_hi[4];
  for (int i = 0; i < 4; ++i) {
    point_lo[i] = {StdMin(x0[i].x, x1[i].x), StdMin(x0[i].y, x1[i].y), StdMin(x0[i].z, x1[i].z)};
    point_hi[i] = {StdMax(x0[i].x, x1[i].x), StdMax(x0[i].y, x1[i].y), StdMax(x0[i].z, x1[i].z)};
  }
  Lanes3 a_lo = point_lo[0], a_hi = point_hi[0], b_lo = point_lo[3], b_hi = point_hi[3];
  for (int i = 1; i < 3; ++i) MergeBox(i < split ? a_lo : b_lo, i < split ? a_hi : b_hi, point_lo[i], point_hi[i]);
  M apart = hn::Or(hn::Or(ApartRanges(a_lo.x, a_hi.x, b_lo.x, b_hi.x, need), ApartRanges(a_lo.y, a_hi.y, b_lo.y, b_hi.y, need)),
                   ApartRanges(a_lo.z, a_hi.z, b_lo.z, b_hi.z, need));
  // The shape's axes (shape_axes_apart), at the midpoints of the run.
  const V half = hn::Set(d, 0.5);
  Lanes3 m[4];
  for (int i = 0; i < 4; ++i) m[i] = {half * (x0[i].x + x1[i].x), half * (x0[i].y + x1[i].y), half * (x0[i].z + x1[i].z)};
  if constexpr (kind == QueryKind::VertexFace) {
    // The in-plane normal of the triangle edge the vertex lies farthest outside of.
    const Lanes3 e[3] = {m[2] - m[1], m[3] - m[2], m[1] - m[3]};
    const Lanes3 n = Cross(e[0], {hn::Neg(e[2].x), hn::Neg(e[2].y), hn::Neg(e[2].z)});
    Lanes3 best = Cross(n, e[0]);
    V best_value = hn::Set(d, std::numeric_limits<Scalar>::infinity());
    for (int i = 0; i < 3; ++i) {
      const Lanes3 axis = i == 0 ? best : Cross(n, e[i]);
      const V value = Dot(m[0] - m[1 + i], axis) / Norm1(axis);
      const M lower = hn::Lt(value, best_value);
      best_value = hn::IfThenElse(lower, value, best_value);
      best = Select(lower, axis, best);
    }
    apart = hn::Or(apart, ApartAlong(x0, x1, split, best, need));
  } else {
    // The in-plane normals of the two edges.
    const Lanes3 a = m[1] - m[0], bb = m[3] - m[2];
    const Lanes3 n = Cross(a, bb);
    apart = hn::Or(apart, hn::Or(ApartAlong(x0, x1, split, Cross(n, bb), need), ApartAlong(x0, x1, split, Cross(n, a), need)));
  }
  decided |= runs;
  apart_lanes |= runs & unsigned(Bits(d, apart));
}

template <QueryKind kind, bool VINCENT, class Pair>
StageBits Stage(const BatchInput& input, const Pair* pairs, const Left* left, int count, Scalar gap,
                Scalar contact_tolerance, int depth) {
  const D d;
  constexpr int split = kind == QueryKind::VertexFace ? 1 : 2;  // points [0, split) are the first feature
  StageBits out;
  const V thickness = hn::Set(d, gap), tolerance = hn::Set(d, contact_tolerance);
  const V margin = hn::Set(d, PROJECTION_ERROR_FACTOR * UNIT_ROUNDOFF);
  // The whole step's boxes (coordinate_axes_apart over [0, 1] with the gap gap + tolerance *
  // extent: vincent's contact_distance, conservative's thickness with 0). The positions at
  // t = 0 and t = 1 are start and start + motion (what start + t * motion gives there, but for
  // the sign of a zero, which no decision reads). Only read for tests that pass stage_runs
  // (finite coordinates).
  for (int j = 0; j < count; j += int(N)) {
    const Left* test[N];  // a tail repeats the last test; its bits are dropped below
    for (std::size_t l = 0; l < N; ++l) test[l] = left + std::min(j + int(l), count - 1);
    V b[4];
    for (int k = 0; k < 4; ++k) b[k] = FromTests(test, [k](const Left& t) { return t.cubic.b[k]; });
    const V error = FromTests(test, [](const Left& t) { return t.cubic.error; });
    out.stage |= Bits(d, ReachesStage<VINCENT>(b, error)) << j;
    const Pair* pair[N];
    for (std::size_t l = 0; l < N; ++l) pair[l] = pairs + test[l]->index;
    // Point 0 is always the first feature's, point 3 the second's; point 1 is the vertex-face
    // test's triangle's, the edge-edge test's first edge's.
    V largest = hn::Zero(d);
    Lanes3 a_lo, a_hi, b_lo, b_hi, lo, hi;
    PointBox(input, pair, 0, a_lo, a_hi, largest);
    PointBox(input, pair, 3, b_lo, b_hi, largest);
    PointBox(input, pair, 1, lo, hi, largest);
    MergeBox(split == 1 ? b_lo : a_lo, split == 1 ? b_hi : a_hi, lo, hi);
    PointBox(input, pair, 2, lo, hi, largest);
    MergeBox(b_lo, b_hi, lo, hi);
    // stage_runs's coordinate limit (the largest magnitude of the points, at both ends).
    out.stage &= ~(Bits(d, hn::Not(hn::Le(largest, hn::Set(d, STAGE_COORDINATE_LIMIT)))) << j);
    const V extent = FromTests(test, [](const Left& t) { return t.cubic.extent; });
    const V need = (thickness + tolerance * extent) + margin * largest;
    HWY_ALIGN Scalar lanes[N];
    hn::Store(need, d, lanes);
    for (std::size_t l = 0; l < N && j + int(l) < count; ++l) out.need[j + int(l)] = lanes[l];
    const M apart = hn::Or(hn::Or(ApartRanges(a_lo.x, a_hi.x, b_lo.x, b_hi.x, need), ApartRanges(a_lo.y, a_hi.y, b_lo.y, b_hi.y, need)),
                           ApartRanges(a_lo.z, a_hi.z, b_lo.z, b_hi.z, need));
    out.whole_step_apart |= Bits(d, apart) << j;
  }
  out.stage &= chunk_bits(std::size_t(count));
  out.whole_step_apart &= out.stage & chunk_bits(std::size_t(count));
  // The rest of the stage for the tests whose whole step's boxes were not apart, N at a time.
  int asked[LEFT_MAX], asked_count = 0;
  for (std::uint64_t rest = out.stage & ~out.whole_step_apart; rest != 0; rest &= rest - 1)
    asked[asked_count++] = __builtin_ctzll(rest);
  for (int g = 0; g < asked_count; g += int(N)) {
    int lane[N];
    const Left* test[N];
    HWY_ALIGN Scalar need[N];
    for (std::size_t l = 0; l < N; ++l) {
      lane[l] = asked[std::min(g + int(l), asked_count - 1)];
      test[l] = left + lane[l];
      need[l] = out.need[lane[l]];
    }
    unsigned decided = 0, apart = 0;
    StageWithin<kind>(input, pairs, test, hn::Load(d, need), depth, decided, apart);
    for (std::size_t l = 0; l < N && g + int(l) < asked_count; ++l) {
      out.decided |= std::uint64_t((decided >> l) & 1) << lane[l];
      out.apart |= std::uint64_t((apart >> l) & 1) << lane[l];
    }
  }
  return out;
}

StageBits StageVertexFace(const BatchInput& input, const VertexFacePair* pairs, const Left* left, int count,
                          bool vincent, Scalar gap, Scalar contact_tolerance, int depth) {
  return vincent ? Stage<QueryKind::VertexFace, true>(input, pairs, left, count, gap, contact_tolerance, depth)
                 : Stage<QueryKind::VertexFace, false>(input, pairs, left, count, gap, contact_tolerance, depth);
}
StageBits StageEdgeEdge(const BatchInput& input, const EdgeEdgePair* pairs, const Left* left, int count,
                        bool vincent, Scalar gap, Scalar contact_tolerance, int depth) {
  return vincent ? Stage<QueryKind::EdgeEdge, true>(input, pairs, left, count, gap, contact_tolerance, depth)
                 : Stage<QueryKind::EdgeEdge, false>(input, pairs, left, count, gap, contact_tolerance, depth);
}

void FilterDecisions(const CoplanarityCubic* cubics, std::size_t n, bool* culled) {
  const D d;
  for (std::size_t i = 0; i < n; i += N) {
    HWY_ALIGN double k[4][N], e[N];
    for (std::size_t j = 0; j < N; ++j) {
      const CoplanarityCubic& c = cubics[std::min(i + j, n - 1)];
      for (int m = 0; m < 4; ++m) k[m][j] = c.b[m];
      e[j] = c.error;
    }
    M resolved;
    const std::uint64_t bits = Bits(d, FilterCulls(hn::Load(d, k[0]), hn::Load(d, k[1]), hn::Load(d, k[2]),
                                                   hn::Load(d, k[3]), hn::Load(d, e), resolved));
    for (std::size_t j = 0; j < N && i + j < n; ++j) culled[i + j] = (bits >> j) & 1;
  }
}

void MinMaxAbs(const double* a, const double* b, std::size_t n, double* min, double* max, double* abs) {
  const D d;
  for (std::size_t i = 0; i < n; i += N) {
    const V x = hn::LoadU(d, a + i), y = hn::LoadU(d, b + i);
    hn::StoreU(StdMin(x, y), d, min + i);
    hn::StoreU(StdMax(x, y), d, max + i);
    hn::StoreU(hn::Abs(x), d, abs + i);
  }
}

}  // namespace drape::ccd::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace drape::ccd::detail {
HWY_EXPORT(CubicsVertexFace);
HWY_EXPORT(CubicsEdgeEdge);
HWY_EXPORT(StageVertexFace);
HWY_EXPORT(StageEdgeEdge);
HWY_EXPORT(MinMaxAbs);
HWY_EXPORT(FilterDecisions);

void chunk_cubics(const BatchInput& input, const VertexFacePair* pairs, std::size_t n, Apart apart, Scalar thickness,
                  ChunkCubics& c) {
  HWY_DYNAMIC_DISPATCH(CubicsVertexFace)(input, pairs, n, apart, thickness, c);
}
void chunk_cubics(const BatchInput& input, const EdgeEdgePair* pairs, std::size_t n, Apart apart, Scalar thickness,
                  ChunkCubics& c) {
  HWY_DYNAMIC_DISPATCH(CubicsEdgeEdge)(input, pairs, n, apart, thickness, c);
}

StageBits separation_stage(const BatchInput& input, const VertexFacePair* pairs, const Left* left, int count,
                           bool vincent, Scalar gap, Scalar contact_tolerance, int depth) {
  return HWY_DYNAMIC_DISPATCH(StageVertexFace)(input, pairs, left, count, vincent, gap, contact_tolerance, depth);
}
StageBits separation_stage(const BatchInput& input, const EdgeEdgePair* pairs, const Left* left, int count,
                           bool vincent, Scalar gap, Scalar contact_tolerance, int depth) {
  return HWY_DYNAMIC_DISPATCH(StageEdgeEdge)(input, pairs, left, count, vincent, gap, contact_tolerance, depth);
}

void min_max_abs(const double* a, const double* b, std::size_t n, double* min, double* max, double* abs) {
  HWY_DYNAMIC_DISPATCH(MinMaxAbs)(a, b, n, min, max, abs);
}

void filter_decisions(const CoplanarityCubic* cubics, std::size_t n, bool* culled) {
  HWY_DYNAMIC_DISPATCH(FilterDecisions)(cubics, n, culled);
}

}  // namespace drape::ccd::detail
#endif  // HWY_ONCE
