// Hand-built queries with known answers: simple contacts and misses, and every degenerate case
// of ccd-notes.md section 3, at scales from 1e-8 to 1e8. The conservative method must be right
// on all of them; the root-finding methods on the ones their contract covers.
#include <gtest/gtest.h>

#include "drape/ccd/query.h"

using namespace drape;
using namespace drape::ccd;

namespace {

constexpr Method ROOT_FINDING[] = {Method::Cubic, Method::Dnf, Method::Vincent};

Result run(Method method, QueryKind kind, const Query& q) {
  Options options;
  options.method = method;
  return elementary_ccd(kind, q, options);
}

Query static_triangle_with_vertex(const Vec3& vertex_start, const Vec3& vertex_end) {
  Query q;
  q.start = {vertex_start, Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  q.end = {vertex_end, Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  return q;
}

Query scaled(Query q, Scalar scale, const Vec3& offset = Vec3::Zero()) {
  for (int i = 0; i < 4; ++i) q.start[i] = q.start[i] * scale + offset, q.end[i] = q.end[i] * scale + offset;
  return q;
}

void expect_all_methods(QueryKind kind, const Query& q, bool hit, Scalar toc = -1) {
  for (Method m : ALL_METHODS) {
    const Result r = run(m, kind, q);
    EXPECT_EQ(r.hit, hit) << method_name(m);
    if (hit && toc >= 0) {
      EXPECT_NEAR(r.toc, toc, 1e-6) << method_name(m);
    }
  }
}

}  // namespace

TEST(DegenerateCases, VertexThroughFaceInterior) {
  const Query q = static_triangle_with_vertex(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, -1));
  expect_all_methods(QueryKind::VertexFace, q, true, 0.5);
  const Result r = run(Method::Vincent, QueryKind::VertexFace, q);
  EXPECT_NEAR(r.params[0], 0.25, 1e-9);
  EXPECT_NEAR(r.params[1], 0.25, 1e-9);
}

TEST(DegenerateCases, VertexPassesBesideFace) {
  expect_all_methods(QueryKind::VertexFace, static_triangle_with_vertex(Vec3(0.75, 0.75, 1), Vec3(0.75, 0.75, -1)),
                     false);
}

TEST(DegenerateCases, CoplanarMotionIntoTheFace) {
  // Everything in z = 0: the cubic vanishes identically. The vertex enters across the edge
  // x + y = 1 at t = 0.25 (from (1, 0.5) to (-1, 0.5): x + y = 1 at x = 0.5).
  const Query q = static_triangle_with_vertex(Vec3(1, 0.5, 0), Vec3(-1, 0.5, 0));
  for (Method m : ALL_METHODS) {
    const Result r = run(m, QueryKind::VertexFace, q);
    EXPECT_TRUE(r.hit) << method_name(m);
    EXPECT_LE(r.toc, 0.25 + 1e-9) << method_name(m);
    EXPECT_GE(r.toc, 0.25 - 1e-6) << method_name(m);
    EXPECT_NE(r.path, Path::Culled) << method_name(m);
  }
}

TEST(DegenerateCases, CoplanarMotionBesideTheFace) {
  expect_all_methods(QueryKind::VertexFace, static_triangle_with_vertex(Vec3(1, 0.25, 0), Vec3(1, 1, 0)), false);
}

TEST(DegenerateCases, ZeroAreaTriangle) {
  // Collinear corners along the x axis; the vertex crosses the segment at t = 0.5, or misses it.
  Query q;
  q.start = {Vec3(0.5, 1, 0.25), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  q.end = {Vec3(0.5, -1, -0.25), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  EXPECT_TRUE(run(Method::Conservative, QueryKind::VertexFace, q).hit);
  q.start[0].z() = 1;  // now passes 0.375 above the segment at its closest
  q.end[0].z() = 0.25;
  EXPECT_FALSE(run(Method::Conservative, QueryKind::VertexFace, q).hit);
}

TEST(DegenerateCases, ZeroMotion) {
  expect_all_methods(QueryKind::VertexFace, static_triangle_with_vertex(Vec3(0.25, 0.25, 0.125), Vec3(0.25, 0.25, 0.125)),
                     false);
  // Resting exactly on the face for the whole step: contact at t = 0.
  expect_all_methods(QueryKind::VertexFace, static_triangle_with_vertex(Vec3(0.25, 0.25, 0), Vec3(0.25, 0.25, 0)),
                     true, 0.0);
}

TEST(DegenerateCases, ContactExactlyAtStartAndEnd) {
  expect_all_methods(QueryKind::VertexFace, static_triangle_with_vertex(Vec3(0.25, 0.25, 0), Vec3(0.25, 0.25, 1)),
                     true, 0.0);
  expect_all_methods(QueryKind::VertexFace, static_triangle_with_vertex(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, 0)),
                     true, 1.0);
  // Missing by one ulp-scale gap at t = 1.
  expect_all_methods(QueryKind::VertexFace,
                     static_triangle_with_vertex(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, 0x1p-40)), false);
}

TEST(DegenerateCases, EdgesCrossing) {
  Query q;
  q.start = {Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0.5, -0.5, 0), Vec3(0.5, 0.5, 0)};
  q.end = {Vec3(0, 0, -1), Vec3(1, 0, -1), Vec3(0.5, -0.5, 0), Vec3(0.5, 0.5, 0)};
  expect_all_methods(QueryKind::EdgeEdge, q, true, 0.5);
  const Result r = run(Method::Vincent, QueryKind::EdgeEdge, q);
  EXPECT_NEAR(r.params[0], 0.5, 1e-9);
  EXPECT_NEAR(r.params[1], 0.5, 1e-9);
}

