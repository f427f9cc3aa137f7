#include "drape/core/textile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drape {
namespace {

// Grids larger than this per side get coarser cells instead (memory: one byte a cell).
constexpr int MAX_CELLS_PER_SIDE = 8192;

// Peaks of a circular signal that rise and fall by at least prominence on both sides: a
// hysteresis walk from its lowest point around the circle and back.
int count_peaks(const std::vector<Scalar>& s, Scalar prominence) {
  const std::size_t n = s.size();
  const std::size_t start = std::size_t(std::min_element(s.begin(), s.end()) - s.begin());
  bool rising = true;
  Scalar trough = s[start], peak = s[start];
  int peaks = 0;
  for (std::size_t k = 1; k <= n; ++k) {
    const Scalar x = s[(start + k) % n];
    if (rising) {
      trough = std::min(trough, x);
      if (x - trough >= prominence) rising = false, peak = x;
    } else {
      peak = std::max(peak, x);
      if (peak - x >= prominence) ++peaks, rising = true, trough = x;
    }
  }
  return peaks;  // the walk ends on the lowest point: a peak still open has fallen to it
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
  r.nodes = count_peaks(smooth, NODE_PROMINENCE * setup.fabric_radius);
  return r;
}

}  // namespace drape
