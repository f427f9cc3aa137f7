// The SIMD kernels (kernels.h), written once against Google Highway: foreach_target.h compiles
// this file once per instruction set, HWY_EXPORT tables them and HWY_DYNAMIC_DISPATCH calls the
// best one the machine runs. Batch kernels put a test in each lane, so the same source runs 1
// (Highway's portable HWY_SCALAR), 2 (SSE4, or the portable EMU128 of newer compilers), 4 (AVX2)
// or 8 (AVX-512) tests at a time; the one-query kernels put a point's coordinates in the lanes of
// a four-lane vector on x86 targets that have one.
//
// Every operation is the scalar code's on the same operands in the same order (coplanarity.h,
// conservative.cpp, separation.cpp), so every target gives the same bits and decisions:
// -ffp-contract=off and no MulAdd, min and max through StdMin and StdMax below.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <limits>

#include "kernels.h"
#include "separation.h"

HWY_BEFORE_NAMESPACE();
namespace drape::ccd::detail::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<double, 8>;  // a chunk's decisions are bits of a byte per vector
using V = hn::Vec<D>;
using M = hn::Mask<D>;
constexpr std::size_t N = hn::MaxLanes(D());
static_assert(N >= 1 && N <= 8 && CHUNK % N == 0, "a chunk holds whole vectors; lane bits fit a byte");

// std::max(a, b) and std::min(a, b) lane by lane, NaN and signed zeros included: b where
// a < b (b < a), else a. On x86, maxpd(x, y) is x > y ? x : y, so with the operands swapped
// it is exactly that; Highway's portable Max returns the other operand for a NaN, so there
// the comparison is written out.
#if HWY_ARCH_X86 && HWY_TARGET != HWY_EMU128 && HWY_TARGET != HWY_SCALAR
template <class Vec>
HWY_INLINE Vec StdMax(Vec a, Vec b) { return hn::Max(b, a); }
template <class Vec>
HWY_INLINE Vec StdMin(Vec a, Vec b) { return hn::Min(b, a); }
#else
template <class Vec>
HWY_INLINE Vec StdMax(Vec a, Vec b) { return hn::IfThenElse(hn::Lt(a, b), b, a); }
template <class Vec>
HWY_INLINE Vec StdMin(Vec a, Vec b) { return hn::IfThenElse(hn::Lt(b, a), b, a); }
#endif

// The lane bits of a mask, lane 0 lowest.
template <class DM, class Mask>
HWY_INLINE std::uint64_t Bits(DM d, Mask m) {
  std::uint8_t bits[8] = {};
  hn::StoreMaskBits(d, m, bits);
  return bits[0];
}

// Three coordinates, a test per lane.
struct Lanes3 {
  V x, y, z;
};

