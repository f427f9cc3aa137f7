// The textile laboratory's measurements on shapes whose answers are known in closed form: the
// Cusick drape test's, and the cantilever test's with the heavy elastica it compares against.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
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
    // Each node 0.04 m deep, less the smoothing over 5 degrees each side (sin 30 deg / (pi / 6)).
    ASSERT_EQ(r.node_depths.size(), 6u);
    for (const Scalar depth : r.node_depths) EXPECT_NEAR(depth / (0.04 * 0.5 / (M_PI / 6)), 1.0, 0.02) << slanted;
  }
  const Mesh ripples = polar_mesh([](Scalar f, Scalar a) {
    const Scalar r = f * (0.12 + 0.001 * std::cos(6 * a));
    return Vec3(r * std::cos(a), r * std::sin(a), 0);
  });
  EXPECT_EQ(measure_cusick(ripples.x, ripples.t, {}).nodes, 0);
}

// r = 0.12 + 0.02 cos 6a + 0.006 cos 3a: six nodes, alternately deeper and shallower by twice
// the small wave (smoothed): about 0.0441 and 0.0323 m, in that order from a = 0.
TEST(Cusick, ANodesDepthIsItsRiseAboveTheTroughsBesideIt) {
  const Mesh m = polar_mesh([](Scalar f, Scalar a) {
    const Scalar r = f * (0.12 + 0.02 * std::cos(6 * a) + 0.006 * std::cos(3 * a));
    return Vec3(r * std::cos(a), r * std::sin(a), 0);
  });
  const CusickResult r = measure_cusick(m.x, m.t, {});
  ASSERT_EQ(r.nodes, 6);
  ASSERT_EQ(r.node_depths.size(), 6u);
  const Scalar smooth6 = 0.5 / (M_PI / 6), smooth3 = std::sin(M_PI / 12) / (M_PI / 12);  // over +-5 degrees
  const Scalar deep = 0.04 * smooth6 + 0.006 * smooth3, shallow = 0.04 * smooth6 - 0.006 * smooth3;
  int deeper = 0, shallower = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    const Scalar d = r.node_depths[k], next = r.node_depths[(k + 1) % 6];
    if (std::abs(d / deep - 1) < 0.03) ++deeper;
    if (std::abs(d / shallow - 1) < 0.03) ++shallower;
    EXPECT_GT(std::abs(d - next), 0.5 * (deep - shallow)) << "nodes " << k << " and " << (k + 1) % 6 << " alternate";
  }
  EXPECT_EQ(deeper, 3);
  EXPECT_EQ(shallower, 3);
  // r = 0.12 + 0.02 cos 6a + 0.006 sin 3a: equal peaks between troughs alternately 0.006 higher
  // and lower: each node's depth is its rise above the higher trough, 2 x 0.02 - 0.006 (smoothed).
  const Mesh lopsided = polar_mesh([](Scalar f, Scalar a) {
    const Scalar r = f * (0.12 + 0.02 * std::cos(6 * a) + 0.006 * std::sin(3 * a));
    return Vec3(r * std::cos(a), r * std::sin(a), 0);
  });
  const CusickResult l = measure_cusick(lopsided.x, lopsided.t, {});
  ASSERT_EQ(l.node_depths.size(), 6u);
  for (const Scalar d : l.node_depths) EXPECT_NEAR(d / shallow, 1.0, 0.03);
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

TEST(Cantilever, TheElasticaSolverMeetsTheBeamAndItself) {
  // The reference itself: a light load is the linear beam's w L^4 / (8 B); a strip of bending
  // length c overhanging 2c drops 0.6406 of its length at any scale (a property of the
  // equation, found here by the solver at two scales).
  EXPECT_NEAR(heavy_elastica_drop(1, 0.01) / (0.01 / 8), 1, 1e-4);
  const Scalar small = heavy_elastica_drop(0.02, 1 / std::pow(0.01, 3)) / 0.02;
  EXPECT_NEAR(heavy_elastica_drop(0.12, 1 / std::pow(0.06, 3)) / 0.12, small, 1e-6);
  EXPECT_NEAR(small, 0.6406, 1e-3);  // shooting on theta'(0), where it finds the root, gives 0.64063
  // Six bending lengths out it hangs nearly straight down.
  EXPECT_GT(heavy_elastica_drop(0.06, 1 / std::pow(0.01, 3)) / 0.06, 0.9);
}


