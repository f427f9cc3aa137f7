// The closed-form cubic solver and the bracketed root refinement.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "drape/ccd/cubic_solver.h"
#include "root_refinement.h"

using namespace drape;
using namespace drape::ccd;

namespace {

Power3 from_roots(Scalar r0, Scalar r1, Scalar r2) {
  // (t - r0)(t - r1)(t - r2)
  return {-r0 * r1 * r2, r0 * r1 + r0 * r2 + r1 * r2, -(r0 + r1 + r2), 1.0};
}

}  // namespace

TEST(CubicSolver, ThreeSimpleRoots) {
  std::array<Scalar, 3> roots{};
  ASSERT_EQ(solve_cubic(from_roots(0.8, 0.2, 0.5), roots), 3);
  EXPECT_NEAR(roots[0], 0.2, 1e-14);
  EXPECT_NEAR(roots[1], 0.5, 1e-14);
  EXPECT_NEAR(roots[2], 0.8, 1e-14);
}

TEST(CubicSolver, OneRealRoot) {
  std::array<Scalar, 3> roots{};
  // (t - 0.25)(t^2 + 1)
  ASSERT_EQ(solve_cubic({-0.25, 1.0, -0.25, 1.0}, roots), 1);
  EXPECT_NEAR(roots[0], 0.25, 1e-14);
}

TEST(CubicSolver, DoubleRootIsFound) {
  std::array<Scalar, 3> roots{};
  // (t - 0.5)^2 (t - 3): a tangential contact at 0.5.
  const int count = solve_cubic(from_roots(0.5, 0.5, 3.0), roots);
  ASSERT_GE(count, 2);
  bool found = false;
  for (int i = 0; i < count; ++i) found |= std::abs(roots[i] - 0.5) < 1e-7;
  EXPECT_TRUE(found);
}

TEST(CubicSolver, RootsAtZeroAndOne) {
  std::array<Scalar, 3> roots{};
  ASSERT_EQ(solve_cubic(from_roots(0.0, 1.0, 2.0), roots), 3);
  EXPECT_NEAR(roots[0], 0.0, 1e-15);
  EXPECT_NEAR(roots[1], 1.0, 1e-14);
}

TEST(CubicSolver, DegeneratesToQuadraticAndLinear) {
  std::array<Scalar, 3> roots{};
  ASSERT_EQ(solve_cubic({-0.06, -0.1, 1.0, 0.0}, roots), 2);  // (t - 0.3)(t + 0.2)
  EXPECT_NEAR(roots[0], -0.2, 1e-14);
  EXPECT_NEAR(roots[1], 0.3, 1e-14);
  ASSERT_EQ(solve_cubic({-0.5, 2.0, 0.0, 0.0}, roots), 1);
  EXPECT_NEAR(roots[0], 0.25, 1e-15);
  EXPECT_EQ(solve_cubic({0, 0, 0, 0}, roots), -1);
  EXPECT_EQ(solve_cubic({1, 0, 0, 0}, roots), 0);
}

TEST(RootRefinement, FindsTheBracketedRootToTolerance) {
  for (Scalar root : {0.3, 1e-9, 0.999999, 0.5}) {
    const Bernstein3 b = to_bernstein(from_roots(root, 2.0, 5.0));
    ASSERT_EQ(sign_variations(b), 1);
    EXPECT_NEAR(detail::refine_single_root<Scalar>(b, 1e-14), root, 1e-13) << root;
  }
  // Works in long double too (the conservative method's second pass).
  const auto a = from_roots(0.3, 2.0, 5.0);
  const Bernstein3 b = to_bernstein(a);
  const std::array<long double, 4> bl{b[0], b[1], b[2], b[3]};
  EXPECT_NEAR(double(detail::refine_single_root<long double>(bl, 1e-17L)), 0.3, 1e-15);
}

namespace {

// refine_single_root as it was before it stopped at a bracket that cannot shrink: all
// MAX_ITERATIONS (100) run there.
template <class T>
T refine_every_iteration(const std::array<T, 4>& b, T tolerance) {
  const std::array<T, 4> a{b[0], 3 * (b[1] - b[0]), 3 * (b[2] - 2 * b[1] + b[0]), b[3] - 3 * b[2] + 3 * b[1] - b[0]};
  const T first = b[0] != 0 ? b[0] : (b[1] != 0 ? b[1] : b[2]);
  const bool negative_at_lo = first < 0;
  T lo = 0, hi = 1, s = T(0.5);
  for (int iteration = 0; iteration < 100; ++iteration) {
    const T f = ((a[3] * s + a[2]) * s + a[1]) * s + a[0];
    if (f == 0) return s;
    if ((f < 0) == negative_at_lo) lo = s; else hi = s;
    if (hi - lo <= tolerance) break;
    const T slope = (3 * a[3] * s + 2 * a[2]) * s + a[1];
    const T next = slope != 0 ? s - f / slope : lo;
    if (!(next > lo && next < hi)) {
      s = T(0.5) * (lo + hi);
    } else if (std::abs(next - s) <= tolerance) {
      return next;
    } else {
      s = next;
    }
  }
  return T(0.5) * (lo + hi);
}

template <class T>
void expect_same_roots_as_every_iteration() {
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int below_spacing = 0;
  for (int i = 0; i < 20000; ++i) {
    // A cubic with one root in (0, 1), the others outside, scaled and perturbed.
    const double root = unit(random), scale = std::ldexp(1.0, int(unit(random) * 60) - 30);
    Bernstein3 b = to_bernstein(from_roots(root, 1.0 + 4 * unit(random), -1.0 - 4 * unit(random)));
    for (Scalar& c : b) c *= scale;
    if (sign_variations(b) != 1) continue;
    const std::array<T, 4> bt{T(b[0]), T(b[1]), T(b[2]), T(b[3])};
    // Tolerances from 1e-3 down to far below the spacing of the numbers near the root.
    const T tolerance = T(std::pow(10.0, -3 - 30 * unit(random)));
    below_spacing += tolerance < std::numeric_limits<T>::epsilon() * T(root) / 2;
    const T fast = detail::refine_single_root<T>(bt, tolerance), full = refine_every_iteration<T>(bt, tolerance);
    ASSERT_EQ(std::memcmp(&fast, &full, sizeof(T) > 8 ? 10 : sizeof(T)), 0)
        << "root " << root << " tolerance " << double(tolerance);
  }
  EXPECT_GT(below_spacing, 1000);
}

}  // namespace

// The conservative search refines its monotone windows' roots to a tolerance below what the
// numbers can resolve; the refinement stops where its bracket can no longer shrink. Bit for bit
// what all its iterations gave, in double and in long double (80 bits compared).
TEST(RootRefinement, StopsWhereTheBracketCannotShrinkWithTheSameRoot) {
  expect_same_roots_as_every_iteration<double>();
  expect_same_roots_as_every_iteration<long double>();
}
