// Bernstein form of a cubic: conversion, sign variations, de Casteljau subdivision.
#include <gtest/gtest.h>

#include <random>

#include "drape/ccd/bernstein.h"

using namespace drape;
using namespace drape::ccd;

TEST(Bernstein, PowerAndBernsteinConvertBothWays) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<Scalar> coef(-5, 5);
  for (int trial = 0; trial < 1000; ++trial) {
    const Power3 a{coef(rng), coef(rng), coef(rng), coef(rng)};
    const Bernstein3 b = to_bernstein(a);
    const Power3 back = to_power(b);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(back[i], a[i], 1e-12);
    for (Scalar t : {0.0, 0.1, 0.37, 0.5, 0.9, 1.0})
      EXPECT_NEAR(evaluate_bernstein(b, t), evaluate_power(a, t), 1e-12) << "t = " << t;
  }
}

TEST(Bernstein, EndCoefficientsAreTheEndValues) {
  const Power3 a{0.3, -2.0, 1.5, 0.25};
  const Bernstein3 b = to_bernstein(a);
  EXPECT_DOUBLE_EQ(b[0], evaluate_power(a, 0.0));
  EXPECT_NEAR(b[3], evaluate_power(a, 1.0), 1e-15);
}

TEST(Bernstein, SignVariationsSkipZeros) {
  EXPECT_EQ(sign_variations({1, 2, 3, 4}), 0);
  EXPECT_EQ(sign_variations({1, -2, 3, 4}), 2);
  EXPECT_EQ(sign_variations({1, -2, 3, -4}), 3);
  EXPECT_EQ(sign_variations({1, 0, 0, -4}), 1);
  EXPECT_EQ(sign_variations({0, 0, 0, 0}), 0);
  EXPECT_EQ(sign_variations({-1, 0, 2, 0}), 1);
}

TEST(Bernstein, SignVariationsBoundTheRootsInTheInterval) {
  // (t - 0.2)(t - 0.5)(t - 0.8): three roots in (0, 1), so V = 3.
  const Power3 three_roots{-0.08, 0.66, -1.5, 1.0};
  EXPECT_EQ(sign_variations(to_bernstein(three_roots)), 3);
  // (t - 2)(t - 3)(t - 4): none in (0, 1) and V = 0.
  const Power3 no_roots{-24, 26, -9, 1};
  EXPECT_EQ(sign_variations(to_bernstein(no_roots)), 0);
  // (t - 0.5)(t^2 + 1): one root, V = 1.
  const Power3 one_root{-0.5, 1.0, -0.5, 1.0};
  EXPECT_EQ(sign_variations(to_bernstein(one_root)), 1);
}

TEST(Bernstein, SplitHalfGivesTheCubicOnEachHalf) {
  const Power3 a{-0.08, 0.66, -1.5, 1.0};  // roots 0.2, 0.5, 0.8
  const Bernstein3 b = to_bernstein(a);
  Bernstein3 left, right;
  split_half(b, left, right);
  for (Scalar s : {0.0, 0.25, 0.5, 0.75, 1.0}) {
    EXPECT_NEAR(evaluate_bernstein(left, s), evaluate_power(a, 0.5 * s), 1e-14);
    EXPECT_NEAR(evaluate_bernstein(right, s), evaluate_power(a, 0.5 + 0.5 * s), 1e-14);
  }
}

TEST(Bernstein, SubdivisionSeparatesSimpleRoots) {
  // Roots 0.2, 0.3, 0.8: V = 3 on [0, 1]; 2 on [0, 1/2] and 1 on [1/2, 1]; then 1 and 1 on the
  // quarters [0, 1/4] and [1/4, 1/2] (Vincent's theorem).
  const Bernstein3 b = to_bernstein({-0.048, 0.46, -1.3, 1.0});
  EXPECT_EQ(sign_variations(b), 3);
  Bernstein3 left, right, left_left, left_right;
  split_half(b, left, right);
  EXPECT_EQ(sign_variations(left), 2);
  EXPECT_EQ(sign_variations(right), 1);
  split_half(left, left_left, left_right);
  EXPECT_EQ(sign_variations(left_left), 1);
  EXPECT_EQ(sign_variations(left_right), 1);
}

TEST(Bernstein, SameStrictSignAndCertainlyNonzero) {
  EXPECT_TRUE(same_strict_sign({1, 2, 3, 4}));
  EXPECT_TRUE(same_strict_sign({-1, -2, -3, -4}));
  EXPECT_FALSE(same_strict_sign({1, 0, 3, 4}));
  EXPECT_TRUE(certainly_nonzero({1, 2, 3, 4}, 0.5));
  EXPECT_FALSE(certainly_nonzero({1, 2, 3, 4}, 1.0));
}
