// The Cusick drape test's measurements on shapes whose answers are known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

#include "drape/core/textile.h"

using namespace drape;

namespace {

// A disc meshed in rings around its centre; place(radius fraction, angle) gives each vertex.
struct Mesh {
  std::vector<Vec3> x;
  std::vector<Triangle> t;
};
Mesh polar_mesh(const std::function<Vec3(Scalar, Scalar)>& place, int rings = 40, int segments = 360) {
  Mesh m;
  m.x.push_back(place(0, 0));
  for (int k = 1; k <= rings; ++k)
    for (int s = 0; s < segments; ++s) m.x.push_back(place(Scalar(k) / rings, 2 * M_PI * s / segments));
  const auto at = [&](int k, int s) { return k == 0 ? 0 : 1 + (k - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.t.push_back({0, at(1, s), at(1, s + 1)});
  for (int k = 1; k < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      m.t.push_back({at(k, s), at(k + 1, s), at(k + 1, s + 1)});
      m.t.push_back({at(k, s), at(k + 1, s + 1), at(k, s + 1)});
    }
  return m;
}

// The area of a regular polygon of n sides inscribed in a circle, over the circle's.
Scalar polygon_fraction(int n) { return n / (2 * M_PI) * std::sin(2 * M_PI / n); }

constexpr Scalar FABRIC = 0.15, SUPPORT = 0.09;

}  // namespace

TEST(Cusick, AFlatDiscHasCoefficientOneAndNoNodes) {
  const Mesh m = polar_mesh([](Scalar f, Scalar a) { return Vec3(FABRIC * f * std::cos(a), FABRIC * f * std::sin(a), 0.3); });
  const CusickResult r = measure_cusick(m.x, m.t, {});
  const Scalar polygon = polygon_fraction(360) * M_PI * FABRIC * FABRIC;
  EXPECT_NEAR(r.shadow_area / polygon, 1.0, 2e-3);
  EXPECT_NEAR(r.drape_coefficient, 1.0, 2e-3);
  EXPECT_EQ(r.nodes, 0);
}

// The part beyond the support hangs straight down (a cylinder seen end on): no shadow beyond
// the support's.
TEST(Cusick, AClothHangingStraightDownHasCoefficientZero) {
  const Mesh m = polar_mesh([](Scalar f, Scalar a) {
    const Scalar r = FABRIC * f;
    const Scalar radius = std::min(r, SUPPORT), drop = std::max<Scalar>(0, r - SUPPORT);
    return Vec3(radius * std::cos(a), radius * std::sin(a), 0.3 - drop);
  });
  const CusickResult r = measure_cusick(m.x, m.t, {});
  EXPECT_NEAR(r.drape_coefficient, 0.0, 3e-3);
  EXPECT_EQ(r.nodes, 0);
}

// A flat outline r = 0.12 + 0.02 cos 6a: six folds, and a shadow of pi (0.12^2 + 0.02^2 / 2).
// Seen along a slanted axis, the same. Lobes below the prominence are no nodes.
TEST(Cusick, SixLobesAreSixNodesAndTheirAreaIsExact) {
  const Vec3 axis = Vec3(1, 2, -3).normalized(), e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  for (const bool slanted : {false, true}) {
    const Mesh m = polar_mesh([&](Scalar f, Scalar a) {
      const Scalar r = f * (0.12 + 0.02 * std::cos(6 * a));
      return slanted ? Vec3(r * std::cos(a) * e1 + r * std::sin(a) * e2 + 0.5 * axis) : Vec3(r * std::cos(a), r * std::sin(a), 0);
    });
    CusickSetup setup;
    if (slanted) setup.down = axis;
    const CusickResult r = measure_cusick(m.x, m.t, setup);
    const Scalar area = M_PI * (0.12 * 0.12 + 0.02 * 0.02 / 2);
    EXPECT_NEAR(r.shadow_area / area, 1.0, 2e-3) << slanted;
    EXPECT_NEAR(r.drape_coefficient, (area - M_PI * SUPPORT * SUPPORT) / (M_PI * (FABRIC * FABRIC - SUPPORT * SUPPORT)), 3e-3);
    EXPECT_EQ(r.nodes, 6) << slanted;
  }
  const Mesh ripples = polar_mesh([](Scalar f, Scalar a) {
    const Scalar r = f * (0.12 + 0.001 * std::cos(6 * a));
    return Vec3(r * std::cos(a), r * std::sin(a), 0);
  });
  EXPECT_EQ(measure_cusick(ripples.x, ripples.t, {}).nodes, 0);
}

TEST(Cusick, ADegenerateSetupIsRefused) {
  const Mesh m = polar_mesh([](Scalar f, Scalar a) { return Vec3(f * std::cos(a), f * std::sin(a), 0); }, 2, 8);
  CusickSetup inverted;
  inverted.support_radius = 0.2;
  EXPECT_THROW(measure_cusick(m.x, m.t, inverted), std::invalid_argument);
  CusickSetup nowhere;
  nowhere.down = Vec3::Zero();
  EXPECT_THROW(measure_cusick(m.x, m.t, nowhere), std::invalid_argument);
}
