// The independent intersection tests behind drape check, decided exactly: every kind of
// meeting (crossing, coplanar overlap, touching) found, near misses of one unit in the last place
// not, for triangles, balls and half-spaces.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "drape/core/penetration.h"
#include "../temp_root.h"

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

// A scene whose meshes meet at its start is refused (drape keeps a cloth free of intersections
// only from a start free of them; a cloth started through a mesh box stayed through it in
// every frame, and a mesh cloth with overlapping triangles froze in the fail-safe, both
// silently): the error names the scene's JSON paths, the mesh files and triangles, and what is
// expected. What the run can answer for is a warning: cloth inside a sphere or below a plane
// (the first step pushes it out), meshes touching at distance exactly zero.
TEST(StartCheck, RefusesMeshesThatMeetAtTheStartAndNamesThem) {
  const std::filesystem::path dir = drape::testing::temp_root("penetration");
  std::filesystem::create_directories(dir);
  // Two triangles of one mesh overlapping in z = 0, sharing no vertex.
  std::ofstream(dir / "overlapping.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.25 0.25 0\nv 2 0.25 0\nv 0.25 2 0\nf 1 2 3\nf 4 5 6\n";
  const auto model_of = [&](const std::string& json) { return build_model(parse_scene(json, dir / "scene.json")); };
  const std::string overlapping = R"({"cloths": [{"mesh": "overlapping.obj", "transform": {"translate": [0, 0, 1]}}], "collisions": {"self": )";
  const StartCheck self = check_start(model_of(overlapping + "true}}"));
  EXPECT_NE(self.error.find("scene.json: the scene starts with its meshes meeting"), std::string::npos) << self.error;
  EXPECT_NE(self.error.find("/cloths/0 (overlapping.obj) triangles 0 and 1 overlap in one plane"), std::string::npos) << self.error;
  EXPECT_NE(self.error.find("or collisions.self false"), std::string::npos) << self.error;
  EXPECT_TRUE(check_start(model_of(overlapping + "false}}")).error.empty());  // self-collision off: nothing to keep apart

  // A grid through a mesh box (the shipped box.obj, a unit cube) cutting its sides: refused;
  // with obstacle collisions off, not. (A mesh is a surface: a cloth wholly inside a closed
  // mesh meets none of its triangles, and is not found.)
  const std::string box = std::string(DRAPE_SOURCE_DIR) + "/scenes/meshes/box.obj";
  const std::string through = R"({"cloths": [{"grid": {"size": [2, 2], "resolution": [5, 5]}, "transform": {"translate": [0, 0, 0.1]}}],
      "obstacles": [{"mesh": ")" + box + R"("}], "collisions": {"obstacles": )";
  const StartCheck boxed = check_start(model_of(through + "true}}"));
  EXPECT_NE(boxed.error.find("/cloths/0 (a grid) triangle "), std::string::npos) << boxed.error;
  EXPECT_NE(boxed.error.find(" passes through /obstacles/0 (box.obj) triangle "), std::string::npos) << boxed.error;
  EXPECT_NE(boxed.error.find("the cloths clear of the obstacles"), std::string::npos) << boxed.error;
  EXPECT_TRUE(check_start(model_of(through + "false}}")).error.empty());

  // Two grids crossing each other: refused with self-collision on.
  const StartCheck crossed = check_start(model_of(R"({"cloths": [{"grid": {"resolution": [2, 2]}},
      {"grid": {"resolution": [2, 2]}, "transform": {"rotate": [90, 1, 0, 0], "translate": [0.1, 0.1, 0.05]}}],
      "collisions": {"self": true}})"));
  EXPECT_NE(crossed.error.find("/cloths/0 (a grid) triangle "), std::string::npos) << crossed.error;
  EXPECT_NE(crossed.error.find(" and /cloths/1 (a grid) triangle "), std::string::npos) << crossed.error;
  EXPECT_NE(crossed.error.find("pass through each other"), std::string::npos) << crossed.error;

  // Below a plane: a warning, not an error; lying exactly on it: touching, a warning.
  const StartCheck below_plane = check_start(model_of(R"({"cloths": [{"grid": {}, "transform": {"translate": [0, 0, -0.05]}}],
      "obstacles": [{"plane": {}}]})"));
  EXPECT_TRUE(below_plane.error.empty()) << below_plane.error;
  EXPECT_NE(below_plane.warning.find("inside a sphere or below a plane, which its first step pushes out"), std::string::npos);
  EXPECT_NE(below_plane.warning.find("passes through /obstacles/0 (a plane: the half-space below it)"), std::string::npos);
  const StartCheck on_plane = check_start(model_of(R"({"cloths": [{"grid": {}}], "obstacles": [{"plane": {}}]})"));
  EXPECT_TRUE(on_plane.error.empty()) << on_plane.error;
  EXPECT_NE(on_plane.warning.find("touching (at distance exactly zero"), std::string::npos) << on_plane.warning;
  // Clear of everything: neither.
  const StartCheck clear = check_start(model_of(R"({"cloths": [{"grid": {}, "transform": {"translate": [0, 0, 1]}}],
      "obstacles": [{"plane": {}}], "collisions": {"self": true}})"));
  EXPECT_TRUE(clear.error.empty() && clear.warning.empty()) << clear.error << clear.warning;
}
