// The independent intersection tests behind drape check, decided exactly: every kind of
// meeting (crossing, coplanar overlap, touching) found, near misses of one unit in the last place
// not, for triangles, balls and half-spaces.
#include <gtest/gtest.h>

#include <cmath>

#include "drape/core/penetration.h"

using namespace drape;

namespace {

const TriangleCorners FLAT{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};

Scalar below(Scalar v) { return std::nextafter(v, -1.0); }
Scalar above(Scalar v) { return std::nextafter(v, 2.0); }

}  // namespace

TEST(Penetration, TrianglesCrossing) {
  const TriangleCorners through{Vec3(0.2, 0.2, -1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.3, 1)};
  const TriangleCorners pierced{Vec3(-1, 0.25, -1), Vec3(2, 0.25, -1), Vec3(0.25, 0.25, 2)};  // big, cut by FLAT's edge
  EXPECT_EQ(triangles_meet(FLAT, through), PenetrationKind::Crossing);
  EXPECT_EQ(triangles_meet(FLAT, pierced), PenetrationKind::Crossing);
  const TriangleCorners above_it{Vec3(0.2, 0.2, 0.1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.3, 1)};
  EXPECT_FALSE(triangles_meet(FLAT, above_it));
}

TEST(Penetration, CoplanarTrianglesOverlapping) {
  // Two triangles in z = 0 sharing an area, and sharing no vertex: floating-point determinants
  // of a crossing test are all zero here.
  const TriangleCorners overlapping{Vec3(0.25, 0.25, 0), Vec3(2, 0.25, 0), Vec3(0.25, 2, 0)};
  EXPECT_EQ(triangles_meet(FLAT, overlapping), PenetrationKind::CoplanarOverlap);
  // In one plane, apart by one unit in the last place across the hypotenuse x + y = 1.
  const TriangleCorners beside{Vec3(above(0.5), 0.5, 0), Vec3(1, 1, 0), Vec3(above(0.5), 2, 0)};
  EXPECT_FALSE(triangles_meet(FLAT, beside));
  // In a tilted plane that is not a coordinate plane, coplanar and overlapping.
  const Vec3 u(1, 0, 1), v(0, 1, 2);
  const TriangleCorners tilted{Vec3::Zero(), u, v};
  const TriangleCorners tilted_overlap{0.25 * u + 0.25 * v, 2 * u + 0.25 * v, 0.25 * u + 2 * v};
  EXPECT_EQ(triangles_meet(tilted, tilted_overlap), PenetrationKind::CoplanarOverlap);
}

TEST(Penetration, TrianglesTouchingAlongAnEdgeOrAtAPoint) {
  // A vertex exactly on FLAT's interior, the rest above: touching at a point.
  const TriangleCorners at_point{Vec3(0.25, 0.25, 0), Vec3(0.5, 0.25, 1), Vec3(0.25, 0.5, 1)};
  EXPECT_EQ(triangles_meet(FLAT, at_point), PenetrationKind::Touching);
  // An edge lying on FLAT, the third corner above: touching along an edge.
  const TriangleCorners along_edge{Vec3(0.1, 0.1, 0), Vec3(0.4, 0.1, 0), Vec3(0.2, 0.2, 1)};
  EXPECT_EQ(triangles_meet(FLAT, along_edge), PenetrationKind::Touching);
  // The same, one unit in the last place above: apart.
  const TriangleCorners lifted{Vec3(0.25, 0.25, above(0)), Vec3(0.5, 0.25, 1), Vec3(0.25, 0.5, 1)};
  EXPECT_FALSE(triangles_meet(FLAT, lifted));
  // A degenerate triangle (a segment) through FLAT, and one lying on it.
  const TriangleCorners needle{Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0.5)};
  EXPECT_EQ(triangles_meet(FLAT, needle), PenetrationKind::Crossing);
  const TriangleCorners lying{Vec3(0.1, 0.1, 0), Vec3(0.2, 0.2, 0), Vec3(0.3, 0.3, 0)};
  EXPECT_EQ(triangles_meet(FLAT, lying), PenetrationKind::CoplanarOverlap);
}