HWY_INLINE Lanes3 operator-(const Lanes3& a, const Lanes3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

HWY_INLINE Lanes3 Cross(const Lanes3& u, const Lanes3& v) {
  return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
}

HWY_INLINE V Dot(const Lanes3& u, const Lanes3& w) { return (u.x * w.x + u.y * w.y) + u.z * w.z; }

HWY_INLINE V Norm1(const Lanes3& u) { return (hn::Abs(u.x) + hn::Abs(u.y)) + hn::Abs(u.z); }

// std::max of the 1-norms at the two ends of the step.
HWY_INLINE V LargerNorm1(const Lanes3& s, const Lanes3& e) { return StdMax(Norm1(s), Norm1(e)); }

HWY_INLINE V Norm(const Lanes3& u) { return hn::Sqrt((u.x * u.x + u.y * u.y) + u.z * u.z); }

#if HWY_TARGET != HWY_SCALAR
// A vector of doubles whose 128-bit block k is the two doubles at p[k] (a unaligned load each).
template <class DB>
HWY_INLINE hn::Vec<DB> LoadBlocks(DB d, const double* const* p) {
  if constexpr (hn::MaxLanes(DB()) <= 2) {
    return hn::LoadU(d, p[0]);
  } else {
    const hn::Half<DB> half;
    constexpr std::size_t blocks = hn::MaxLanes(DB()) / 4;  // in each half
    return hn::Combine(d, LoadBlocks(half, p + blocks), LoadBlocks(half, p));
  }
}
#endif


// Point `point` (in the pair's order) of N tests, a test per lane: each test's (x, y) and
// (y, z) as 128-bit loads, the even and the odd tests interleaved; at width one, x, y and z.
template <class Pair>
HWY_INLINE Lanes3 LoadPoint(const Vec3* base, const Pair* const (&pair)[N], int point) {
  const D d;
#if HWY_TARGET == HWY_SCALAR
  const double* p = base[points(*pair[0])[point]].data();
  return {hn::LoadU(d, p), hn::LoadU(d, p + 1), hn::LoadU(d, p + 2)};
#else
  const double *xy_even[N / 2], *xy_odd[N / 2], *yz_even[N / 2], *yz_odd[N / 2];
  for (std::size_t j = 0; j < N / 2; ++j) {
    xy_even[j] = base[points(*pair[2 * j])[point]].data();
    xy_odd[j] = base[points(*pair[2 * j + 1])[point]].data();
    yz_even[j] = xy_even[j] + 1;
    yz_odd[j] = xy_odd[j] + 1;
  }
  const V xy0 = LoadBlocks(d, xy_even), xy1 = LoadBlocks(d, xy_odd);
  const V yz0 = LoadBlocks(d, yz_even), yz1 = LoadBlocks(d, yz_odd);
  return {hn::InterleaveLower(d, xy0, xy1), hn::InterleaveLower(d, yz0, yz1), hn::InterleaveUpper(d, yz0, yz1)};
#endif
}

// certainly_nonzero(b, margin) lane by lane: every coefficient above margin, or every one
// below -margin.
HWY_INLINE M CertainlyNonzero(const V (&b)[4], V margin) {
  const V minus = hn::Neg(margin);
  const M above = hn::And(hn::And(hn::Gt(b[0], margin), hn::Gt(b[1], margin)),
                          hn::And(hn::Gt(b[2], margin), hn::Gt(b[3], margin)));
  const M below = hn::And(hn::And(hn::Lt(b[0], minus), hn::Lt(b[1], minus)),
                          hn::And(hn::Lt(b[2], minus), hn::Lt(b[3], minus)));
  return hn::Or(above, below);
}

// filter_culls lane by lane: resolved (not cubic_poorly_resolved, also returned), one strict
// sign, both ends clear of the error.
HWY_INLINE M FilterCulls(V k0, V k1, V k2, V k3, V e, M& resolved) {
  const D d;
  // max_abs: std::max({|k0|, |k1|, |k2|, |k3|}), left to right (the order matters for a NaN).
  const V largest = StdMax(StdMax(StdMax(hn::Abs(k0), hn::Abs(k1)), hn::Abs(k2)), hn::Abs(k3));
  const V lo = StdMin(StdMin(k0, k1), StdMin(k2, k3)), hi = StdMax(StdMax(k0, k1), StdMax(k2, k3));
  resolved = hn::Not(hn::Le(largest, hn::Set(d, POORLY_RESOLVED_RATIO) * e));
  const M one_sign = hn::Or(hn::Gt(lo, hn::Zero(d)), hn::Lt(hi, hn::Zero(d)));
  const M ends_clear = hn::Gt(StdMin(hn::Abs(k0), hn::Abs(k3)), e);
  return hn::And(hn::And(resolved, one_sign), ends_clear);
}

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

// ---------------------------------------------------------------------------------------
// One query, a point's x, y, z in lanes 0-2 of a four-lane vector (lane 3 never decides).
// Targets with fewer lanes of doubles run the scalar code (DRAPE_COORDINATE_LANES 0).

#undef DRAPE_COORDINATE_LANES
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2  // AVX2 and the AVX-512 targets (lower is wider)
#define DRAPE_COORDINATE_LANES 1
using D4 = hn::CappedTag<double, 4>;
static_assert(hn::MaxLanes(D4()) == 4, "four lanes of doubles");
#else
#define DRAPE_COORDINATE_LANES 0
#endif

#if DRAPE_COORDINATE_LANES
// Point i of a query at the start or the end of the step: one four-double load where another
// point of the query follows (lane 3 its x), the last end point with a zero after it.
static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(Query) == 8 * sizeof(Vec3),
              "LoadStart and LoadEnd read a query's points as 8 consecutive packed Vec3");
