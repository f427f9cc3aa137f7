// The batch entry point: same results as the elementary calls, and consistent counters.
#include <gtest/gtest.h>

#include "drape/ccd/batch.h"
#include "drape/ccd_eval/query_generator.h"
#include "kernel_targets.h"
#include "methods.h"

using namespace drape;
using namespace drape::ccd;

namespace {

// run_batch on input against the one-query calls: every hit, in order, with the same fields
// bit for bit (the batch computes the same cubics), nothing else, and every counter.
BatchOutput expect_batch_matches_elementary_calls(const BatchInput& input, const Options& options) {
  const BatchOutput out = run_batch(input, options);
  BatchCounters expected;
  const auto compare = [&](const std::vector<BatchHit>& hits, std::size_t count, auto one_query) {
    std::size_t next = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const Result r = one_query(i);
      expected.add(r);
      if (!r.hit) continue;
      ASSERT_LT(next, hits.size()) << "hit " << i << " missing";
      EXPECT_EQ(hits[next].index, i);
      EXPECT_EQ(hits[next].result.toc, r.toc);
      EXPECT_EQ(hits[next].result.params, r.params);
      EXPECT_EQ(hits[next].result.path, r.path);
      EXPECT_EQ(hits[next].result.root_solves, r.root_solves);
      ++next;
    }
    EXPECT_EQ(next, hits.size());
    for (const BatchHit& h : hits) EXPECT_TRUE(h.result.hit);
  };
  const auto& vf = input.vertex_face;
  const auto& ee = input.edge_edge;
  compare(out.vertex_face, vf.size(), [&](std::size_t i) { return vertex_face_ccd(gather(input, vf[i]), options); });
  compare(out.edge_edge, ee.size(), [&](std::size_t i) { return edge_edge_ccd(gather(input, ee[i]), options); });
  EXPECT_EQ(out.counters.tests, vf.size() + ee.size());
  EXPECT_EQ(out.counters.tests, expected.tests);
  EXPECT_EQ(out.counters.culled, expected.culled);
  EXPECT_EQ(out.counters.separated, expected.separated);
  EXPECT_EQ(out.counters.hits, expected.hits);
  EXPECT_EQ(out.counters.root_solves, expected.root_solves);
  EXPECT_EQ(out.counters.degenerate, expected.degenerate);
  return out;
}

std::vector<VertexFacePair> vertex_face_pairs(const ClothLikeSet& set) {
  std::vector<VertexFacePair> vf;
  for (const auto& p : set.vertex_face) vf.push_back({p[0], {p[1], p[2], p[3]}});
  return vf;
}

std::vector<EdgeEdgePair> edge_edge_pairs(const ClothLikeSet& set) {
  std::vector<EdgeEdgePair> ee;
  for (const auto& p : set.edge_edge) ee.push_back({{p[0], p[1]}, {p[2], p[3]}});
  return ee;
}

void check_batch_against_elementary_calls() {
  const ClothLikeSet set = cloth_like_set(8, 42);
  const std::vector<VertexFacePair> vf = vertex_face_pairs(set);
  const std::vector<EdgeEdgePair> ee = edge_edge_pairs(set);
  const BatchInput input{set.start, set.end, vf, ee};
  for (const Scalar thickness : {0.0, 0.01})
  for (Method method : ALL_METHODS) {
    SCOPED_TRACE(std::string(method_name(method)) + " thickness " + std::to_string(thickness));
    Options options;
    options.method = method;
    options.thickness = thickness;
    const BatchOutput out = expect_batch_matches_elementary_calls(input, options);
    if (method == Method::Cubic) {
      EXPECT_EQ(out.counters.culled, 0u);
    }
    if (method == Method::Vincent && thickness == 0) {
      EXPECT_GT(out.counters.culled, out.counters.tests / 2);
    }
    // Two threads split the tests into other chunks: the same results.
    const BatchOutput two = run_batch(input, options, 2);
    ASSERT_EQ(two.vertex_face.size(), out.vertex_face.size());
    ASSERT_EQ(two.edge_edge.size(), out.edge_edge.size());
    for (std::size_t i = 0; i < out.vertex_face.size(); ++i) {
      EXPECT_EQ(two.vertex_face[i].index, out.vertex_face[i].index);
      EXPECT_EQ(two.vertex_face[i].result.toc, out.vertex_face[i].result.toc);
    }
    for (std::size_t i = 0; i < out.edge_edge.size(); ++i) {
      EXPECT_EQ(two.edge_edge[i].index, out.edge_edge[i].index);
      EXPECT_EQ(two.edge_edge[i].result.toc, out.edge_edge[i].result.toc);
    }
    EXPECT_EQ(two.counters.culled, out.counters.culled);
    EXPECT_EQ(two.counters.hits, out.counters.hits);
  }
}

}  // namespace

