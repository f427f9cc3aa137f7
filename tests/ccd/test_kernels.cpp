// The SIMD kernels and their helpers (ccd/src/lanes-inl.h, kernels_batch.cpp, kernels_cones.cpp), on every target this
// machine runs: each is the scalar operation it stands for, bit for bit, NaN, signed zeros and infinities included.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "drape/ccd/coplanarity.h"
#include "drape/ccd/types.h"
#include "kernel_targets.h"

using namespace drape;
using namespace drape::ccd;

namespace {
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
}  // namespace

TEST(Kernels, TheTargetsAreDistinctAndEndWithThePortableCode) {
  const std::vector<std::int64_t> targets = detail::kernel_targets();
  ASSERT_FALSE(targets.empty());
  EXPECT_EQ(std::set<std::int64_t>(targets.begin(), targets.end()).size(), targets.size());
  std::set<std::string> names;
  kernel_testing::on_every_kernel_target([&] { names.insert(detail::kernel_target_name()); });
  EXPECT_EQ(names.size(), targets.size()) << "use_kernel_target must select each target in turn";
  detail::use_kernel_target(kernel_testing::portable_kernel_target());
  const std::string portable = detail::kernel_target_name();
  detail::use_kernel_target(0);
  EXPECT_TRUE(portable == "SCALAR" || portable == "EMU128") << portable;
}

TEST(Kernels, MinMaxAbsAreTheStdFunctions) {
  const double inf = std::numeric_limits<double>::infinity();
  const double values[] = {std::numeric_limits<double>::quiet_NaN(), -0.0, 0.0, 1.0, -1.0, inf, -inf,
                           std::numeric_limits<double>::denorm_min(), 2.5};
  std::vector<double> a, b;
  for (double x : values)
    for (double y : values) a.push_back(x), b.push_back(y);
  while (a.size() % 8) a.push_back(1), b.push_back(2);
  kernel_testing::on_every_kernel_target([&] {
    std::vector<double> min(a.size()), max(a.size()), abs(a.size());
    detail::min_max_abs(a.data(), b.data(), a.size(), min.data(), max.data(), abs.data());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_TRUE(same_bits(max[i], std::max(a[i], b[i]))) << a[i] << " " << b[i];
      EXPECT_TRUE(same_bits(min[i], std::min(a[i], b[i]))) << a[i] << " " << b[i];
      EXPECT_TRUE(same_bits(abs[i], std::abs(a[i]))) << a[i];
    }
  });
}

TEST(Kernels, FilterDecisionIsFilterCulls) {
  // Every combination of four coefficients from a set of values around the decision's edges
  // (signs, zeros, within and beyond 2048 errors, infinities, NaN) and four errors.
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const double values[] = {nan, -0.0, 0.0, 1e-3, -1e-3, 1.5, -1.5, 1e3, -1e3, inf, -inf};
  std::vector<CoplanarityCubic> cubics;
  for (double error : {0.0, 1e-3, 1.0, nan})
    for (double b0 : values)
      for (double b1 : values)
        for (double b2 : values)
          for (double b3 : values) {
            CoplanarityCubic c;
            c.b = {b0, b1, b2, b3};
            c.error = error;
            cubics.push_back(c);
          }
  std::size_t culled = 0;
  for (const CoplanarityCubic& c : cubics) culled += filter_culls(c);
  EXPECT_GT(culled, 1000u);  // both answers occur (2,274 of 58,564)
  kernel_testing::on_every_kernel_target([&] {
    std::vector<char> decisions(cubics.size());
    detail::filter_decisions(cubics.data(), cubics.size(), reinterpret_cast<bool*>(decisions.data()));
    std::size_t differences = 0;
    for (std::size_t i = 0; i < cubics.size(); ++i) differences += bool(decisions[i]) != filter_culls(cubics[i]);
    EXPECT_EQ(differences, 0u) << "of " << cubics.size();
  });
}

namespace {

// The scalar code the cones' kernel stands for (patch_tree.cpp's before the kernel): a leaf's
// cone through Eigen's cross, dot, squaredNorm and norm.
struct ScalarCone {
  Vec3 sum, axis;
  double cos = 0, sin = 0;
  bool ok = false;
};
ScalarCone scalar_cone(const std::vector<Vec3>& start, const std::vector<Vec3>& end,
                       const std::vector<std::array<std::int32_t, 3>>& triangles, std::int32_t first, std::int32_t count) {
  std::array<Vec3, 3 * detail::CONE_LEAF_TRIANGLES> coefficient;
  std::array<double, 3 * detail::CONE_LEAF_TRIANGLES> scale_squared;
  Vec3 sum = Vec3::Zero();
  for (std::int32_t k = 0; k < count; ++k) {
    const std::array<std::int32_t, 3>& tri = triangles[std::size_t(first + k)];
    const Vec3 e0 = start[tri[1]] - start[tri[0]], f0 = start[tri[2]] - start[tri[0]];
    const Vec3 e1 = end[tri[1]] - end[tri[0]], f1 = end[tri[2]] - end[tri[0]];
    coefficient[3 * k] = e0.cross(f0);
    coefficient[3 * k + 1] = 0.5 * (e0.cross(f1) + e1.cross(f0));
    coefficient[3 * k + 2] = e1.cross(f1);
    const double se0 = e0.squaredNorm(), sf0 = f0.squaredNorm(), se1 = e1.squaredNorm(), sf1 = f1.squaredNorm();
    scale_squared[3 * k] = se0 * sf0;
    scale_squared[3 * k + 1] = 0.5 * (se0 * sf1 + se1 * sf0);
    scale_squared[3 * k + 2] = se1 * sf1;
    sum += coefficient[3 * k] + coefficient[3 * k + 1] + coefficient[3 * k + 2];
  }
  ScalarCone c;
  c.sum = sum;
  const double length = sum.norm();
  bool ok = length > 0;
  c.axis = ok ? Vec3(sum / length) : Vec3::UnitZ();
  double least_squared = 1;
  for (std::int32_t i = 0; i < 3 * count && ok; ++i) {
    const double along = coefficient[std::size_t(i)].dot(c.axis), norm_squared = coefficient[std::size_t(i)].squaredNorm();
    ok = along > 0 && norm_squared > detail::DEGENERATE * detail::DEGENERATE * scale_squared[std::size_t(i)];
    least_squared = std::min(least_squared, along * along / norm_squared);
  }
  c.cos = ok ? std::sqrt(least_squared) : 0;
  c.ok = ok && c.cos > detail::CONE_MARGIN;
  c.sin = std::sqrt(std::max(0.0, 1 - c.cos * c.cos));
  return c;
}

}  // namespace