TEST(Cantilever, TheBendingLengthOfADropIsTheElasticasInverse) {
  for (const Scalar c : {0.005, 0.01, 0.03, 0.06, 0.5}) {
    const Scalar length = 0.06, drop = heavy_elastica_drop(length, 1 / (c * c * c));
    EXPECT_NEAR(elastica_bending_length(length, drop) / c, 1, 1e-5) << "c " << c;
  }
  EXPECT_THROW(elastica_bending_length(0.06, 0), std::invalid_argument);
  EXPECT_THROW(elastica_bending_length(0.06, -1e-3), std::invalid_argument);
  EXPECT_THROW(elastica_bending_length(0.06, 0.06), std::invalid_argument);  // straight down: any short c
  EXPECT_THROW(elastica_bending_length(0, 0.01), std::invalid_argument);
  EXPECT_THROW(heavy_elastica_drop(0.06, std::nan("")), std::invalid_argument);
}

TEST(Cantilever, AStripTurnedAboutItsClampsEdgeDropsByTheSine) {
  // A strip of 4 x 3 held columns behind x = 0 and 8 free ones of 1 cm beyond it, its free part
  // turned down by 30 degrees about the clamp's edge; the whole set-up then turned and moved
  // anywhere, gravity with it.
  const Scalar a = 0.01, angle = M_PI / 6;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 shift(3, -2, 5);
  std::vector<Vec3> initial, bent;
  std::vector<bool> held;
  for (int i = -3; i <= 8; ++i)
    for (int j = 0; j < 4; ++j) {
      const Scalar x = i * a, y = j * 0.005;
      initial.push_back(turn * Vec3(x, y, 0) + shift);
      bent.push_back(turn * (x > 0 ? Vec3(x * std::cos(angle), y, -x * std::sin(angle)) : Vec3(x, y, 0)) + shift);
      held.push_back(x <= 0);
    }
  const CantileverResult r = measure_cantilever(initial, bent, held, turn * Vec3(0, 0, -9.81));
  EXPECT_NEAR(r.overhang, 8 * a, 1e-12);
  EXPECT_NEAR(r.clamp_offset, a / 2, 1e-12);
  EXPECT_EQ(r.tip_vertices, 4);
  EXPECT_NEAR(r.drop, 8 * a * std::sin(angle), 1e-12);
  EXPECT_NEAR(r.clamped_length(), 8.5 * a, 1e-12);
}

TEST(Cantilever, AStripWithoutAClampOrAnOverhangIsRefused) {
  const std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0.02, 0, 0)};
  const Vec3 down(0, 0, -1);
  EXPECT_THROW(measure_cantilever(x, x, {false, false, false}, down), std::invalid_argument);
  EXPECT_THROW(measure_cantilever(x, x, {true, true, true}, down), std::invalid_argument);
  EXPECT_THROW(measure_cantilever(x, x, {true, false}, down), std::invalid_argument);
  EXPECT_THROW(measure_cantilever(x, x, {true, false, false}, Vec3::Zero()), std::invalid_argument);
  // Free vertices straight below the clamp: no overhang across gravity.
  const std::vector<Vec3> hanging = {Vec3(0, 0, 0), Vec3(0, 0, -0.01)};
  EXPECT_THROW(measure_cantilever(hanging, hanging, {true, false}, down), std::invalid_argument);
  EXPECT_NO_THROW(measure_cantilever(x, x, {true, false, false}, down));
}
