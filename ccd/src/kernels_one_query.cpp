// The one-query kernels: one query's cubic and box test, a point's x, y, z in the lanes of a
// four-lane vector on x86 targets that have one (the scalar code elsewhere).
// Written once against Google Highway: foreach_target.h compiles this file once per instruction
// set, HWY_EXPORT tables the kernels and HWY_DYNAMIC_DISPATCH calls the best one the machine runs
// (kernels.h). The lane helpers and the rule that every target gives the scalar code's bits are in
// lanes-inl.h.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "kernels_one_query.cpp"
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

}  // namespace drape::ccd::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace drape::ccd::detail {
HWY_EXPORT(OneQueryCubic);
HWY_EXPORT(OneQueryBoxesApart);

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

}  // namespace drape::ccd::detail
#endif  // HWY_ONCE