// Chunks of every length: a batch of n tests for n around the chunk size (64) and the SIMD
// widths (1 to 8), so that partial vectors and partial chunks occur, every method, every kernel
// target, two thicknesses: every counter and every hit as the one-query calls give them.
TEST(Batch, EveryChunkTailMatchesElementaryCalls) {
  const ClothLikeSet set = cloth_like_set(6, 9);
  const std::vector<VertexFacePair> all_vf = vertex_face_pairs(set);
  const std::vector<EdgeEdgePair> all_ee = edge_edge_pairs(set);
  std::size_t offset = 0;
  kernel_testing::on_every_kernel_target([&] {
    for (const std::size_t n : {1, 2, 3, 4, 5, 7, 8, 9, 15, 63, 64, 65, 67, 130, 191}) {
      offset = (offset + 977) % (all_vf.size() - 200);  // a different stretch of tests each time
      const std::vector<VertexFacePair> vf(all_vf.begin() + offset, all_vf.begin() + offset + n);
      const std::vector<EdgeEdgePair> ee(all_ee.begin() + offset, all_ee.begin() + offset + n);
      const BatchInput input{set.start, set.end, vf, ee};
      for (const Scalar thickness : {0.0, 0.01})
        for (Method method : ALL_METHODS) {
          SCOPED_TRACE(std::string(method_name(method)) + " n " + std::to_string(n) + " thickness " +
                       std::to_string(thickness));
          Options options;
          options.method = method;
          options.thickness = thickness;
          expect_batch_matches_elementary_calls(input, options);
        }
    }
  });
}

// Tests far from the origin, around STAGE_COORDINATE_LIMIT: the batch's stage stops at the same
// limit as the one-query calls', on every target.
TEST(Batch, CoordinatesAroundTheStageLimitMatchElementaryCalls) {
  std::vector<Vec3> start, end;
  std::vector<VertexFacePair> vf;
  for (const Scalar offset : {1e99, 1e101, 1e110}) {
    const Scalar size = offset * 1e-8;
    const std::int32_t first = std::int32_t(start.size());
    start.push_back(Vec3(offset, offset, offset));
    start.push_back(Vec3(offset + size, offset, offset));
    start.push_back(Vec3(offset, offset + size, offset));
    end.insert(end.end(), start.end() - 3, start.end());
    for (const Scalar outside : {0.25, 8.0}) {  // a vertex crossing the plane inside and outside the triangle
      vf.push_back({std::int32_t(start.size()), {first, first + 1, first + 2}});
      start.push_back(Vec3(offset + outside * size, offset + outside * size, offset + size));
      end.push_back(Vec3(offset + outside * size, offset + outside * size, offset - size));
    }
  }
  const BatchInput input{start, end, vf, {}};
  kernel_testing::on_every_kernel_target([&] {
    for (Method method : {Method::Vincent, Method::Conservative}) {
      SCOPED_TRACE(method_name(method));
      Options options;
      options.method = method;
      const BatchOutput out = expect_batch_matches_elementary_calls(input, options);
      EXPECT_EQ(out.counters.separated, 1u);  // the vertex outside the triangle within the limit
    }
  });
}

// Every kernel target this machine runs, the portable one-lane code included.
TEST(Batch, MatchesElementaryCallsAndCounts) {
  kernel_testing::on_every_kernel_target([] { check_batch_against_elementary_calls(); });
}