HWY_INLINE hn::Vec<D4> LoadStart(const Query& q, int i) { return hn::LoadU(D4(), q.start[i].data()); }
HWY_INLINE hn::Vec<D4> LoadEnd(const Query& q, int i) {
  if (i < 3) return hn::LoadU(D4(), q.end[i].data());
  // (x, y) and (y, z) shifted to (z, 0): two loads, no store (a stored array read back as a
  // vector stalls store forwarding).
  const hn::Half<D4> half;
  const double* p = q.end[3].data();
  return hn::Combine(D4(), hn::ShiftRightLanes<1>(half, hn::LoadU(half, p + 1)), hn::LoadU(half, p));
}

// A lane permutation of a four-lane vector.
HWY_INLINE hn::Vec<D4> Permute(hn::Vec<D4> v, const std::int64_t (&index)[4]) {
  const D4 d;
  const hn::RebindToSigned<D4> di;
  return hn::TableLookupLanes(v, hn::IndicesFromVec(d, hn::LoadU(di, index)));
}

// Lane i of the result: (p_i[0] + p_i[1]) + p_i[2], the scalar code's order of a 3-term sum.
HWY_INLINE hn::Vec<D4> LaneSums(hn::Vec<D4> p0, hn::Vec<D4> p1, hn::Vec<D4> p2, hn::Vec<D4> p3) {
  const D4 d;
  const auto t0 = hn::InterleaveLower(d, p0, p1), t1 = hn::InterleaveUpper(d, p0, p1);
  const auto t2 = hn::InterleaveLower(d, p2, p3), t3 = hn::InterleaveUpper(d, p2, p3);
  const auto x = hn::ConcatLowerLower(d, t2, t0), y = hn::ConcatLowerLower(d, t3, t1);
  const auto z = hn::ConcatUpperUpper(d, t2, t0);
  return (x + y) + z;
}
#endif