TEST(Kernels, LeafConesAreTheScalarCodes) {
  // Leaves of 1 to 8 triangles: nearly flat ones (cones that pass), turned and folded ones
  // (that fail), degenerate ones (a repeated corner, a sliver), at scales from 1e-4 to 1e3.
  std::mt19937 random(20261129);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<Vec3> start, end;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::int32_t> first, count;
  int flat = 0;
  for (int leaf = 0; leaf < 300; ++leaf) {
    const double scale = std::pow(10.0, -4 + 7 * (unit(random) + 1) / 2);
    const double tilt = leaf % 3 == 0 ? 1.0 : 1e-3;  // a third folded every which way
    first.push_back(std::int32_t(triangles.size()));
    count.push_back(1 + leaf % detail::CONE_LEAF_TRIANGLES);
    for (std::int32_t k = 0; k < count.back(); ++k) {
      const std::int32_t v = std::int32_t(start.size());
      for (int c = 0; c < 3; ++c) {
        const Vec3 p(unit(random), unit(random), tilt * unit(random));
        start.push_back(scale * p);
        end.push_back(scale * (p + 0.1 * Vec3(unit(random), unit(random), tilt * unit(random))));
      }
      std::array<std::int32_t, 3> t{v, v + 1, v + 2};
      // Counter-clockwise about +z at the start, so that a flat leaf's triangles agree.
      if ((start[std::size_t(v + 1)] - start[std::size_t(v)]).cross(start[std::size_t(v + 2)] - start[std::size_t(v)]).z() < 0)
        std::swap(t[1], t[2]);
      if (leaf % 17 == 5) t[2] = t[1];                                            // a repeated corner
      if (leaf % 19 == 7) start[std::size_t(t[2])] = start[std::size_t(t[1])] * (1 + 1e-12);  // a sliver
      triangles.push_back(t);
    }
  }
  // Leaves that fail on the margin alone: two still triangles whose normals (+-1, 0, e) are
  // 90 degrees less about e from their sum's direction, z (a cosine of about e).
  int margin_only = 0;
  for (const double e : {3e-7, 5e-7, 2e-6}) {
    first.push_back(std::int32_t(triangles.size()));
    count.push_back(2);
    for (const double side : {1.0, -1.0}) {
      const Vec3 normal(side, 0, e), along = Vec3::UnitY(), across = normal.cross(along);  // along x across = normal
      const std::int32_t v = std::int32_t(start.size());
      const Vec3 corner(side, 0, 0);
      for (const Vec3& p : {corner, Vec3(corner + along), Vec3(corner + across)}) {
        start.push_back(p);
        end.push_back(p);
      }
      triangles.push_back({v, v + 1, v + 2});
    }
  }
  std::vector<ScalarCone> expected;
  for (std::size_t l = 0; l < first.size(); ++l) {
    expected.push_back(scalar_cone(start, end, triangles, first[l], count[l]));
    flat += expected.back().ok;
    margin_only += !expected.back().ok && expected.back().cos > 0;
  }
  ASSERT_GT(flat, 50);
  ASSERT_LT(flat, 250);
  ASSERT_EQ(margin_only, 2);  // e = 3e-7 and 5e-7; 2e-6 passes
  kernel_testing::on_every_kernel_target([&] {
    for (const std::size_t chunk : {std::size_t(1), std::size_t(5), std::size_t(37), detail::CHUNK})
      for (std::size_t b = 0; b < first.size(); b += chunk) {
        const std::size_t n = std::min(chunk, first.size() - b);
        detail::ChunkCones c;
        detail::chunk_cones(start.data(), end.data(), triangles.data(), first.data() + b, count.data() + b, n, c);
        if (n < 64) {
          EXPECT_EQ(c.ok >> n, 0u);
        }
        for (std::size_t j = 0; j < n; ++j) {
          const ScalarCone& e = expected[b + j];
          SCOPED_TRACE("leaf " + std::to_string(b + j));
          for (int a = 0; a < 3; ++a) {
            EXPECT_TRUE(same_bits(c.sum[a][j], e.sum[a])) << c.sum[a][j] << " " << e.sum[a];
            EXPECT_TRUE(same_bits(c.axis[a][j], e.axis[a])) << c.axis[a][j] << " " << e.axis[a];
          }
          EXPECT_TRUE(same_bits(c.cos[j], e.cos)) << c.cos[j] << " " << e.cos;
          EXPECT_TRUE(same_bits(c.sin[j], e.sin)) << c.sin[j] << " " << e.sin;
          EXPECT_EQ(bool((c.ok >> j) & 1), e.ok);
        }
      }
  });
}
