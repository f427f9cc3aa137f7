// The btDbvt broad phase and the candidate tests generated from triangle pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "drape/ccd/broad_phase.h"
#include "drape/ccd/distance.h"
#include "sorted_pairs.h"

using namespace drape;
using namespace drape::ccd;

namespace {

std::vector<Aabb> random_boxes(std::mt19937_64& rng, int count) {
  std::uniform_real_distribution<Scalar> u(0, 1), size(0.01, 0.1);
  std::vector<Aabb> boxes;
  for (int i = 0; i < count; ++i) {
    const Vec3 lo(u(rng), u(rng), u(rng));
    boxes.push_back({lo, lo + Vec3(size(rng), size(rng), size(rng))});
  }
  return boxes;
}

}  // namespace

TEST(BroadPhase, SelfPairsMatchBruteForceAcrossUpdates) {
  std::mt19937_64 rng(8);
  BoxTree tree;
  for (int round = 0; round < 5; ++round) {
    const auto boxes = random_boxes(rng, 300);  // same count: updated in place after round 0
    tree.update(boxes);
    std::vector<std::pair<std::int32_t, std::int32_t>> expected;
    for (int i = 0; i < 300; ++i)
      for (int j = i + 1; j < 300; ++j)
        if (overlap(boxes[i], boxes[j])) expected.emplace_back(i, j);
    EXPECT_EQ(tree.self_pairs(), expected) << "round " << round;
  }
}

TEST(BroadPhase, PairsBetweenTwoTreesAcrossUpdates) {
  std::mt19937_64 rng(9);
  BoxTree ta, tb;
  for (int round = 0; round < 4; ++round) {
    // Every box moves between rounds: the trees' later updates refit their shapes in place.
    const auto a = random_boxes(rng, 200), b = random_boxes(rng, 150);
    ta.update(a);
    tb.update(b);
    std::vector<std::pair<std::int32_t, std::int32_t>> expected;
    for (int i = 0; i < 200; ++i)
      for (int j = 0; j < 150; ++j)
        if (overlap(a[i], b[j])) expected.emplace_back(i, j);
    EXPECT_EQ(ta.pairs_with(tb), expected) << "round " << round;
  }
}

TEST(BroadPhase, PairsWithBoxesAreThoseOfATreeOfThem) {
  std::mt19937_64 rng(10);
  BoxTree tb;
  for (int round = 0; round < 4; ++round) {
    auto a = random_boxes(rng, 200);
    const auto b = random_boxes(rng, 150);
    // Some boxes touching a leaf's face exactly: overlap counts a shared face, as btDbvt does.
    for (int i = 0; i < 10; ++i) {
      const Aabb& leaf = b[std::size_t(i)];
      a[std::size_t(i)] = {Vec3(leaf.max.x(), leaf.min.y(), leaf.min.z()), Vec3(leaf.max.x() + 0.05, leaf.max.y(), leaf.max.z())};
    }
    tb.update(b);
    std::vector<std::int32_t> which;
    for (std::int32_t i = 0; i < 200; i += 1 + round) which.push_back(i);
    std::vector<std::pair<std::int32_t, std::int32_t>> expected;
    for (const std::int32_t i : which)
      for (int j = 0; j < 150; ++j)
        if (overlap(a[std::size_t(i)], b[std::size_t(j)])) expected.emplace_back(i, j);
    EXPECT_EQ(tb.pairs_with_boxes(a, which), expected) << "round " << round;
    if (round == 0) {  // every box: what a tree of them finds against this one
      BoxTree ta;
      ta.update(a);
      EXPECT_EQ(tb.pairs_with_boxes(a, which), ta.pairs_with(tb));
    }
  }
  EXPECT_TRUE(BoxTree().pairs_with_boxes(random_boxes(rng, 3), std::vector<std::int32_t>{0, 1, 2}).empty());
}