template <QueryKind kind>
HWY_INLINE bool CubicOfQuery(const Query& query, bool cull, CoplanarityCubic& out) {
#if !DRAPE_COORDINATE_LANES
  out = coplanarity_cubic_in<Scalar>(kind, query);
  return cull && filter_culls(out);
#else
  {
    const D4 d;
    using V4 = hn::Vec<D4>;
    constexpr std::array<int, 4> order = coplanarity_order(kind);
    const V4 x1s = LoadStart(query, order[0]), x1e = LoadEnd(query, order[0]);
    const V4 A0 = LoadStart(query, order[1]) - x1s, A1 = LoadEnd(query, order[1]) - x1e;
    const V4 B0 = LoadStart(query, order[2]) - x1s, B1 = LoadEnd(query, order[2]) - x1e;
    const V4 C0 = LoadStart(query, order[3]) - x1s, C1 = LoadEnd(query, order[3]) - x1e;
    // (u1, u2, u0) and (u2, u0, u1): u x v = yzx(u) zxy(v) - zxy(u) yzx(v), lane by lane.
    static constexpr std::int64_t yzx[4] = {1, 2, 0, 3}, zxy[4] = {2, 0, 1, 3};
    const V4 B0yzx = Permute(B0, yzx), B0zxy = Permute(B0, zxy), B1yzx = Permute(B1, yzx), B1zxy = Permute(B1, zxy);
    const V4 C0yzx = Permute(C0, yzx), C0zxy = Permute(C0, zxy), C1yzx = Permute(C1, yzx), C1zxy = Permute(C1, zxy);
    const V4 B0C0 = B0yzx * C0zxy - B0zxy * C0yzx, B1C0 = B1yzx * C0zxy - B1zxy * C0yzx;
    const V4 B0C1 = B0yzx * C1zxy - B0zxy * C1yzx, B1C1 = B1yzx * C1zxy - B1zxy * C1yzx;
    // first: [A0 B0 C0], [A1 B0 C0], [A1 B1 C0], [A1 B1 C1] (the first terms of b0..b3);
    // rest: [A0 B1 C0], [A1 B0 C1] (second terms of b1, b2), [A0 B0 C1], [A0 B1 C1] (third).
    const V4 first = LaneSums(A0 * B0C0, A1 * B0C0, A1 * B1C0, A1 * B1C1);
    const V4 rest = LaneSums(A0 * B1C0, A1 * B0C1, A0 * B0C1, A0 * B1C1);
    // second = (-0, rest0, rest1, -0), third = (-0, rest2, rest3, -0): x + (-0) = x, bit for bit.
    static constexpr std::int64_t second_of[4] = {0, 0, 1, 3}, third_of[4] = {2, 2, 3, 3};
    HWY_ALIGN static constexpr double inner[4] = {0, 1, 1, 0}, divisor[4] = {1, 3, 3, 1};
    const auto middle = hn::Gt(hn::Load(d, inner), hn::Zero(d));
    const V4 negative_zero = hn::Set(d, -0.0);
    const V4 second = hn::IfThenElse(middle, Permute(rest, second_of), negative_zero);
    const V4 third = hn::IfThenElse(middle, Permute(rest, third_of), negative_zero);
    const V4 b = ((first + second) + third) / hn::Load(d, divisor);
    // The 1-norms of A0, A1, B0, B1 and C0, C1 (lane 3 is not summed); a, b, c the larger of
    // each pair.
    HWY_ALIGN double norms[8];
    hn::Store(LaneSums(hn::Abs(A0), hn::Abs(A1), hn::Abs(B0), hn::Abs(B1)), d, norms);
    hn::Store(LaneSums(hn::Abs(C0), hn::Abs(C1), hn::Zero(d), hn::Zero(d)), d, norms + 4);
    const Scalar a = std::max(norms[0], norms[1]), bb = std::max(norms[2], norms[3]), c = std::max(norms[4], norms[5]);
    const Scalar error = Scalar(COPLANARITY_ERROR_FACTOR) * UNIT_ROUNDOFF * a * bb * c;
    HWY_ALIGN double coefficients[4];
    hn::Store(b, d, coefficients);
    CoplanarityCubic cubic;
    for (int k = 0; k < 4; ++k) cubic.b[k] = coefficients[k];
    cubic.error = error;
    if (cull && filter_culls(cubic)) return true;
    cubic.extent = std::max({a, bb, c});
    out = cubic;
    return false;
  }
#endif
}

bool OneQueryCubic(QueryKind kind, const Query& query, bool cull, CoplanarityCubic& cubic) {
  return kind == QueryKind::VertexFace ? CubicOfQuery<QueryKind::VertexFace>(query, cull, cubic)
                                       : CubicOfQuery<QueryKind::EdgeEdge>(query, cull, cubic);
}

