#include "drape/core/textile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <stdexcept>

namespace drape {
namespace {

// Grids larger than this per side get coarser cells instead (memory: one byte a cell).
constexpr int MAX_CELLS_PER_SIDE = 8192;

// Peaks of a circular signal that rise and fall by at least prominence on both sides: a
// hysteresis walk from its lowest point around the circle and back. Each peak's depth is the
// lesser of its rise from the lowest point since the peak before and its fall to the lowest
// point before the next one.
std::vector<Scalar> peak_depths(const std::vector<Scalar>& s, Scalar prominence) {
  const std::size_t n = s.size();
  const std::size_t start = std::size_t(std::min_element(s.begin(), s.end()) - s.begin());
  bool rising = true;
  Scalar trough = s[start], peak = s[start], before = s[start];  // before: the trough the peak rose from
  bool falling_from_counted = false;  // a counted peak whose fall is still being followed
  Scalar counted_peak = 0, counted_rise = 0;
  std::vector<Scalar> depths;
  const auto close = [&] {
    depths.push_back(std::min(counted_rise, counted_peak - trough));
    falling_from_counted = false;
  };
  for (std::size_t k = 1; k <= n; ++k) {
    const Scalar x = s[(start + k) % n];
    if (rising) {
      trough = std::min(trough, x);
      if (x - trough >= prominence) {
        if (falling_from_counted) close();
        rising = false, peak = x, before = trough;
      }
    } else {
      peak = std::max(peak, x);
      if (peak - x >= prominence) {
        falling_from_counted = true, counted_peak = peak, counted_rise = peak - before;
        rising = true, trough = x;
      }
    }
  }
  if (falling_from_counted) close();  // the walk ends on the lowest point: the last peak's fall
  return depths;
}

}  // namespace

CusickResult measure_cusick(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles, const CusickSetup& setup) {
  if (!(setup.support_radius > 0 && setup.fabric_radius > setup.support_radius))
    throw std::invalid_argument("expected radii with 0 < support radius < fabric radius");
  if (!(setup.down.norm() > 0)) throw std::invalid_argument("expected a direction of projection of nonzero length");
  const Vec3 down = setup.down.normalized(), u = down.unitOrthogonal(), v = down.cross(u);
  // The cloth in the plane across the axis, relative to the axis.
  std::vector<Eigen::Vector2d> p(positions.size());
  Scalar extent = setup.fabric_radius;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3 d = positions[i] - setup.centre;
    p[i] = Eigen::Vector2d(d.dot(u), d.dot(v));
    extent = std::max(extent, p[i].cwiseAbs().maxCoeff());
  }
  Scalar cell = SHADOW_CELL * setup.fabric_radius;
  int side = int(std::ceil(2 * extent / cell)) + 2;
  if (side > MAX_CELLS_PER_SIDE) side = MAX_CELLS_PER_SIDE, cell = 2 * extent / (side - 2);
  const Scalar origin = -extent - cell;  // the grid's lower corner, both axes
  std::vector<unsigned char> covered(std::size_t(side) * side, 0);
  // Each triangle's cells: those whose centres lie inside it or on its edges.
  for (const Triangle& t : triangles) {
    const Eigen::Vector2d a = p[t[0]], b = p[t[1]], c = p[t[2]];
    const auto edge = [](const Eigen::Vector2d& from, const Eigen::Vector2d& to, const Eigen::Vector2d& q) {
      return (to.x() - from.x()) * (q.y() - from.y()) - (to.y() - from.y()) * (q.x() - from.x());
    };
    const Scalar area = edge(a, b, c);
    if (area == 0) continue;  // seen edge-on: no area in the shadow
    const Eigen::Vector2d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    const int x0 = std::max(0, int(std::floor((lo.x() - origin) / cell))), x1 = std::min(side - 1, int(std::ceil((hi.x() - origin) / cell)));
    const int y0 = std::max(0, int(std::floor((lo.y() - origin) / cell))), y1 = std::min(side - 1, int(std::ceil((hi.y() - origin) / cell)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d q(origin + (x + 0.5) * cell, origin + (y + 0.5) * cell);
        const Scalar e0 = edge(a, b, q), e1 = edge(b, c, q), e2 = edge(c, a, q);
        const bool inside = area > 0 ? (e0 >= 0 && e1 >= 0 && e2 >= 0) : (e0 <= 0 && e1 <= 0 && e2 <= 0);
        if (inside) covered[std::size_t(y) * side + x] = 1;
      }
  }
  CusickResult r;
  r.outline.assign(OUTLINE_BINS, 0);
  long cells = 0;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      if (!covered[std::size_t(y) * side + x]) continue;
      ++cells;
      const Eigen::Vector2d q(origin + (x + 0.5) * cell, origin + (y + 0.5) * cell);
      const int bin = std::min(OUTLINE_BINS - 1, int((std::atan2(q.y(), q.x()) + M_PI) / (2 * M_PI) * OUTLINE_BINS));
      r.outline[std::size_t(bin)] = std::max(r.outline[std::size_t(bin)], q.norm());
    }
  r.shadow_area = Scalar(cells) * cell * cell;
  const Scalar fabric = M_PI * setup.fabric_radius * setup.fabric_radius, support = M_PI * setup.support_radius * setup.support_radius;
  r.drape_coefficient = (r.shadow_area - support) / (fabric - support);
  std::vector<Scalar> smooth(OUTLINE_BINS, 0);
  for (int i = 0; i < OUTLINE_BINS; ++i) {
    for (int k = -OUTLINE_SMOOTHING; k <= OUTLINE_SMOOTHING; ++k) smooth[std::size_t(i)] += r.outline[std::size_t((i + k + OUTLINE_BINS) % OUTLINE_BINS)];
    smooth[std::size_t(i)] /= 2 * OUTLINE_SMOOTHING + 1;
  }
  r.node_depths = peak_depths(smooth, NODE_PROMINENCE * setup.fabric_radius);
  r.nodes = int(r.node_depths.size());
  return r;
}