TEST(BroadPhase, SweptBoxCoversBothEndsAndTheMargin) {
  const std::vector<Vec3> start{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const std::vector<Vec3> end{Vec3(0, 0, 2), Vec3(1, 0, 2), Vec3(0, 1, -1)};
  const Aabb box = swept_box({0, 1, 2}, start, end, 0.1);
  EXPECT_TRUE(box.min.isApprox(Vec3(-0.1, -0.1, -1.1)));
  EXPECT_TRUE(box.max.isApprox(Vec3(1.1, 1.1, 2.1)));
}

TEST(FeaturePairs, FifteenTestsPerDisjointPairOnceEach) {
  const std::vector<TriangleIndices> tris{{0, 1, 2}, {3, 4, 5}};
  const std::vector<std::pair<std::int32_t, std::int32_t>> pairs{{0, 1}, {0, 1}};  // twice: counted once
  const Candidates c = feature_pairs(tris, tris, pairs);
  EXPECT_EQ(c.vertex_face.size(), 6u);
  EXPECT_EQ(c.edge_edge.size(), 9u);
}

TEST(FeaturePairs, FeaturesSharingAVertexAreSkippedAndSharedEdgesTestedOnce) {
  // Two triangles sharing edge (1, 2): vertex 0 vs face (1,2,3) and 3 vs (0,1,2) remain; of
  // the 9 edge pairs only those with no common vertex remain: (0,1)-(2,3) and (0,2)-(1,3).
  const std::vector<TriangleIndices> tris{{0, 1, 2}, {1, 3, 2}, {2, 3, 4}};
  const Candidates c = feature_pairs(tris, tris, std::vector<std::pair<std::int32_t, std::int32_t>>{{0, 1}});
  EXPECT_EQ(c.vertex_face.size(), 2u);
  EXPECT_EQ(c.edge_edge.size(), 2u);
  for (const auto& p : c.vertex_face)
    for (auto f : p.face) EXPECT_NE(p.vertex, f);
  // A fan of triangles around vertex 2: the same edge pair from two triangle pairs, once.
  const Candidates fan = feature_pairs(tris, tris, std::vector<std::pair<std::int32_t, std::int32_t>>{{0, 1}, {0, 2}, {1, 2}});
  std::set<std::array<std::int32_t, 4>> unique;
  for (const auto& p : fan.edge_edge) unique.insert({p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]});
  EXPECT_EQ(unique.size(), fan.edge_edge.size());
}

