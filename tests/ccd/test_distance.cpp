// Closest points and distance estimates, including the degenerate shapes.
#include <gtest/gtest.h>

#include <random>

#include "drape/ccd/distance.h"

using namespace drape;
using namespace drape::ccd;

namespace {

// Brute force: the smallest distance over a fine grid of the features' parameters.
Scalar brute_point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  Scalar best = 1e300;
  const int n = 200;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j)
      best = std::min(best, (p - (a + (b - a) * i / Scalar(n) + (c - a) * j / Scalar(n))).norm());
  return best;
}

Scalar brute_segment_segment(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  Scalar best = 1e300;
  const int n = 400;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      best = std::min(best, ((a0 + (a1 - a0) * i / Scalar(n)) - (b0 + (b1 - b0) * j / Scalar(n))).norm());
  return best;
}

}  // namespace

TEST(Distance, PointTriangleMatchesBruteForce) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<Scalar> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 p(u(rng), u(rng), u(rng)), a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)),
        c(u(rng), u(rng), u(rng));
    const auto closest = closest_point_triangle<Scalar>(p, a, b, c);
    const Scalar brute = brute_point_triangle(p, a, b, c);
    EXPECT_LE(std::sqrt(closest.distance_squared), brute + 1e-12);
    EXPECT_GE(std::sqrt(closest.distance_squared), brute - 2e-2);  // the grid's resolution
    const Vec3 q = a + closest.weight_b * (b - a) + closest.weight_c * (c - a);
    EXPECT_NEAR((q - closest.point).norm(), 0.0, 1e-12);
  }
}

TEST(Distance, SegmentSegmentMatchesBruteForce) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<Scalar> u(-1, 1);
  for (int trial = 0; trial < 100; ++trial) {
    const Vec3 a0(u(rng), u(rng), u(rng)), a1(u(rng), u(rng), u(rng)), b0(u(rng), u(rng), u(rng)),
        b1(u(rng), u(rng), u(rng));
    const auto closest = closest_segment_segment<Scalar>(a0, a1, b0, b1);
    const Scalar brute = brute_segment_segment(a0, a1, b0, b1);
    EXPECT_LE(std::sqrt(closest.distance_squared), brute + 1e-12);
    EXPECT_GE(std::sqrt(closest.distance_squared), brute - 1e-2);
  }
}

TEST(Distance, ZeroAreaTriangleIsItsEdges) {
  // Collinear corners: the distance to the segment they span.
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(2, 0, 0);
  const auto closest = closest_point_triangle<Scalar>(Vec3(1.5, 1, 0), a, b, c);
  EXPECT_NEAR(std::sqrt(closest.distance_squared), 1.0, 1e-15);
  // All three corners at one point.
  const auto point = closest_point_triangle<Scalar>(Vec3(0, 3, 4), a, a, a);
  EXPECT_NEAR(std::sqrt(point.distance_squared), 5.0, 1e-15);
}

TEST(Distance, ParallelAndDegenerateSegments) {
  // Parallel, overlapping, one unit apart.
  auto c = closest_segment_segment<Scalar>(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 1, 0), Vec3(3, 1, 0));
  EXPECT_NEAR(std::sqrt(c.distance_squared), 1.0, 1e-15);
  // Collinear and disjoint.
  c = closest_segment_segment<Scalar>(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(3, 0, 0), Vec3(5, 0, 0));
  EXPECT_NEAR(std::sqrt(c.distance_squared), 2.0, 1e-15);
  // A zero-length segment.
  c = closest_segment_segment<Scalar>(Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(-1, 2, 0), Vec3(1, 2, 0));
  EXPECT_NEAR(std::sqrt(c.distance_squared), 2.0, 1e-15);
}

TEST(Distance, EstimateErrorCoversNearlyParallelCrossingSegments) {
  // Two segments at an angle of about 1e-17 that cross: distance 0. The interior formulas cannot
  // see it; the estimate's error bound must cover the endpoint distance it returns instead.
  const long double tiny = 1e-17L;
  const Vector3<long double> a0(1, 0.5L, 1 - 3 * tiny), a1(-tiny, 0.5L, 7 * tiny);
  const Vector3<long double> b0(0, 0.5L, 0), b1(1, 0.5L, 1);
  const auto d = segment_segment_distance<long double>(a0, a1, b0, b1);
  EXPECT_LE(d.distance - d.error, 0.0L);
}

TEST(Distance, EstimateIsTightForWellShapedFeatures) {
  const auto d = point_triangle_distance<Scalar>(Vec3(0.2, 0.2, 1e-9), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));
  EXPECT_NEAR(d.distance, 1e-9, 1e-20);
  EXPECT_LT(d.error, 1e-13);
  const auto e = segment_segment_distance<Scalar>(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, -1, 1e-9), Vec3(0.5, 1, 1e-9));
  EXPECT_NEAR(e.distance, 1e-9, 1e-20);
  EXPECT_LT(e.error, 1e-13);
}