// The heavy elastica: theta'' = -q (L - s) cos theta with theta(0) = 0 (clamped level) and
// theta'(L) = 0 (a free end carries no moment), theta the strip's angle below the level at
// arc length s and q = w g / B. Central differences on ELASTICA_INTERVALS intervals, solved by
// Newton's method, the load raised from zero in ELASTICA_STAGES steps (shooting on theta'(0)
// or on the tip's angle finds spurious roots once the strip hangs nearly straight down); the
// drop is the integral of sin theta.
Scalar heavy_elastica_drop(Scalar length, Scalar load_over_rigidity) {
  if (!(std::isfinite(length) && length > 0 && std::isfinite(load_over_rigidity) && load_over_rigidity >= 0))
    throw std::invalid_argument("expected a finite positive length and a finite load over rigidity of 0 or more");
  constexpr int ELASTICA_STAGES = 100, NEWTON_ITERATIONS = 50;
  constexpr Scalar NEWTON_STEP = 1e-13;  // rad: the largest change that ends the iteration
  constexpr Scalar UNCONVERGED = 1e-9;   // rad: a last change this large after every iteration
  const int n = ELASTICA_INTERVALS;      // theta_0 = 0 is fixed, theta_1 .. theta_n unknown
  const Scalar h = length / n;
  std::vector<Scalar> theta(n + 1, 0.0), lower(n + 1), diagonal(n + 1), upper(n + 1), residual(n + 1);
  for (int stage = 1; stage <= ELASTICA_STAGES; ++stage) {
    const Scalar q = load_over_rigidity * stage / ELASTICA_STAGES;
    for (int iteration = 0; iteration < NEWTON_ITERATIONS; ++iteration) {
      // Row i: (theta_{i-1} - 2 theta_i + theta_{i+1}) / h^2 + q (L - s_i) cos theta_i, with
      // theta_{n+1} = theta_{n-1} at the free end; its Jacobian is tridiagonal.
      for (int i = 1; i <= n; ++i) {
        const std::size_t k = std::size_t(i);
        const Scalar next = i < n ? theta[k + 1] : theta[std::size_t(n - 1)];
        const Scalar load = q * (length - i * h);
        residual[k] = (theta[k - 1] - 2 * theta[k] + next) / (h * h) + load * std::cos(theta[k]);
        lower[k] = i < n ? 1 / (h * h) : 2 / (h * h);
        upper[k] = 1 / (h * h);
        diagonal[k] = -2 / (h * h) - load * std::sin(theta[k]);
      }
      // Thomas's algorithm on J delta = -residual (row 1 has no lower term: theta_0 is fixed).
      for (std::size_t k = 2; k <= std::size_t(n); ++k) {
        const Scalar factor = lower[k] / diagonal[k - 1];
        diagonal[k] -= factor * upper[k - 1];
        residual[k] -= factor * residual[k - 1];
      }
      Scalar largest = 0, delta = 0;
      for (std::size_t k = std::size_t(n); k >= 1; --k) {
        delta = (-residual[k] - (k < std::size_t(n) ? upper[k] * delta : 0)) / diagonal[k];
        theta[k] += delta;
        largest = std::max(largest, std::abs(delta));
      }
      if (largest < NEWTON_STEP) break;
      // Rounding may stall the last steps above NEWTON_STEP; a step above UNCONVERGED is not rounding.
      if (iteration + 1 == NEWTON_ITERATIONS && largest > UNCONVERGED)
        throw std::invalid_argument("the heavy elastica did not converge (length " + std::to_string(length) +
                                    " m, load over rigidity " + std::to_string(load_over_rigidity) + " 1/m^3)");
    }
  }
  Scalar drop = 0;
  for (std::size_t k = 0; k < std::size_t(n); ++k) drop += 0.5 * h * (std::sin(theta[k]) + std::sin(theta[k + 1]));
  return drop;
}