// Feature volumes drop exactly the pairs whose features' volumes are apart, and nothing the
// conservative test would find within twice the margin.
TEST(FeaturePairs, FeatureVolumesDropOnlyPairsThatStayApart) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<Scalar> coordinate(0, 1), step(-0.05, 0.05);
  constexpr int TRIANGLES = 60;
  constexpr Scalar MARGIN = 0.02;
  std::vector<Vec3> start, end;
  std::vector<TriangleIndices> tris;
  for (int t = 0; t < TRIANGLES; ++t) {
    const Vec3 centre(coordinate(rng), coordinate(rng), coordinate(rng));
    for (int k = 0; k < 3; ++k) {
      start.push_back(centre + Vec3(step(rng), step(rng), step(rng)) * 2);
      end.push_back(start.back() + Vec3(step(rng), step(rng), step(rng)));
    }
    tris.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  for (int i = 0; i < TRIANGLES; ++i)
    for (int j = i + 1; j < TRIANGLES; ++j) pairs.emplace_back(i, j);
  const auto volumes = vertex_volumes(start, end, MARGIN);
  const Candidates all = feature_pairs(tris, tris, pairs);
  const Candidates kept = feature_pairs(tris, tris, pairs, volumes);
  // In parallel chunks, the same lists in the same order. The pairs six times over: more than
  // two chunks of them, and the same features found in different chunks.
  std::vector<std::pair<std::int32_t, std::int32_t>> repeated;
  for (int k = 0; k < 6; ++k) repeated.insert(repeated.end(), pairs.begin(), pairs.end());
  ASSERT_GT(repeated.size(), 2u * 4096) << "too few pairs to split into chunks";
  for (const int threads : {1, 2, 3}) {
    const Candidates parallel_all = feature_pairs(tris, tris, repeated, {}, threads);
    const Candidates parallel_kept = feature_pairs(tris, tris, repeated, volumes, threads);
    ASSERT_EQ(parallel_all.vertex_face.size(), all.vertex_face.size());
    ASSERT_EQ(parallel_kept.edge_edge.size(), kept.edge_edge.size());
    for (std::size_t i = 0; i < all.vertex_face.size(); ++i) {
      EXPECT_EQ(parallel_all.vertex_face[i].vertex, all.vertex_face[i].vertex);
      EXPECT_EQ(parallel_all.vertex_face[i].face, all.vertex_face[i].face);
    }
    for (std::size_t i = 0; i < kept.edge_edge.size(); ++i) {
      EXPECT_EQ(parallel_kept.edge_edge[i].edge_a, kept.edge_edge[i].edge_a);
      EXPECT_EQ(parallel_kept.edge_edge[i].edge_b, kept.edge_edge[i].edge_b);
    }
  }
  // Apart, computed here independently: some direction among x, y, z and the six face
  // diagonals separates the two features' start and end points by more than twice the margin.
  const std::vector<Vec3> directions{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1),  Vec3(1, 1, 0), Vec3(1, -1, 0),
                                     Vec3(1, 0, 1), Vec3(1, 0, -1), Vec3(0, 1, 1), Vec3(0, 1, -1)};
  const auto apart_along_an_axis = [&](std::initializer_list<std::int32_t> a, std::initializer_list<std::int32_t> b) {
    for (const Vec3& d : directions) {
      const auto range = [&](std::initializer_list<std::int32_t> vertices) {
        Scalar lo = INFINITY, hi = -INFINITY;
        for (auto v : vertices)
          for (const Vec3& p : {start[v], end[v]}) lo = std::min(lo, p.dot(d)), hi = std::max(hi, p.dot(d));
        return std::pair{lo, hi};
      };
      const auto [lo_a, hi_a] = range(a);
      const auto [lo_b, hi_b] = range(b);
      const Scalar gap = std::max(lo_b - hi_a, lo_a - hi_b) / d.norm();
      if (gap > 2 * MARGIN * (1 + 1e-12)) return true;
    }
    return false;
  };
  Options near;
  near.method = Method::Conservative;
  near.thickness = 1.999 * MARGIN;
  const BatchInput input{start, end, {}, {}};
  std::size_t vf_kept = 0, ee_kept = 0;
  std::set<std::array<std::int32_t, 4>> kept_vf, kept_ee;
  for (const auto& p : kept.vertex_face) kept_vf.insert({p.vertex, p.face[0], p.face[1], p.face[2]});
  for (const auto& p : kept.edge_edge) kept_ee.insert({p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]});
  for (const auto& p : all.vertex_face) {
    const bool apart = apart_along_an_axis({p.vertex}, {p.face[0], p.face[1], p.face[2]});
    EXPECT_EQ(kept_vf.count({p.vertex, p.face[0], p.face[1], p.face[2]}), apart ? 0u : 1u);
    vf_kept += !apart;
    if (apart) {
      EXPECT_FALSE(vertex_face_ccd(gather(input, p), near).hit);
    }
  }
  for (const auto& p : all.edge_edge) {
    const bool apart = apart_along_an_axis({p.edge_a[0], p.edge_a[1]}, {p.edge_b[0], p.edge_b[1]});
    EXPECT_EQ(kept_ee.count({p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]}), apart ? 0u : 1u);
    ee_kept += !apart;
    if (apart) {
      EXPECT_FALSE(edge_edge_ccd(gather(input, p), near).hit);
    }
  }
  EXPECT_EQ(kept.vertex_face.size(), vf_kept);
  EXPECT_EQ(kept.edge_edge.size(), ee_kept);
  EXPECT_GT(vf_kept, 0u);
  EXPECT_LT(vf_kept, all.vertex_face.size());  // the random set has both kinds
  EXPECT_LT(ee_kept, all.edge_edge.size());
}