// Features that become coplanar at mid-step a distance d apart along one coordinate axis, so
// that their boxes over the whole step are d apart along it: for every axis, for each feature
// on either side, a vertex-face test and an edge-edge test both ways.
BatchInput coplanar_at_distances(const std::vector<Scalar>& distances, std::vector<Vec3>& start, std::vector<Vec3>& end,
                                 std::vector<VertexFacePair>& vf, std::vector<EdgeEdgePair>& ee) {
  const auto point = [&](Vec3 s, Vec3 e, int axis) {
    // Coordinates rotated so that the offset lies along axis (0: x, 1: y, 2: z).
    const auto rotate = [axis](const Vec3& p) { return Vec3(p[(3 - axis) % 3], p[(4 - axis) % 3], p[(5 - axis) % 3]); };
    start.push_back(rotate(s));
    end.push_back(rotate(e));
    return static_cast<std::int32_t>(start.size() - 1);
  };
  for (int axis = 0; axis < 3; ++axis)
    for (const Scalar side : {-1.0, 1.0})
      for (const Scalar d : distances) {
        // A vertex falling through the plane z = 0 at t = 0.5, d beyond the triangle's edge
        // x = 0 (side -1) or its corner x = 1 (side 1), along x.
        const Scalar x = side < 0 ? -d : 1 + d;
        const std::int32_t v = point({x, 0.0, 0.5}, {x, 0.0, -0.5}, axis);
        const std::int32_t a = point({0, -0.5, 0}, {0, -0.5, 0}, axis), b = point({1, 0, 0}, {1, 0, 0}, axis),
                           c = point({0, 0.5, 0}, {0, 0.5, 0}, axis);
        vf.push_back({v, {a, b, c}});
        // An edge along y falling through z = 0 at t = 0.5, d beyond the end of an edge along x.
        const std::int32_t e0 = point({0, 0, 0}, {0, 0, 0}, axis), e1 = point({1, 0, 0}, {1, 0, 0}, axis);
        const std::int32_t f0 = point({x, -0.5, 0.5}, {x, -0.5, -0.5}, axis),
                           f1 = point({x, 0.5, 0.5}, {x, 0.5, -0.5}, axis);
        ee.push_back({{e0, e1}, {f0, f1}});
        ee.push_back({{f0, f1}, {e0, e1}});
      }
  return BatchInput{start, end, vf, ee};
}

// The batch asks the separation stage's first question itself (four tests at a time, on every
// axis): with a thickness, vincent must keep the contacts within it and separate the rest.
// Fails when any lane's box test reads the gap as zero.
TEST(Batch, WholeStepBoxesKeepContactsWithinTheThickness) {
  constexpr Scalar thickness = 0.01;
  const std::vector<Scalar> ratios{0.1, 0.5, 0.9, 0.99, 1.01, 1.1, 2.0, 5.0};
  std::vector<Scalar> distances;
  for (const Scalar r : ratios) distances.push_back(r * thickness);
  const std::size_t near = 3 * 2 * 4;  // axes, sides, ratios below 1
  std::vector<Vec3> start, end;
  std::vector<VertexFacePair> vf;
  std::vector<EdgeEdgePair> ee;
  const BatchInput input = coplanar_at_distances(distances, start, end, vf, ee);
  Options options;
  options.method = Method::Vincent;
  options.thickness = thickness;
  const BatchOutput out = expect_batch_matches_elementary_calls(input, options);
  // Every pair within the thickness touches; every pair beyond it is separated.
  EXPECT_EQ(out.vertex_face.size(), near);
  EXPECT_EQ(out.edge_edge.size(), 2 * near);
  EXPECT_EQ(out.counters.separated, out.counters.tests - 3 * near);
}