Scalar elastica_bending_length(Scalar length, Scalar drop) {
  if (!(std::isfinite(length) && length > 0 && std::isfinite(drop) && drop > 0))
    throw std::invalid_argument("expected a finite positive length and a tip that dropped (length " + std::to_string(length) +
                                " m, drop " + std::to_string(drop) + " m)");
  const auto drop_for = [&](Scalar c) { return heavy_elastica_drop(length, 1 / (c * c * c)); };
  // The shortest bending length told apart, and the longest: a heavy elastica drops less than
  // the linear beam's L^4 / (8 c^3), so the beam's c for this drop drops at most this much
  // (capped where the drop is too small to tell: a millionth of the length).
  const Scalar lo0 = length / MAX_OVERHANG_OVER_BENDING_LENGTH, shortest_drop = drop_for(lo0);
  if (!(drop < shortest_drop))
    throw std::invalid_argument("a drop of " + std::to_string(drop) + " m from a clamped length of " + std::to_string(length) +
                                " m is more than a strip of bending length 1/" +
                                std::to_string(int(MAX_OVERHANG_OVER_BENDING_LENGTH)) + " of it drops (" +
                                std::to_string(shortest_drop) + " m): too nearly straight down to tell a bending length");
  if (!(drop > MIN_DROP_OVER_LENGTH * length))
    throw std::invalid_argument("a drop of " + std::to_string(drop) + " m from a clamped length of " + std::to_string(length) +
                                " m is too small to tell a bending length");
  Scalar lo = lo0, hi = std::cbrt(std::pow(length, 4) / (8 * drop));
  if (hi <= lo) return lo;
  while (hi / lo - 1 > BENDING_LENGTH_TOLERANCE) {
    const Scalar mid = std::sqrt(lo * hi);
    (drop_for(mid) > drop ? lo : hi) = mid;  // a longer bending length drops less
  }
  return std::sqrt(lo * hi);
}

CantileverResult measure_cantilever(const std::vector<Vec3>& initial, const std::vector<Vec3>& positions,
                                    const std::vector<bool>& held, const Vec3& down) {
  if (initial.size() != positions.size() || held.size() != positions.size())
    throw std::invalid_argument("expected the start, the frame and the held flags for the same vertices");
  if (!(down.norm() > 0)) throw std::invalid_argument("expected gravity of nonzero length");
  const Vec3 g = down.normalized();
  Vec3 clamp = Vec3::Zero(), free = Vec3::Zero();
  int held_count = 0, free_count = 0;
  for (std::size_t v = 0; v < initial.size(); ++v)
    if (held[v]) clamp += initial[v], ++held_count;
    else free += initial[v], ++free_count;
  if (held_count == 0) throw std::invalid_argument("expected a clamp: vertices held by a handle");
  if (free_count == 0) throw std::invalid_argument("expected free vertices beyond the clamp");
  Vec3 along = free / free_count - clamp / held_count;
  along -= along.dot(g) * g;
  Scalar extent = 0;  // the strip's size, against which the free part's offset must tell a direction
  for (const Vec3& x : initial) extent = std::max(extent, (x - initial.front()).norm());
  if (!(along.norm() > TIP_BAND * extent))
    throw std::invalid_argument("expected the free vertices beside the clamp, across gravity (a strip held at one end)");
  along.normalize();
  // Distances along the strip: the clamp's edge, the first free column, the tip.
  Scalar edge = -std::numeric_limits<Scalar>::infinity(), tip = edge;
  for (std::size_t v = 0; v < initial.size(); ++v)
    if (held[v]) edge = std::max(edge, initial[v].dot(along));
    else tip = std::max(tip, initial[v].dot(along));
  CantileverResult r;
  r.overhang = tip - edge;
  if (!(r.overhang > 0)) throw std::invalid_argument("expected free vertices beyond the clamp's edge");
  Scalar first = r.overhang;
  for (std::size_t v = 0; v < initial.size(); ++v)
    if (!held[v] && initial[v].dot(along) > edge) first = std::min(first, initial[v].dot(along) - edge);
  r.clamp_offset = first / 2;
  const Scalar tip_band = TIP_BAND * r.overhang;  // the tip: free vertices this close to the farthest
  for (std::size_t v = 0; v < initial.size(); ++v)
    if (!held[v] && initial[v].dot(along) >= tip - tip_band) r.drop += (positions[v] - initial[v]).dot(g), ++r.tip_vertices;
  r.drop /= r.tip_vertices;
  return r;
}

}  // namespace drape
