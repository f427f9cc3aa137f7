// The SIMD kernels' helpers (ccd/src/lanes-inl.h, kernels_batch.cpp), on every target this
// machine runs: each is the scalar operation it stands for, bit for bit, NaN, signed zeros and infinities included.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <vector>

#include "drape/ccd/coplanarity.h"
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
