// Internal to ccd/: the lane helpers the SIMD kernels share (kernels_batch.cpp,
// kernels_one_query.cpp, kernels_cones.cpp), compiled once per instruction set with the file that includes it
// (Highway's -inl.h convention: the guard toggles with HWY_TARGET_TOGGLE so that
// foreach_target.h's every pass sees it).
//
// Every operation is the scalar code's on the same operands in the same order (coplanarity.h,
// conservative.cpp, separation.cpp), so every target gives the same bits and decisions:
// -ffp-contract=off and no MulAdd, min and max through StdMin and StdMax below.
#if defined(DRAPE_CCD_LANES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef DRAPE_CCD_LANES_INL_H_
#undef DRAPE_CCD_LANES_INL_H_
#else
#define DRAPE_CCD_LANES_INL_H_
#endif

#include <hwy/highway.h>

#include <cstdint>

#include "kernels.h"

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

}  // namespace drape::ccd::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // DRAPE_CCD_LANES_INL_H_
