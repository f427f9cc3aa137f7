#include "drape/ccd/cubic_solver.h"

#include <algorithm>
#include <cmath>

namespace drape::ccd {
namespace {

constexpr Scalar PI = 3.14159265358979323846;
// Newton steps applied to each closed-form root: enough to reach full precision from the
// closed form's few-ulp (or, near a double root, square-root-of-ulp) error.
constexpr int POLISH_STEPS = 3;
// Only roots this close to [0, 1] (in units of the step) are polished: the others cannot
// become roots inside the step by polishing.
constexpr Scalar POLISH_WINDOW = 1e-3;

int solve_linear(Scalar a1, Scalar a0, std::array<Scalar, 3>& roots) {
  if (a1 == 0) return a0 == 0 ? -1 : 0;
  roots[0] = -a0 / a1;
  return 1;
}

int solve_quadratic(Scalar a2, Scalar a1, Scalar a0, std::array<Scalar, 3>& roots) {
  const Scalar scale = std::max({std::abs(a2), std::abs(a1), std::abs(a0)});
  if (std::abs(a2) <= LEADING_COEFFICIENT_RATIO * scale) return solve_linear(a1, a0, roots);
  const Scalar discriminant = a1 * a1 - 4 * a2 * a0;
  if (discriminant < 0) {
    if (-discriminant > DOUBLE_ROOT_RATIO * (a1 * a1 + std::abs(4 * a2 * a0))) return 0;
    roots[0] = -a1 / (2 * a2);  // a double root rounded into a complex pair
    return 1;
  }
  // The stable form: no cancellation between -a1 and the square root.
  const Scalar q = -0.5 * (a1 + std::copysign(std::sqrt(discriminant), a1));
  if (q == 0) {
    roots[0] = 0;
    return 1;
  }
  const Scalar r1 = q / a2;
  const Scalar r2 = a0 / q;
  roots[0] = std::min(r1, r2);
  roots[1] = std::max(r1, r2);
  return 2;
}

// Monic cubic t^3 + p t^2 + q t + r, after Numerical Recipes (3rd ed.) section 5.6.
int solve_monic_cubic(Scalar p, Scalar q, Scalar r, std::array<Scalar, 3>& roots) {
  const Scalar Q = (p * p - 3 * q) / 9;
  const Scalar R = (2 * p * p * p - 9 * p * q + 27 * r) / 54;
  const Scalar Q3 = Q * Q * Q;
  const Scalar R2 = R * R;
  if (R2 < Q3) {
    const Scalar theta = std::acos(std::clamp(R / std::sqrt(Q3), Scalar(-1), Scalar(1)));
    const Scalar m = -2 * std::sqrt(Q);
    roots[0] = m * std::cos(theta / 3) - p / 3;
    roots[1] = m * std::cos((theta + 2 * PI) / 3) - p / 3;
    roots[2] = m * std::cos((theta - 2 * PI) / 3) - p / 3;
    std::sort(roots.begin(), roots.end());
    return 3;
  }
  const Scalar A = -std::copysign(std::cbrt(std::abs(R) + std::sqrt(R2 - Q3)), R);
  const Scalar B = A != 0 ? Q / A : 0;
  roots[0] = (A + B) - p / 3;
  // The complex pair -(A+B)/2 - p/3 +- i sqrt(3)/2 (A-B) is a double real root when A = B.
  if (std::abs(A - B) <= std::sqrt(DOUBLE_ROOT_RATIO) * (std::abs(A) + std::abs(B))) {
    roots[1] = -0.5 * (A + B) - p / 3;
    if (roots[1] < roots[0]) std::swap(roots[0], roots[1]);
    return 2;
  }
  return 1;
}

}  // namespace

int solve_cubic(const Power3& a, std::array<Scalar, 3>& roots) {
  const Scalar scale = std::max({std::abs(a[0]), std::abs(a[1]), std::abs(a[2]), std::abs(a[3])});
  if (scale == 0) return -1;
  int count = 0;
  if (std::abs(a[3]) <= LEADING_COEFFICIENT_RATIO * scale) {
    count = solve_quadratic(a[2], a[1], a[0], roots);
    if (count < 0) return count;
  } else {
    count = solve_monic_cubic(a[2] / a[3], a[1] / a[3], a[0] / a[3], roots);
  }
  for (int i = 0; i < count; ++i) {
    Scalar t = roots[i];
    if (t < -POLISH_WINDOW || t > 1 + POLISH_WINDOW) continue;  // irrelevant to the step
    for (int step = 0; step < POLISH_STEPS; ++step) {
      const Scalar slope = evaluate_power_derivative(a, t);
      if (slope == 0) break;
      const Scalar next = t - evaluate_power(a, t) / slope;
      if (!std::isfinite(next)) break;
      t = next;
    }
    roots[i] = t;
  }
  std::sort(roots.begin(), roots.begin() + count);
  return count;
}

}  // namespace drape::ccd
