#pragma once
// Internal to ccd/: refining the one root of a cubic in Bernstein form on a bracket (vincent's
// intervals with one sign variation, conservative's monotone windows).

#include <array>
#include <cmath>

namespace drape::ccd::detail {

/// Root of a cubic with exactly one root on its interval (a sign change between the ends), in
/// the interval's local coordinate s in [0, 1]: safeguarded Newton (rtsafe, Numerical Recipes
/// section 9.4) inside the sign bracket, to within tolerance.
template <class T>
T refine_single_root(const std::array<T, 4>& b, T tolerance) {
  constexpr int MAX_ITERATIONS = 100;  // bisection alone halves the bracket 100 times
  const std::array<T, 4> a{b[0], 3 * (b[1] - b[0]), 3 * (b[2] - 2 * b[1] + b[0]), b[3] - 3 * b[2] + 3 * b[1] - b[0]};
  // The sign just right of s = 0 is that of the first nonzero coefficient.
  const T first = b[0] != 0 ? b[0] : (b[1] != 0 ? b[1] : b[2]);
  const bool negative_at_lo = first < 0;
  // Start at the midpoint: a secant start lands next to an end whose value is tiny, where the
  // computed sign may be wrong and the bracket would lose the root (found by the agreement test).
  T lo = 0, hi = 1, s = T(0.5);
  for (int iteration = 0; iteration < MAX_ITERATIONS; ++iteration) {
    const T f = ((a[3] * s + a[2]) * s + a[1]) * s + a[0];
    if (f == 0) return s;
    if ((f < 0) == negative_at_lo) lo = s; else hi = s;
    if (hi - lo <= tolerance) break;
    const T slope = (3 * a[3] * s + 2 * a[2]) * s + a[1];
    const T next = slope != 0 ? s - f / slope : lo;
    if (!(next > lo && next < hi)) {
      // Newton left the bracket: bisect. Where the midpoint rounds to s (a bound now), lo and
      // hi are adjacent numbers and every further iteration repeats this one, with the same
      // answer at the end: return it now (a tolerance below the spacing of the numbers near
      // the root, as the conservative search's monotone windows ask, would take all
      // MAX_ITERATIONS).
      const T mid = T(0.5) * (lo + hi);
      if (mid == s) break;
      s = mid;
    } else if (std::abs(next - s) <= tolerance) {
      return next;  // Newton converged
    } else {
      s = next;
    }
  }
  return T(0.5) * (lo + hi);
}

}  // namespace drape::ccd::detail
