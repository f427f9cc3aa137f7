// The batch entry point: same results as the elementary calls, and consistent counters.
#include <gtest/gtest.h>

#include "drape/ccd/batch.h"
#include "drape/ccd/query_generator.h"

using namespace drape;
using namespace drape::ccd;

TEST(Batch, MatchesElementaryCallsAndCounts) {
  const ClothLikeSet set = cloth_like_set(8, 42);
  std::vector<VertexFacePair> vf;
  std::vector<EdgeEdgePair> ee;
  for (const auto& p : set.vertex_face) vf.push_back({p[0], {p[1], p[2], p[3]}});
  for (const auto& p : set.edge_edge) ee.push_back({{p[0], p[1]}, {p[2], p[3]}});
  const BatchInput input{set.start, set.end, vf, ee};
  for (const Scalar thickness : {0.0, 0.01})
  for (Method method : ALL_METHODS) {
    SCOPED_TRACE(std::string(method_name(method)) + " thickness " + std::to_string(thickness));
    Options options;
    options.method = method;
    options.thickness = thickness;
    const BatchOutput out = run_batch(input, options);
    ASSERT_EQ(out.vertex_face.size(), vf.size());
    ASSERT_EQ(out.edge_edge.size(), ee.size());
    BatchCounters expected;
    for (std::size_t i = 0; i < vf.size(); ++i) {
      const Result r = vertex_face_ccd(gather(input, vf[i]), options);
      EXPECT_EQ(r.hit, out.vertex_face[i].hit);
      EXPECT_EQ(r.toc, out.vertex_face[i].toc);  // bit for bit: the batch computes the same cubics
      EXPECT_EQ(r.params, out.vertex_face[i].params);
      EXPECT_EQ(r.path, out.vertex_face[i].path);
      EXPECT_EQ(r.root_solves, out.vertex_face[i].root_solves);
      expected.add(r);
    }
    for (std::size_t i = 0; i < ee.size(); ++i) {
      const Result r = edge_edge_ccd(gather(input, ee[i]), options);
      EXPECT_EQ(r.hit, out.edge_edge[i].hit);
      EXPECT_EQ(r.toc, out.edge_edge[i].toc);
      EXPECT_EQ(r.params, out.edge_edge[i].params);
      EXPECT_EQ(r.path, out.edge_edge[i].path);
      EXPECT_EQ(r.root_solves, out.edge_edge[i].root_solves);
      expected.add(r);
    }
    EXPECT_EQ(out.counters.tests, vf.size() + ee.size());
    EXPECT_EQ(out.counters.tests, expected.tests);
    EXPECT_EQ(out.counters.culled, expected.culled);
    EXPECT_EQ(out.counters.hits, expected.hits);
    EXPECT_EQ(out.counters.root_solves, expected.root_solves);
    EXPECT_EQ(out.counters.degenerate, expected.degenerate);
    if (method == Method::Cubic) {
      EXPECT_EQ(out.counters.culled, 0u);
    }
    if (method == Method::Vincent && thickness == 0) {
      EXPECT_GT(out.counters.culled, out.counters.tests / 2);
    }
    // Two threads split the tests into other chunks: the same results.
    const BatchOutput two = run_batch(input, options, 2);
    for (std::size_t i = 0; i < vf.size(); ++i) EXPECT_EQ(two.vertex_face[i].toc, out.vertex_face[i].toc);
    for (std::size_t i = 0; i < ee.size(); ++i) EXPECT_EQ(two.edge_edge[i].toc, out.edge_edge[i].toc);
    EXPECT_EQ(two.counters.culled, out.counters.culled);
  }
}