TEST(DegenerateCases, ParallelEdges) {
  // Parallel edges along x, approaching in z, overlapping in x: they touch at t = 0.5.
  Query q;
  q.start = {Vec3(0, 0, 1), Vec3(2, 0, 1), Vec3(1, 0, 0), Vec3(3, 0, 0)};
  q.end = {Vec3(0, 0, -1), Vec3(2, 0, -1), Vec3(1, 0, 0), Vec3(3, 0, 0)};
  for (Method m : ALL_METHODS) {
    const Result r = run(m, QueryKind::EdgeEdge, q);
    EXPECT_TRUE(r.hit) << method_name(m);
    EXPECT_NEAR(r.toc, 0.5, 1e-6) << method_name(m);
  }
  // The same edges offset in y by 0.5: parallel, never touching.
  for (int i = 2; i < 4; ++i) q.start[i].y() = q.end[i].y() = 0.5;
  expect_all_methods(QueryKind::EdgeEdge, q, false);
}

TEST(DegenerateCases, CollinearEdgesSliding) {
  // Both edges on the x axis for the whole step; one slides into the other at t = 0.5.
  Query q;
  q.start = {Vec3(-3, 0, 0), Vec3(-2, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)};
  q.end = {Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)};
  const Result r = run(Method::Conservative, QueryKind::EdgeEdge, q);
  EXPECT_TRUE(r.hit);
  EXPECT_NEAR(r.toc, 0.5, 1e-6);
}

TEST(DegenerateCases, ScalesFromTinyToHuge) {
  const Query through = static_triangle_with_vertex(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, -1));
  const Query beside = static_triangle_with_vertex(Vec3(0.75, 0.75, 1), Vec3(0.75, 0.75, -1));
  for (Scalar scale : {1e-8, 1e-4, 1.0, 1e4, 1e8}) {
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(3 * scale, -7 * scale, 5 * scale)}) {
      for (Method m : ALL_METHODS) {
        const Result hit = run(m, QueryKind::VertexFace, scaled(through, scale, offset));
        EXPECT_TRUE(hit.hit) << method_name(m) << " scale " << scale;
        EXPECT_NEAR(hit.toc, 0.5, 1e-6) << method_name(m) << " scale " << scale;
        EXPECT_FALSE(run(m, QueryKind::VertexFace, scaled(beside, scale, offset)).hit)
            << method_name(m) << " scale " << scale;
      }
    }
  }
}

TEST(DegenerateCases, ThicknessCountsNearMissesAsContact) {
  // Passing 0.25 beside the triangle's corner (1, 0, 0) in the plane z = 0... at its closest.
  const Query q = static_triangle_with_vertex(Vec3(1.25, 0, 1), Vec3(1.25, 0, -1));
  Options options;
  options.method = Method::Conservative;
  EXPECT_FALSE(elementary_ccd(QueryKind::VertexFace, q, options).hit);
  options.thickness = 0.3;
  const Result r = elementary_ccd(QueryKind::VertexFace, q, options);
  EXPECT_TRUE(r.hit);
  // The distance first drops to 0.3 when the height is sqrt(0.3^2 - 0.25^2) = 0.1658: t = 0.417.
  EXPECT_LE(r.toc, 0.5 - std::sqrt(0.3 * 0.3 - 0.25 * 0.25) / 2 + 1e-6);
  options.thickness = 0.2;
  EXPECT_FALSE(elementary_ccd(QueryKind::VertexFace, q, options).hit);
}