// At zero thickness conservative's gap is the rounding margin alone (64 u times the largest
// coordinate, about 7e-15 here), vincent's the contact tolerance (1e-9 of the extent) besides:
// features closer than that go on to the tree, the roots and the search, farther ones are
// separated, every counter as the one-query calls give it.
TEST(Batch, WholeStepBoxesAtZeroThicknessMatchElementaryCalls) {
  const Scalar margin = 64 * UNIT_ROUNDOFF;
  std::vector<Vec3> start, end;
  std::vector<VertexFacePair> vf;
  std::vector<EdgeEdgePair> ee;
  const BatchInput input = coplanar_at_distances({0.0, 0.1 * margin, 0.5 * margin, 4 * margin, 16 * margin, 1e-10, 1e-6, 1e-3},
                                                 start, end, vf, ee);
  for (const Method method : {Method::Vincent, Method::Conservative}) {
    SCOPED_TRACE(method_name(method));
    Options options;
    options.method = method;
    const BatchOutput out = expect_batch_matches_elementary_calls(input, options);
    EXPECT_GT(out.counters.separated, 0u);
    EXPECT_LT(out.counters.separated, out.counters.tests);
    EXPECT_GT(out.counters.hits, 0u);
  }
}

// The rest of the separation stage (the tree of halvings, each test's run of kept sub-intervals
// through the coordinate boxes and the shape's axes) is asked four tests at a time too, at
// every depth of the tree: the same decisions as the one-query calls, at each depth, where the
// runs, the shapes and the axes that separate differ from test to test.
TEST(Batch, SeparationStageAtEveryDepthMatchesElementaryCalls) {
  const ClothLikeSet set = cloth_like_set(8, 7);
  const std::vector<VertexFacePair> vf = vertex_face_pairs(set);
  const std::vector<EdgeEdgePair> ee = edge_edge_pairs(set);
  const BatchInput input{set.start, set.end, vf, ee};
  for (int depth = 1; depth <= 7; ++depth)
    for (const Method method : {Method::Vincent, Method::Conservative})
      for (const Scalar thickness : {0.0, 0.01}) {
        SCOPED_TRACE(std::string(method_name(method)) + " depth " + std::to_string(depth) + " thickness " +
                     std::to_string(thickness));
        Options options;
        options.method = method;
        options.thickness = thickness;
        options.separation_depth = depth;
        const BatchOutput out = expect_batch_matches_elementary_calls(input, options);
        EXPECT_GT(out.counters.separated, 0u);
      }
}

// Edges that become coplanar at mid-step, the second's line crossing the first outside it, at
// angles where no coordinate box separates them: only the first edge's in-plane normal does,
// or with the edges swapped only the second's. The batch, which asks both axes of every lane,
// must separate them all, as the one-query calls do.
TEST(Batch, EdgeEdgeShapeAxesSeparateEitherWay) {
  std::vector<Vec3> start, end;
  std::vector<EdgeEdgePair> ee;
  const auto point = [&](const Vec3& s, const Vec3& e) {
    start.push_back(s);
    end.push_back(e);
    return static_cast<std::int32_t>(start.size() - 1);
  };
  for (const Scalar angle : {0.3, 0.7, 0.785, 1.1, 1.3}) {
    const Vec3 u(std::cos(angle), std::sin(angle), 0), v(-std::sin(angle), std::cos(angle), 0);
    for (const Scalar gap : {0.05, 0.5}) {
      // The first edge at rest across the origin along u; the second along v from gap to 2,
      // falling through z = 0 at t = 0.4 (inside a sub-interval at every depth).
      const std::int32_t a0 = point(-u, -u), a1 = point(u, u);
      const Vec3 above(0, 0, 0.4), below(0, 0, -0.6);
      const std::int32_t b0 = point(gap * v + above, gap * v + below), b1 = point(2 * v + above, 2 * v + below);
      ee.push_back({{a0, a1}, {b0, b1}});
      ee.push_back({{b0, b1}, {a0, a1}});
    }
  }
  const BatchInput input{start, end, {}, ee};
  for (int depth = 1; depth <= 6; ++depth) {
    SCOPED_TRACE("depth " + std::to_string(depth));
    Options options;
    options.method = Method::Vincent;
    options.separation_depth = depth;
    const BatchOutput out = expect_batch_matches_elementary_calls(input, options);
    EXPECT_EQ(out.counters.separated, ee.size());
  }
}
