// The independent intersection tests behind drape check.
#include <gtest/gtest.h>

#include "drape/core/penetration.h"

using namespace drape;

TEST(Penetration, SegmentTriangleCrossing) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(segment_crosses_triangle(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, -1), a, b, c));
  EXPECT_FALSE(segment_crosses_triangle(Vec3(0.8, 0.8, 1), Vec3(0.8, 0.8, -1), a, b, c));  // beside
  EXPECT_FALSE(segment_crosses_triangle(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0.5), a, b, c));  // short
  EXPECT_FALSE(segment_crosses_triangle(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0), a, b, c));    // only touches
}

TEST(Penetration, TriangleTriangle) {
  const std::array<Vec3, 3> flat{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const std::array<Vec3, 3> through{Vec3(0.2, 0.2, -1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.3, 1)};
  const std::array<Vec3, 3> above{Vec3(0.2, 0.2, 0.1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.3, 1)};
  const std::array<Vec3, 3> pierced{Vec3(-1, 0.25, -1), Vec3(2, 0.25, -1), Vec3(0.25, 0.25, 2)};  // big, cut by flat's edge
  EXPECT_TRUE(triangles_intersect(flat, through));
  EXPECT_FALSE(triangles_intersect(flat, above));
  EXPECT_TRUE(triangles_intersect(flat, pierced));
}

TEST(Penetration, FindsCrossedClothAndIgnoresNeighbours) {
  // Two separate quads of one cloth; push a vertex of the second through the first.
  Model model = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [1, 1]}},
    {"grid": {"resolution": [1, 1]}, "transform": {"translate": [0, 0, 0.1], "rotate": [90, 1, 0, 0]}}]})", "p.json"));
  std::vector<Vec3> x = model.initial_positions;
  EXPECT_TRUE(find_penetrations(model, x, 0).size() > 0);  // the upright quad goes through the flat one
  for (int v = 4; v < 8; ++v) x[v].z() += 1.0;              // lift it clear
  EXPECT_TRUE(find_penetrations(model, x, 0).empty());
}
