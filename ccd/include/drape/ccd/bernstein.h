#pragma once
/// \file
/// Cubics on an interval in the Bernstein basis: evaluation, subdivision and sign variations.
///
/// Cubics on an interval in the Bernstein basis: d(t) = sum_i b_i C(3,i) s^i (1-s)^(3-i), where
/// s runs from 0 to 1 over the interval. ccd-notes.md section 2.

#include <algorithm>
#include <array>
#include <cmath>

#include "drape/ccd/types.h"

namespace drape::ccd {

using Bernstein3 = std::array<Scalar, 4>;
/// Power-basis coefficients a0 + a1 t + a2 t^2 + a3 t^3, lowest degree first.
using Power3 = std::array<Scalar, 4>;

/// Sign variations of (b0, b1, b2, b3), zeros skipped. By Descartes' rule applied through
/// t = 1/(1+x), the number of roots in the open interval is this number minus an even number.
inline int sign_variations(const Bernstein3& b) {
  // No zero coefficient (the usual case): count the changes without branching on the signs.
  if ((b[0] != 0) & (b[1] != 0) & (b[2] != 0) & (b[3] != 0))
    return ((b[0] < 0) != (b[1] < 0)) + ((b[1] < 0) != (b[2] < 0)) + ((b[2] < 0) != (b[3] < 0));
  int variations = 0;
  int last = 0;
  for (Scalar c : b) {
    const int sign = (c > 0) - (c < 0);
    if (sign == 0) continue;
    if (last != 0 && sign != last) ++variations;
    last = sign;
  }
  return variations;
}

/// True when the four coefficients are all > 0 or all < 0: the "deforming non-penetration
/// filter" of Tang et al. 2010 (no root in the closed interval).
inline bool same_strict_sign(const Bernstein3& b) {
  // Branch-free: the signs are random in a cloth step and a branch per comparison mispredicts.
  const Scalar lo = std::min(std::min(b[0], b[1]), std::min(b[2], b[3]));
  const Scalar hi = std::max(std::max(b[0], b[1]), std::max(b[2], b[3]));
  return (lo > 0) | (hi < 0);
}

/// True when every coefficient exceeds margin in one sign: the cubic is then certainly
/// nonzero on the interval even if each coefficient is off by up to margin. Any precision (the
/// conservative method also works in long double).
/// Without branches (& and | rather than && and ||): the signs are random in a cloth step and a
/// mispredicted branch costs more than the comparisons. A NaN coefficient gives false.
template <class T>
bool certainly_nonzero(const std::array<T, 4>& b, T margin) {
  return ((b[0] > margin) & (b[1] > margin) & (b[2] > margin) & (b[3] > margin)) |
         ((b[0] < -margin) & (b[1] < -margin) & (b[2] < -margin) & (b[3] < -margin));
}

/// de Casteljau split at the interval's midpoint: the coefficients on each half.
inline void split_half(const Bernstein3& b, Bernstein3& left, Bernstein3& right) {
  const Scalar b01 = 0.5 * (b[0] + b[1]);
  const Scalar b12 = 0.5 * (b[1] + b[2]);
  const Scalar b23 = 0.5 * (b[2] + b[3]);
  const Scalar b012 = 0.5 * (b01 + b12);
  const Scalar b123 = 0.5 * (b12 + b23);
  const Scalar mid = 0.5 * (b012 + b123);
  left = {b[0], b01, b012, mid};
  right = {mid, b123, b23, b[3]};
}

/// Power basis of the same cubic (t over the same interval).
inline Power3 to_power(const Bernstein3& b) {
  return {b[0], 3.0 * (b[1] - b[0]), 3.0 * (b[2] - 2.0 * b[1] + b[0]),
          b[3] - 3.0 * b[2] + 3.0 * b[1] - b[0]};
}

/// Bernstein basis on [0, 1] of a power-basis cubic (ccd-notes.md section 2).
inline Bernstein3 to_bernstein(const Power3& a) {
  return {a[0], a[0] + a[1] / 3.0, a[0] + 2.0 * a[1] / 3.0 + a[2] / 3.0, a[0] + a[1] + a[2] + a[3]};
}

/// Horner evaluation of a power-basis cubic.
inline Scalar evaluate_power(const Power3& a, Scalar t) { return ((a[3] * t + a[2]) * t + a[1]) * t + a[0]; }

/// Derivative of a power-basis cubic.
inline Scalar evaluate_power_derivative(const Power3& a, Scalar t) {
  return (3.0 * a[3] * t + 2.0 * a[2]) * t + a[1];
}

/// de Casteljau evaluation of a Bernstein cubic at s in [0, 1] (stable; used by tests).
inline Scalar evaluate_bernstein(const Bernstein3& b, Scalar s) {
  const Scalar r = 1.0 - s;
  const Scalar b01 = r * b[0] + s * b[1];
  const Scalar b12 = r * b[1] + s * b[2];
  const Scalar b23 = r * b[2] + s * b[3];
  const Scalar b012 = r * b01 + s * b12;
  const Scalar b123 = r * b12 + s * b23;
  return r * b012 + s * b123;
}

template <class T>
T max_abs(const std::array<T, 4>& b) {
  return std::max({std::abs(b[0]), std::abs(b[1]), std::abs(b[2]), std::abs(b[3])});
}

}  // namespace drape::ccd
