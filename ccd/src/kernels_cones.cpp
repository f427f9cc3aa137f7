// The self-collision culling's normal cones (kernels.h, chunk_cones; patch_tree.cpp), a leaf
// of the patch tree per lane, so the same source runs 1, 2, 4 or 8 leaves at a time. A sheet
// falling flat spends its whole broad phase here: every leaf's cone, every step, before the
// root's proves the sheet free (docs/collisions.md). Every lane takes the operations of the
// scalar reference, tests/ccd/test_kernels.cpp's scalar_cone (Eigen's cross, dot and
// squaredNorm, in their order), on the same operands, so every target gives its bits
// (lanes-inl.h).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "kernels_cones.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>

#include "kernels.h"
#include "lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace drape::ccd::detail::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Leaves [i, i + N) of the chunk (those past n repeat leaf n - 1, stored but not read).
HWY_INLINE void ConesN(const Vec3* start, const Vec3* end, const std::array<std::int32_t, 3>* triangles,
                       const std::int32_t* first, const std::int32_t* count, std::size_t n, std::size_t i,
                       ChunkCones& c) {
  const D d;
  const V zero = hn::Zero(d), half = hn::Set(d, 0.5);
  std::size_t leaf[N];
  alignas(64) double counts[N];
  for (std::size_t j = 0; j < N; ++j) {
    leaf[j] = std::min(i + j, n - 1);
    counts[j] = double(count[leaf[j]]);
  }
  const V lane_count = hn::Load(d, counts);
  constexpr std::size_t K = std::size_t(CONE_LEAF_TRIANGLES);
  Lanes3 coefficient[3 * K];
  V scale_squared[3 * K];
  Lanes3 sum{zero, zero, zero};
  for (std::size_t k = 0; k < K; ++k) {
    // Past a leaf's count its lane repeats its last triangle, and keeps nothing of it.
    const M active = hn::Lt(hn::Set(d, double(k)), lane_count);
    const std::array<std::int32_t, 3>* triangle[N];
    for (std::size_t j = 0; j < N; ++j)
      triangle[j] = &triangles[std::size_t(first[leaf[j]] + std::min(std::int32_t(k), count[leaf[j]] - 1))];
    const Lanes3 s0 = LoadPoint(start, triangle, 0), e0 = LoadPoint(end, triangle, 0);
    // The normal (x1 - x0) x (x2 - x0) over the step, in Bernstein form of degree 2.
    const Lanes3 a0 = LoadPoint(start, triangle, 1) - s0, b0 = LoadPoint(start, triangle, 2) - s0;
    const Lanes3 a1 = LoadPoint(end, triangle, 1) - e0, b1 = LoadPoint(end, triangle, 2) - e0;
    const Lanes3 n0 = Cross(a0, b0), n2 = Cross(a1, b1);
    const Lanes3 m0 = Cross(a0, b1), m1 = Cross(a1, b0);
    const Lanes3 n1{half * (m0.x + m1.x), half * (m0.y + m1.y), half * (m0.z + m1.z)};
    coefficient[3 * k] = n0, coefficient[3 * k + 1] = n1, coefficient[3 * k + 2] = n2;
    const V sa0 = Dot(a0, a0), sb0 = Dot(b0, b0), sa1 = Dot(a1, a1), sb1 = Dot(b1, b1);
    scale_squared[3 * k] = sa0 * sb0;
    scale_squared[3 * k + 1] = half * (sa0 * sb1 + sa1 * sb0);
    scale_squared[3 * k + 2] = sa1 * sb1;
    sum.x = hn::IfThenElse(active, sum.x + ((n0.x + n1.x) + n2.x), sum.x);
    sum.y = hn::IfThenElse(active, sum.y + ((n0.y + n1.y) + n2.y), sum.y);
    sum.z = hn::IfThenElse(active, sum.z + ((n0.z + n1.z) + n2.z), sum.z);
  }
  const V length = Norm(sum);
  M ok = hn::Gt(length, zero);
  const Lanes3 axis{hn::IfThenElse(ok, sum.x / length, zero), hn::IfThenElse(ok, sum.y / length, zero),
                    hn::IfThenElse(ok, sum.z / length, hn::Set(d, 1.0))};
  // The least cosine to the axis, squared (all coefficients on the axis' side).
  V least_squared = hn::Set(d, 1.0);
  const V degenerate = hn::Set(d, DEGENERATE * DEGENERATE);
  for (std::size_t k = 0; k < K; ++k) {
    const M active = hn::Lt(hn::Set(d, double(k)), lane_count);
    for (std::size_t b = 3 * k; b < 3 * k + 3; ++b) {
      const V along = Dot(coefficient[b], axis), norm_squared = Dot(coefficient[b], coefficient[b]);
      const M fine = hn::And(hn::Gt(along, zero), hn::Gt(norm_squared, degenerate * scale_squared[b]));
      ok = hn::And(ok, hn::Or(fine, hn::Not(active)));
      least_squared = hn::IfThenElse(active, StdMin(least_squared, along * along / norm_squared), least_squared);
    }
  }
  const V least = hn::IfThenElseZero(ok, hn::Sqrt(least_squared));
  ok = hn::And(ok, hn::Gt(least, hn::Set(d, CONE_MARGIN)));
  hn::Store(sum.x, d, c.sum[0] + i), hn::Store(sum.y, d, c.sum[1] + i), hn::Store(sum.z, d, c.sum[2] + i);
  hn::Store(axis.x, d, c.axis[0] + i), hn::Store(axis.y, d, c.axis[1] + i), hn::Store(axis.z, d, c.axis[2] + i);
  hn::Store(least, d, c.cos + i);
  hn::Store(hn::Sqrt(StdMax(zero, hn::Set(d, 1.0) - least * least)), d, c.sin + i);
  c.ok |= Bits(d, ok) << i;
}

void Cones(const Vec3* start, const Vec3* end, const std::array<std::int32_t, 3>* triangles, const std::int32_t* first,
           const std::int32_t* count, std::size_t n, ChunkCones& c) {
  c.ok = 0;
  for (std::size_t i = 0; i < n; i += N) ConesN(start, end, triangles, first, count, n, i, c);
  c.ok &= chunk_bits(n);
}

}  // namespace drape::ccd::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace drape::ccd::detail {
HWY_EXPORT(Cones);

void chunk_cones(const Vec3* start, const Vec3* end, const std::array<std::int32_t, 3>* triangles,
                 const std::int32_t* first, const std::int32_t* count, std::size_t n, ChunkCones& c) {
  HWY_DYNAMIC_DISPATCH(Cones)(start, end, triangles, first, count, n, c);
}

}  // namespace drape::ccd::detail
#endif  // HWY_ONCE
