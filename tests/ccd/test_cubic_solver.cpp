// The closed-form cubic solver and the bracketed root refinement.
#include <gtest/gtest.h>

#include "drape/ccd/cubic_solver.h"
#include "problem.h"

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