TEST(Penetration, BallsAndHalfSpacesExactly) {
  // A triangle cutting into a unit ball with every corner outside it.
  const TriangleCorners chord{Vec3(-2, -2, 0.5), Vec3(2, -2, 0.5), Vec3(0, 2, 0.5)};
  EXPECT_EQ(triangle_meets_ball(chord, Vec3::Zero(), 1.0), PenetrationKind::Crossing);
  // Tangent to the ball at (0, 0, 1): touching; one unit in the last place higher: apart.
  const TriangleCorners tangent{Vec3(-2, -2, 1), Vec3(2, -2, 1), Vec3(0, 2, 1)};
  EXPECT_EQ(triangle_meets_ball(tangent, Vec3::Zero(), 1.0), PenetrationKind::Touching);
  const TriangleCorners clear{Vec3(-2, -2, above(1)), Vec3(2, -2, above(1)), Vec3(0, 2, above(1))};
  EXPECT_FALSE(triangle_meets_ball(clear, Vec3::Zero(), 1.0));
  // A corner exactly on the sphere (0.6^2 + 0.8^2 = 1 is not exact in double: use 3-4-5 at scale 8).
  const TriangleCorners on_sphere{Vec3(3, 4, 0), Vec3(9, 9, 9), Vec3(9, 4, 0)};
  EXPECT_EQ(triangle_meets_ball(on_sphere, Vec3::Zero(), 5.0), PenetrationKind::Touching);
  // Half-spaces: a corner exactly on the plane, a corner one unit in the last place below.
  const Vec3 n(0, 0, 1);
  EXPECT_EQ(triangle_meets_half_space({Vec3(0, 0, 0), Vec3(1, 0, 1), Vec3(0, 1, 1)}, Vec3::Zero(), n),
            PenetrationKind::Touching);
  EXPECT_EQ(triangle_meets_half_space({Vec3(0, 0, below(0)), Vec3(1, 0, 1), Vec3(0, 1, 1)}, Vec3::Zero(), n),
            PenetrationKind::Crossing);
  EXPECT_FALSE(triangle_meets_half_space({Vec3(0, 0, above(0)), Vec3(1, 0, 1), Vec3(0, 1, 1)}, Vec3::Zero(), n));
}

TEST(Penetration, FindsCrossedClothAndIgnoresNeighbours) {
  // Two separate quads of one cloth; push a vertex of the second through the first.
  Model model = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [1, 1]}},
    {"grid": {"resolution": [1, 1]}, "transform": {"translate": [0, 0, 0.1], "rotate": [90, 1, 0, 0]}}]})", "p.json"));
  std::vector<Vec3> x = model.initial_positions;
  const auto found = find_penetrations(model, x, 0);
  ASSERT_FALSE(found.empty());  // the upright quad goes through the flat one
  EXPECT_EQ(found[0].kind, PenetrationKind::Crossing);
  EXPECT_NE(found[0].describe().find("crossing"), std::string::npos);
  for (int v = 4; v < 8; ++v) x[std::size_t(v)].z() += 1.0;  // lift it clear
  EXPECT_TRUE(find_penetrations(model, x, 0).empty());
}

TEST(Penetration, FindsCoplanarClothOverlapAndATriangleInsideASphere) {
  // Two flat quads of one cloth in one plane, the second shifted to overlap the first.
  Model model = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [1, 1]}},
    {"grid": {"resolution": [1, 1]}, "transform": {"translate": [0.25, 0.25, 0]}}]})", "p.json"));
  auto found = find_penetrations(model, model.initial_positions, 0);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found[0].kind, PenetrationKind::CoplanarOverlap);
  // A 1 m cloth (one quad) over a sphere of radius 0.3 whose top pokes 0.05 through its middle: every
  // cloth vertex stays outside, the triangles do not.
  Model draped = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [1, 1]}}],
    "obstacles": [{"sphere": {"center": [0, 0, -0.25], "radius": 0.3}}]})", "p.json"));
  found = find_penetrations(draped, draped.initial_positions, 0);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found[0].obstacle, 0);
  EXPECT_EQ(found[0].kind, PenetrationKind::Crossing);
}

TEST(Penetration, FindsTouchingClothOnHandMadeFrames) {
  // Two quads of one cloth; the second set by hand so that one of its edges lies exactly on the
  // first quad's plane, inside it, the rest of it above: touching, not crossing.
  Model model = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [1, 1]}}, {"grid": {"resolution": [1, 1]}}],
    "obstacles": [{"plane": {"point": [0, 0, -1], "normal": [0, 0, 1]}}]})", "p.json"));
  std::vector<Vec3> x = model.initial_positions;
  x[4] = Vec3(-0.25, -0.25, 0), x[5] = Vec3(0.25, -0.25, 0), x[6] = Vec3(-0.25, 0.25, 1), x[7] = Vec3(0.25, 0.25, 1);
  auto found = find_penetrations(model, x, 0);
  ASSERT_FALSE(found.empty());
  for (const Penetration& p : found) EXPECT_EQ(p.kind, PenetrationKind::Touching) << p.describe();
  // Lifted by one unit in the last place: nothing meets.
  x[4].z() = x[5].z() = above(0);
  EXPECT_TRUE(find_penetrations(model, x, 0).empty());
  // A corner of the first quad exactly on the ground plane z = -1: touching the obstacle.
  x[0].z() = -1;
  found = find_penetrations(model, x, 0);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found.back().obstacle, 0);
  EXPECT_EQ(found.back().kind, PenetrationKind::Touching);
}