// Rest gaps (RestGaps): two grids of 3 mm cells with a 5 mm thickness, one crumpled into
// waves and squeezed so that its own features come near, the other laid close over it, all
// moving. Every test the rest gaps drop is one that the volumes alone keep, of two features of
// one grid, whose start distance is at least the gap kept for them (half their rest distance,
// at most the thickness) and which do not touch during the step; tests of the two grids'
// features keep the whole margin; and most of the one grid's neighbours are dropped.
TEST(FeaturePairs, RestGapsDropOnlyTestsThatCannotComeWithinTheirGap) {
  constexpr int N = 14;
  constexpr Scalar CELL = 0.003, THICKNESS = 0.005, FRACTION = 0.5;
  std::mt19937_64 rng(35);
  std::uniform_real_distribution<Scalar> jitter(-0.0004, 0.0004);
  std::vector<Vec3> rest, start, end;
  std::vector<TriangleIndices> tris;
  std::vector<std::int32_t> group;
  for (int sheet = 0; sheet < 2; ++sheet) {
    const int first = int(rest.size());
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        const Vec3 r(i * CELL, j * CELL, 0);
        rest.push_back(r);
        group.push_back(sheet);
        // Sheet 0 squeezed to 70 % along x and waved (folds 6 mm across); sheet 1 flat, 4 mm
        // above the waves' crests.
        const Vec3 p = sheet == 0 ? Vec3(0.7 * r.x(), r.y(), 0.003 * std::sin(r.x() * 900)) : Vec3(r.x() * 0.7, r.y(), 0.007);
        start.push_back(p + Vec3(jitter(rng), jitter(rng), jitter(rng)));
        end.push_back(start.back() + Vec3(jitter(rng), jitter(rng), jitter(rng)));
      }
    for (int j = 0; j + 1 < N; ++j)
      for (int i = 0; i + 1 < N; ++i) {
        const int a = first + j * N + i, b = a + 1, c = a + N, d = c + 1;
        tris.push_back({a, b, d});
        tris.push_back({a, d, c});
      }
  }
  const Scalar margin = 0.5 * THICKNESS;
  const auto volumes = vertex_volumes(start, end, margin);
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  for (std::int32_t i = 0; i < std::int32_t(tris.size()); ++i)
    for (std::int32_t j = i + 1; j < std::int32_t(tris.size()); ++j)
      if (overlap(swept_box(tris[std::size_t(i)], start, end, margin), swept_box(tris[std::size_t(j)], start, end, margin)))
        pairs.emplace_back(i, j);
  const RestGaps gaps{rest, group, FRACTION, THICKNESS, margin};
  const Candidates whole = feature_pairs(tris, tris, pairs, volumes);
  const Candidates rested = feature_pairs(tris, tris, pairs, volumes, 1, {}, &gaps);
  std::set<std::array<std::int32_t, 4>> kept;
  for (const auto& p : rested.vertex_face) kept.insert({p.vertex, p.face[0], p.face[1], p.face[2]});
  for (const auto& p : rested.edge_edge) kept.insert({p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]});
  std::set<std::array<std::int32_t, 4>> all;
  Options touching;
  touching.method = Method::Conservative;
  touching.thickness = 1e-9;
  const BatchInput input{start, end, {}, {}};
  long dropped_one_sheet = 0, one_sheet = 0, across = 0;
  const auto check = [&](const std::array<std::int32_t, 4>& v, bool vertex_face, auto&& query) {
    all.insert(v);
    const bool same = group[std::size_t(v[0])] == group[std::size_t(v[1])] && group[std::size_t(v[0])] == group[std::size_t(v[2])] &&
                      group[std::size_t(v[0])] == group[std::size_t(v[3])];
    one_sheet += same;
    across += !same;
    if (kept.count(v)) return;
    ASSERT_TRUE(same) << "a test across the grids was dropped";
    ++dropped_one_sheet;
    const auto at = [&](const std::vector<Vec3>& x, int k) -> const Vec3& { return x[std::size_t(v[std::size_t(k)])]; };
    const auto distance = [&](const std::vector<Vec3>& x) {
      return vertex_face ? std::sqrt(closest_point_triangle<Scalar>(at(x, 0), at(x, 1), at(x, 2), at(x, 3)).distance_squared)
                         : std::sqrt(closest_segment_segment<Scalar>(at(x, 0), at(x, 1), at(x, 2), at(x, 3)).distance_squared);
    };
    const Scalar gap = std::min(THICKNESS, FRACTION * distance(rest));
    EXPECT_GE(distance(start), gap);
    EXPECT_FALSE(query(touching).hit);
  };
  for (const auto& p : whole.vertex_face)
    check({p.vertex, p.face[0], p.face[1], p.face[2]}, true, [&](const Options& o) { return vertex_face_ccd(gather(input, p), o); });
  for (const auto& p : whole.edge_edge)
    check({p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]}, false,
          [&](const Options& o) { return edge_edge_ccd(gather(input, p), o); });
  for (const auto& v : kept) EXPECT_TRUE(all.count(v)) << "a test the volumes alone drop was kept";
  std::printf("tests: %ld of one grid (%ld dropped by the rest gaps), %ld across\n", one_sheet, dropped_one_sheet, across);
  EXPECT_GT(across, 0);
  EXPECT_GT(dropped_one_sheet, one_sheet / 2);
  EXPECT_LT(dropped_one_sheet, one_sheet);  // the squeezed waves bring some within their gap
}