// The features' boxes over [lo, hi] more than need apart along x, y or z, all three axes at
// once (which axis separates is random in a cloth step).
bool OneQueryBoxesApart(QueryKind kind, const Query& q, Scalar lo, Scalar hi, bool need_given, Scalar& need) {
#if !DRAPE_COORDINATE_LANES
  return boxes_apart_scalar(kind, q, lo, hi, need_given, need);
#else
  {
    const D4 d;
    using V4 = hn::Vec<D4>;
    const int split = kind == QueryKind::VertexFace ? 1 : 2;
    const V4 at_lo = hn::Set(d, lo), at_hi = hn::Set(d, hi);
    V4 point_lo[4], point_hi[4], largest = hn::Zero(d);
    for (int i = 0; i < 4; ++i) {
      const V4 start = LoadStart(q, i), end = LoadEnd(q, i);
      const V4 motion = end - start;
      const V4 x0 = start + at_lo * motion, x1 = start + at_hi * motion;
      point_lo[i] = StdMin(x0, x1);
      point_hi[i] = StdMax(x0, x1);
      if (!need_given) largest = StdMax(largest, StdMax(hn::Abs(start), hn::Abs(end)));
    }
    // Point 0 is always the first feature's, point 3 the second's.
    V4 a_lo = point_lo[0], a_hi = point_hi[0], b_lo = point_lo[3], b_hi = point_hi[3];
    for (int i = 1; i < 3; ++i) {
      V4& lo_i = i < split ? a_lo : b_lo;
      V4& hi_i = i < split ? a_hi : b_hi;
      lo_i = StdMin(lo_i, point_lo[i]);
      hi_i = StdMax(hi_i, point_hi[i]);
    }
    if (!need_given) {
      HWY_ALIGN double lanes[4];
      hn::Store(largest, d, lanes);
      need = need + PROJECTION_ERROR_FACTOR * UNIT_ROUNDOFF * std::max({lanes[0], lanes[1], lanes[2]});
    }
    const V4 need4 = hn::Set(d, need);
    const auto apart = hn::Or(hn::Gt(b_lo - a_hi, need4), hn::Gt(a_lo - b_hi, need4));
    return (Bits(d, apart) & 0b111) != 0;
  }
#endif
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
HWY_EXPORT(OneQueryCubic);
HWY_EXPORT(OneQueryBoxesApart);
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

// The one-query kernels run once or twice per query: their chosen versions are kept as
// function pointers, chosen at start-up and again by use_kernel_target. HWY_DYNAMIC_DISPATCH
// would ask libhwy for the chosen target on every call (a call into the shared library and an
// atomic load), which cost the one-query methods about a tenth of their time.
namespace {

using CubicKernel = bool (*)(QueryKind, const Query&, bool, CoplanarityCubic&);
using BoxesKernel = bool (*)(QueryKind, const Query&, Scalar, Scalar, bool, Scalar&);
CubicKernel cubic_kernel = nullptr;
BoxesKernel boxes_kernel = nullptr;

void choose_one_query_kernels() {
#if (HWY_TARGETS & (HWY_TARGETS - 1)) == 0
  // One target compiled (the portable build, or -march=native): HWY_EXPORT's table then has a
  // single entry, whatever index the chosen target has.
  cubic_kernel = &HWY_STATIC_DISPATCH(OneQueryCubic);
  boxes_kernel = &HWY_STATIC_DISPATCH(OneQueryBoxesApart);
#else
  hwy::ChosenTarget& chosen = hwy::GetChosenTarget();
  chosen.Update(hwy::SupportedTargets());
  const std::size_t index = chosen.GetIndex();
  cubic_kernel = HWY_DISPATCH_TABLE(OneQueryCubic)[index];
  boxes_kernel = HWY_DISPATCH_TABLE(OneQueryBoxesApart)[index];
#endif
}

const bool one_query_kernels_chosen = (choose_one_query_kernels(), true);

}  // namespace

// (A caller's static initialisation may come before this file's: then they are chosen here.)
bool one_query_cubic(QueryKind kind, const Query& query, bool cull, CoplanarityCubic& cubic) {
  if (cubic_kernel == nullptr) [[unlikely]] choose_one_query_kernels();
  return cubic_kernel(kind, query, cull, cubic);
}

bool one_query_boxes_apart(QueryKind kind, const Query& q, Scalar lo, Scalar hi, bool need_given, Scalar& need) {
  if (boxes_kernel == nullptr) [[unlikely]] choose_one_query_kernels();
  return boxes_kernel(kind, q, lo, hi, need_given, need);
}

std::vector<std::int64_t> kernel_targets() { return hwy::SupportedAndGeneratedTargets(); }

void use_kernel_target(std::int64_t target) {
  hwy::SetSupportedTargetsForTest(target);
  choose_one_query_kernels();
}

std::string kernel_target_name() {
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  return targets.empty() ? "none" : hwy::TargetName(targets.front());
}

void min_max_abs(const double* a, const double* b, std::size_t n, double* min, double* max, double* abs) {
  HWY_DYNAMIC_DISPATCH(MinMaxAbs)(a, b, n, min, max, abs);
}

void filter_decisions(const CoplanarityCubic* cubics, std::size_t n, bool* culled) {
  HWY_DYNAMIC_DISPATCH(FilterDecisions)(cubics, n, culled);
}

}  // namespace drape::ccd::detail
#endif  // HWY_ONCE