// On a flat grid at rest the box of a right triangle holds the far corner of its quad; the
// diagonal axes of the volume separate them, so the pair is not tested.
TEST(FeaturePairs, FeatureVolumesSeparateTheFarCornerOfAQuad) {
  const std::vector<Vec3> corners{Vec3(0, 0, 0), Vec3(0.02, 0, 0), Vec3(0, 0.02, 0), Vec3(0.02, 0.02, 0)};
  const std::vector<TriangleIndices> tris{{0, 1, 2}, {1, 3, 2}};
  const std::vector<std::pair<std::int32_t, std::int32_t>> pairs{{0, 1}};
  const Candidates all = feature_pairs(tris, tris, pairs);
  ASSERT_EQ(all.vertex_face.size(), 2u);  // 3 against (0,1,2) and 0 against (1,3,2)
  const auto volumes = vertex_volumes(corners, corners, 0.004);
  EXPECT_TRUE(feature_pairs(tris, tris, pairs, volumes).vertex_face.empty());
  // A box would keep them: vertex 3 lies on the corner of triangle 0's box.
  const Aabb box = swept_box(tris[0], corners, corners, 0.004);
  EXPECT_TRUE((corners[3].array() >= box.min.array()).all() && (corners[3].array() <= box.max.array()).all());
}

TEST(BroadPhase, SortedPairsComeInStdSortsOrder) {
  // The counting sort of the trees' pairs, below and above its threshold, with repeats and
  // first indices spread or bunched: std::sort's order exactly.
  std::mt19937 random(7);
  for (const std::size_t count : {std::size_t(10), ccd::COUNTING_SORT_PAIRS - 1, ccd::COUNTING_SORT_PAIRS, std::size_t(50000)})
    for (const int firsts : {3, 1000, 100000}) {
      std::uniform_int_distribution<std::int32_t> first(0, firsts - 1), second(0, 5000);
      std::vector<std::pair<std::int32_t, std::int32_t>> pairs(count);
      for (auto& p : pairs) p = {first(random), second(random)};
      auto expected = pairs;
      std::sort(expected.begin(), expected.end());
      ccd::sort_pairs(pairs);
      EXPECT_EQ(pairs, expected) << count << " pairs, " << firsts << " first indices";
    }
}
