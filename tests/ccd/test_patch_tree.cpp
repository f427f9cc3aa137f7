// Self-collision culling (ccd::PatchTree): a sheet proven free of self-contact gives no pairs,
// and no culled pair ever held a contact that the whole broad phase's pairs find.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <tuple>

#include "drape/ccd/patch_tree.h"

using namespace drape;
using namespace drape::ccd;

namespace {

using Pairs = std::vector<std::pair<std::int32_t, std::int32_t>>;

struct Sheet {
  std::vector<Vec3> start, end;
  std::vector<TriangleIndices> triangles;
};

// An nx x ny grid of quads on [0, nx] x [0, ny] (unit spacing), two triangles a quad wound
// counter-clockwise about +z; place maps (u, v) to the start and the end positions.
template <typename Place>
Sheet grid(int nx, int ny, const Place& place) {
  Sheet s;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const auto [a, b] = place(Scalar(i), Scalar(j));
      s.start.push_back(a);
      s.end.push_back(b);
    }
  const auto at = [&](int i, int j) { return std::int32_t(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      s.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      s.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return s;
}

// A grid on waves of 2 (frequencies along u and v), every corner moved at random (deviation
// wobble) and then moving at random (deviation move) during the step.
Sheet crumpled(int seed, int nx, int ny, Scalar wobble_deviation, Scalar move_deviation, std::array<Scalar, 2> waves) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  std::normal_distribution<Scalar> wobble(0, wobble_deviation), move(0, move_deviation);
  return grid(nx, ny, [&](Scalar u, Scalar v) {
    const Vec3 p(u + wobble(rng), v + wobble(rng), 2 * std::sin(u * waves[0]) * std::cos(v * waves[1]) + wobble(rng));
    return std::pair{p, Vec3(p + Vec3(move(rng), move(rng), move(rng)))};
  });
}

// The contacts (as feature keys) the narrow phase finds among tests.
std::set<std::array<std::int32_t, 5>> contacts(const Sheet& s, const Candidates& c) {
  const BatchOutput out = run_batch({s.start, s.end, c.vertex_face, c.edge_edge}, Options{});
  std::set<std::array<std::int32_t, 5>> found;
  for (const BatchHit& h : out.vertex_face) {
    const VertexFacePair& p = c.vertex_face[h.index];
    found.insert({0, p.vertex, p.face[0], p.face[1], p.face[2]});
  }
  for (const BatchHit& h : out.edge_edge) {
    const EdgeEdgePair& p = c.edge_edge[h.index];
    found.insert({1, p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]});
  }
  return found;
}

// ... among the features of triangle pairs.
std::set<std::array<std::int32_t, 5>> contacts(const Sheet& s, const Pairs& pairs) {
  return contacts(s, feature_pairs(s.triangles, s.triangles, pairs));
}

// Every triangle pair whose swept boxes overlap, from the btDbvt.
Pairs all_pairs(const Sheet& s, Scalar margin) {
  std::vector<Aabb> boxes;
  for (const auto& t : s.triangles) boxes.push_back(swept_box(t, s.start, s.end, margin));
  BoxTree tree;
  tree.update(boxes);
  return tree.self_pairs();
}

struct Outcome {
  Pairs pairs;
  SelfCullCounters counters;
};

Outcome culled_pairs(const Sheet& s, Scalar margin, int threads = 1) {
  PatchTree tree(s.triangles, s.start);
  Outcome o;
  o.pairs = tree.self_pairs(s.start, s.end, margin, threads, &o.counters);
  return o;
}

// The culled pairs are among the btDbvt's, and every contact found from the btDbvt's pairs
// is found from the culled ones. Returns the number of contacts.
std::size_t expect_no_contact_lost(const Sheet& s, Scalar margin) {
  const Pairs everything = all_pairs(s, margin);
  const Outcome culled = culled_pairs(s, margin);
  EXPECT_TRUE(std::includes(everything.begin(), everything.end(), culled.pairs.begin(), culled.pairs.end()));
  const auto expected = contacts(s, everything), found = contacts(s, culled.pairs);
  std::size_t lost = 0;
  for (const auto& key : expected) lost += found.count(key) == 0;
  EXPECT_EQ(lost, 0u) << "of " << expected.size() << " contacts; " << culled.counters.triangles_culled
                      << " triangles culled";
  return expected.size();
}

}  // namespace

TEST(PatchTree, AFallingFlatSheetGivesNoPairs) {
  // 40 x 40 quads falling and sheared in its plane: nothing to test, not even neighbours.
  const Sheet s = grid(40, 40, [](Scalar u, Scalar v) {
    return std::pair{Vec3(u, v, 5), Vec3(u + 0.1 * v, v, 4.2)};
  });
  const Outcome o = culled_pairs(s, 0.05);
  EXPECT_TRUE(o.pairs.empty());
  EXPECT_EQ(o.counters.triangles_culled, long(s.triangles.size()));
  EXPECT_GT(all_pairs(s, 0.05).size(), 5 * s.triangles.size());  // what the btDbvt alone enumerates
}

TEST(PatchTree, AGentlyCurvedSheetGivesNoPairs) {
  // Bent over a cylinder through 120 degrees (normals within 60 degrees of the axis), and
  // rolling a little further during the step.
  const auto bend = [](Scalar u, Scalar v, Scalar angle) {
    const Scalar phi = (u / 30 - 0.5) * angle;
    return Vec3(10 * std::sin(phi), v, 10 * std::cos(phi));
  };
  const Sheet s = grid(30, 20, [&](Scalar u, Scalar v) {
    return std::pair{bend(u, v, 2.0), bend(u, v, 2.1)};
  });
  const Outcome o = culled_pairs(s, 0.05);
  EXPECT_TRUE(o.pairs.empty());
}

TEST(PatchTree, AFoldClosingThroughItselfKeepsEveryContact) {
  // A strip folded back over itself with a gap of 0.5, its upper layer pushed through the lower.
  const Scalar length = 12, gap = 0.5;
  const auto fold = [&](Scalar u, Scalar v, Scalar drop) {
    if (u <= length) return Vec3(u, v, 0);
    const Scalar s = u - length, arc = std::numbers::pi * gap / 2;
    if (s <= arc) {
      const Scalar phi = s / (gap / 2);
      return Vec3(length + gap / 2 * std::sin(phi), v, gap / 2 * (1 - std::cos(phi)) - drop * s / arc);
    }
    return Vec3(length - (s - arc), v, gap - drop);
  };
  const Sheet s = grid(20, 6, [&](Scalar u, Scalar v) {
    // 20 quads along: 12 flat, the rest around the fold and back.
    const Scalar along = u < 12 ? u : 12 + (u - 12) * 0.9;
    return std::pair{fold(along, v * 0.7, 0), fold(along, v * 0.7, 2 * gap)};
  });
  EXPECT_GT(expect_no_contact_lost(s, 0.01), 10u);
}

TEST(PatchTree, ASheetThatCoversItselfTwiceIsNeverCulled) {
  // A fan around a centre vertex whose rim goes round twice, as a ramp up and down (the two
  // sheets cross along two rays): every normal points up and every rim edge turns
  // counter-clockwise about the centre, so only the rim's winding number (2) shows it is not
  // one sheet. During the step the ramp flips, and the two sheets pass through each other.
  Sheet s;
  const int rim = 48;
  s.start.push_back(Vec3::Zero());
  s.end.push_back(Vec3::Zero());
  for (int k = 0; k < rim; ++k) {
    const Scalar phi = 4 * std::numbers::pi * k / rim;
    const Scalar radius = 1 + 0.07 * (k % 5);  // no two rim corners above one another
    const Vec3 p(radius * std::cos(phi), radius * std::sin(phi), 0);
    s.start.push_back(p + Vec3(0, 0, 0.2 * std::sin(phi / 2)));
    s.end.push_back(p - Vec3(0, 0, 0.2 * std::sin(phi / 2)));
  }
  for (int k = 0; k < rim; ++k) s.triangles.push_back({0, 1 + k, 1 + (k + 1) % rim});
  EXPECT_FALSE(culled_pairs(s, 0.01).pairs.empty());  // each turn alone is one sheet; the whole is not
  EXPECT_GT(expect_no_contact_lost(s, 0.01), 0u);
}

TEST(PatchTree, AStripCurledThroughItselfIsNeverCulled) {
  // A straight strip ending in a curl of 1.15 turns, the curl a gentle ramp turned downwards
  // during the step, so its turns pass through each other. Every normal stays near the
  // vertical and the rim winds once around its centre (in the straight part); the curl's
  // rim turns the other way round that centre (a negative signed area), which is what keeps it.
  const Scalar straight = 6, curl = 2 * std::numbers::pi * 1.15, pitch = 0.4, width = 0.4;
  const Sheet s = grid(60, 3, [&](Scalar u, Scalar v) {
    const Scalar along = u / 60 * (straight + curl), across = (v / 3 - 0.5) * width;
    const Scalar theta = std::max(Scalar(0), along - straight);  // the curl's radius is 1
    const Vec3 centre = along < straight ? Vec3(along - straight, 0, 0) : Vec3(std::sin(theta), 1 - std::cos(theta), 0);
    const Vec3 left(-std::sin(theta), std::cos(theta), 0);
    const Vec3 p = centre + across * left, rise(0, 0, pitch * theta / (2 * std::numbers::pi));
    return std::pair{Vec3(p + rise), Vec3(p - rise)};
  });
  EXPECT_FALSE(culled_pairs(s, 0.01).pairs.empty());
  EXPECT_GT(expect_no_contact_lost(s, 0.01), 10u);
}

TEST(PatchTree, ACrumpledSheetKeepsEveryContact) {
  // Random heights and random motions, many times the spacing: a sheet through itself
  // everywhere, at three seeds.
  for (int seed = 1; seed <= 3; ++seed) {
    const Sheet s = crumpled(seed, 14, 14, 0.7, 0.6, {0.9, 0.7});
    EXPECT_GT(expect_no_contact_lost(s, 0.02), 10u) << "seed " << seed;
  }
}

TEST(PatchTree, AWavySheetCulledInPartsKeepsEveryContact) {
  // Gentle waves (culled in patches) with one corner folded over along the crease u + v = 8
  // and pushed down through the sheet beneath it.
  const auto wave = [](Scalar u, Scalar v) { return 0.3 * std::sin(u / 3) * std::sin(v / 4); };
  const Sheet s = grid(24, 24, [&](Scalar u, Scalar v) {
    const Scalar beyond = 8 - u - v;  // > 0: the corner
    if (beyond <= 0) return std::pair{Vec3(u, v, wave(u, v)), Vec3(u, v, wave(u, v) - 0.05)};
    const Scalar rise = std::min(Scalar(1), beyond);
    const Vec3 folded(8 - v, 8 - u, wave(u, v) + 0.8 * rise);
    return std::pair{folded, Vec3(folded - Vec3(0, 0, 2 * rise))};
  });
  EXPECT_GT(expect_no_contact_lost(s, 0.02), 10u);
  const Outcome o = culled_pairs(s, 0.02);
  EXPECT_GT(o.counters.triangles_culled, long(s.triangles.size()) / 2);  // the waves away from the corner
}

TEST(PatchTree, TheSamePairsForAnyThreadCount) {
  std::mt19937_64 rng(7);
  std::normal_distribution<Scalar> wobble(0, 0.4);
  const Sheet s = grid(90, 90, [&](Scalar u, Scalar v) {
    const Vec3 p(u, v, 6 * std::sin(u / 7) * std::cos(v / 5) + wobble(rng));
    return std::pair{p, Vec3(p + Vec3(0, 0, wobble(rng)))};
  });
  const Outcome one = culled_pairs(s, 0.1, 1), two = culled_pairs(s, 0.1, 2), four = culled_pairs(s, 0.1, 4);
  ASSERT_FALSE(one.pairs.empty());
  for (const Outcome* other : {&two, &four}) {
    EXPECT_EQ(one.pairs, other->pairs);
    EXPECT_EQ(one.counters.triangles_culled, other->counters.triangles_culled);
    EXPECT_EQ(one.counters.patches_culled, other->counters.patches_culled);
    EXPECT_EQ(one.counters.patches_tested, other->counters.patches_tested);
  }
}

TEST(PatchTree, OnlyConsistentlyWoundDisksAreCulled) {
  // A flat ring (not a disk) and a flat sheet with one triangle wound the other way: flat, so
  // they cannot meet themselves, but neither whole is proven so by the test.
  Sheet ring;
  const int around = 32;
  for (int k = 0; k < around; ++k) {
    const Scalar phi = 2 * std::numbers::pi * k / around;
    for (Scalar r : {1.0, 1.3}) {
      ring.start.push_back(Vec3(r * std::cos(phi), r * std::sin(phi), 0));
      ring.end.push_back(ring.start.back() + Vec3(0, 0, -0.1));
    }
  }
  for (int k = 0; k < around; ++k) {
    const std::int32_t a = 2 * k, b = 2 * k + 1, c = 2 * ((k + 1) % around), d = c + 1;
    ring.triangles.push_back({a, c, d});
    ring.triangles.push_back({a, d, b});
  }
  const Outcome o = culled_pairs(ring, 0.01);
  EXPECT_FALSE(o.pairs.empty());
  EXPECT_EQ(contacts(ring, o.pairs).size(), 0u);

  Sheet flipped = grid(6, 6, [](Scalar u, Scalar v) { return std::pair{Vec3(u, v, 0), Vec3(u, v, -0.5)}; });
  std::swap(flipped.triangles[20][1], flipped.triangles[20][2]);
  EXPECT_FALSE(culled_pairs(flipped, 0.01).pairs.empty());
}


TEST(PatchTree, TwoSheetsThroughEachOtherKeepEveryContact) {
  // Two flat sheets, one mesh: each is one culled patch, and the upper one falls through the
  // lower (tilted, so that no corner lands on an edge).
  Sheet s = grid(10, 10, [](Scalar u, Scalar v) { return std::pair{Vec3(u, v, 0), Vec3(u, v, 0)}; });
  const Sheet upper = grid(6, 6, [](Scalar u, Scalar v) {
    const Vec3 p(2.3 + u + 0.1 * v, 2.1 + v, 1 + 0.05 * u);
    return std::pair{p, Vec3(p - Vec3(0, 0, 2))};
  });
  const auto offset = std::int32_t(s.start.size());
  s.start.insert(s.start.end(), upper.start.begin(), upper.start.end());
  s.end.insert(s.end.end(), upper.end.begin(), upper.end.end());
  for (TriangleIndices t : upper.triangles) s.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const Outcome o = culled_pairs(s, 0.01);
  EXPECT_EQ(o.counters.triangles_culled, long(s.triangles.size()));  // each sheet whole
  EXPECT_GT(expect_no_contact_lost(s, 0.01), 10u);
}

TEST(PatchTree, BrokenMeshesAreNeverCulledWhereTheyAreBroken) {
  // A flat sheet falling, made non-manifold four ways; the broken part's patches fail, the
  // rest may be culled, and nothing is lost (checked against the btDbvt on a sheet that also
  // folds a corner through itself).
  const auto sheet = [] {
    return grid(8, 8, [](Scalar u, Scalar v) {
      const Scalar beyond = 3 - u - v;  // the corner, folded over along u + v = 3 and pushed through
      if (beyond <= 0) return std::pair{Vec3(u, v, 0), Vec3(u, v, -0.1)};
      const Vec3 folded(3 - v, 3 - u, 0.5 * std::min(Scalar(1), beyond));
      return std::pair{folded, Vec3(folded - Vec3(0, 0, 1.2 * std::min(Scalar(1), beyond)))};
    });
  };
  Sheet duplicated = sheet();
  duplicated.triangles.push_back(duplicated.triangles[70]);  // one triangle twice
  Sheet degenerate = sheet();
  degenerate.triangles.push_back({40, 40, 41});  // a triangle with a repeated corner
  Sheet fin = sheet();
  fin.start.push_back(Vec3(4.5, 4.5, 1));
  fin.end.push_back(Vec3(4.5, 4.5, 0.9));
  fin.triangles.push_back({40, 41, std::int32_t(fin.start.size() - 1)});  // a third triangle on an edge
  Sheet pinched = sheet();
  // Two sheets sharing one corner (a pinched vertex): the second a small flap off vertex 80.
  pinched.start.push_back(Vec3(8.5, 8.5, 0.3));
  pinched.end.push_back(Vec3(8.5, 8.5, 0.2));
  pinched.start.push_back(Vec3(9, 8.2, 0.3));
  pinched.end.push_back(Vec3(9, 8.2, 0.2));
  pinched.triangles.push_back({80, std::int32_t(pinched.start.size() - 2), std::int32_t(pinched.start.size() - 1)});
  for (const Sheet* s : {&duplicated, &degenerate, &fin, &pinched}) {
    const Outcome o = culled_pairs(*s, 0.01);
    EXPECT_LT(o.counters.triangles_culled, long(s->triangles.size()));
    EXPECT_GT(expect_no_contact_lost(*s, 0.01), 0u);
  }
}

TEST(PatchTree, MovedVerticesRestrictThePairsToTheirs) {
  // With a flag per vertex, exactly the pairs with a triangle holding a flagged vertex, and
  // feature_pairs keeps exactly the tests with a flagged vertex.
  std::mt19937_64 rng(3);
  std::normal_distribution<Scalar> wobble(0, 0.6);
  const Sheet s = grid(16, 16, [&](Scalar u, Scalar v) {
    const Vec3 p(u + wobble(rng), v + wobble(rng), 2 * std::sin(u * 0.7) + wobble(rng));
    return std::pair{p, Vec3(p + Vec3(wobble(rng), wobble(rng), wobble(rng)))};
  });
  std::vector<std::uint8_t> moved(s.start.size(), 0);
  for (std::size_t v = 0; v < moved.size(); v += 7) moved[v] = 1;
  PatchTree tree(s.triangles, s.start);
  const Pairs all = tree.self_pairs(s.start, s.end, 0.02), some = tree.self_pairs(s.start, s.end, 0.02, 1, nullptr, moved);
  Pairs expected;
  const auto flagged = [&](std::int32_t t) {
    return moved[std::size_t(s.triangles[std::size_t(t)][0])] || moved[std::size_t(s.triangles[std::size_t(t)][1])] ||
           moved[std::size_t(s.triangles[std::size_t(t)][2])];
  };
  for (const auto& p : all)
    if (flagged(p.first) || flagged(p.second)) expected.push_back(p);
  ASSERT_GT(expected.size(), 50u);
  EXPECT_LT(expected.size(), all.size());
  EXPECT_EQ(some, expected);
  const Candidates every = feature_pairs(s.triangles, s.triangles, all);
  const Candidates kept = feature_pairs(s.triangles, s.triangles, all, {}, 1, moved);
  std::size_t vf = 0, ee = 0;
  for (const auto& p : every.vertex_face) vf += moved[std::size_t(p.vertex)] || moved[std::size_t(p.face[0])] ||
                                                moved[std::size_t(p.face[1])] || moved[std::size_t(p.face[2])];
  for (const auto& p : every.edge_edge) ee += moved[std::size_t(p.edge_a[0])] || moved[std::size_t(p.edge_a[1])] ||
                                              moved[std::size_t(p.edge_b[0])] || moved[std::size_t(p.edge_b[1])];
  EXPECT_EQ(kept.vertex_face.size(), vf);
  EXPECT_EQ(kept.edge_edge.size(), ee);
}

TEST(PatchTree, OwnedFeaturesAreTheSameTestsOnceEach) {
  // feature_pairs with each vertex and edge answered for by one triangle: from every
  // overlapping pair, exactly the tests of the sorting path, each once; from the patch tree's
  // pairs, a subset that keeps every contact.
  for (int seed = 1; seed <= 3; ++seed) {
    const Sheet s = crumpled(seed, 14, 12, 0.5, 0.4, {0.8, 0.6});
    const FeatureOwners owners = feature_owners(s.triangles);
    const auto volumes = vertex_volumes(s.start, s.end, 0.02);
    const Pairs everything = all_pairs(s, 0.02);
    const Candidates sorted = feature_pairs(s.triangles, s.triangles, everything, volumes);
    for (int threads : {1, 2}) {
      Candidates once = feature_pairs(s.triangles, s.triangles, everything, owners, owners, volumes, threads);
      const std::size_t vf = once.vertex_face.size(), ee = once.edge_edge.size();
      std::sort(once.vertex_face.begin(), once.vertex_face.end(), [](const auto& a, const auto& b) {
        return std::tie(a.vertex, a.face) < std::tie(b.vertex, b.face);
      });
      std::sort(once.edge_edge.begin(), once.edge_edge.end(), [](const auto& a, const auto& b) {
        return std::tie(a.edge_a, a.edge_b) < std::tie(b.edge_a, b.edge_b);
      });
      ASSERT_EQ(vf, sorted.vertex_face.size()) << "seed " << seed;  // no test twice, none missing
      ASSERT_EQ(ee, sorted.edge_edge.size()) << "seed " << seed;
      for (std::size_t i = 0; i < vf; ++i)
        EXPECT_TRUE(once.vertex_face[i].vertex == sorted.vertex_face[i].vertex && once.vertex_face[i].face == sorted.vertex_face[i].face);
      for (std::size_t i = 0; i < ee; ++i)
        EXPECT_TRUE(once.edge_edge[i].edge_a == sorted.edge_edge[i].edge_a && once.edge_edge[i].edge_b == sorted.edge_edge[i].edge_b);
    }
    // From the patch tree's pairs: every contact of the sorting path's tests on all pairs.
    const Pairs culled = culled_pairs(s, 0.02).pairs;
    const Candidates owned = feature_pairs(s.triangles, s.triangles, culled, owners, owners, volumes);
    const auto expected = contacts(s, sorted);
    EXPECT_GT(expected.size(), 10u);
    EXPECT_EQ(contacts(s, owned), expected) << "seed " << seed;
  }
}

TEST(PatchTree, OwnedFeaturesAcrossTwoMeshesWithDuplicatedFaces) {
  // A cloth against a second mesh (its indices offset into one vertex array) that holds some
  // faces twice: the owned path makes exactly the sorting path's tests, each once, at 1 and 2
  // threads (enough pairs for parallel chunks), and only moved tests when asked.
  std::mt19937_64 rng(11);
  std::normal_distribution<Scalar> wobble(0, 0.3);
  Sheet s = grid(40, 40, [&](Scalar u, Scalar v) {
    const Vec3 p(u * 0.5, v * 0.5, 0.3 * std::sin(u * 0.4) + wobble(rng));
    return std::pair{p, Vec3(p + Vec3(0, 0, wobble(rng)))};
  });
  const Sheet other = grid(30, 30, [&](Scalar u, Scalar v) {
    const Vec3 p(u * 0.66 + 0.1, v * 0.66 + 0.2, 0.2 + wobble(rng));
    return std::pair{p, Vec3(p - Vec3(0, 0, 0.3))};
  });
  const auto offset = std::int32_t(s.start.size());
  s.start.insert(s.start.end(), other.start.begin(), other.start.end());
  s.end.insert(s.end.end(), other.end.begin(), other.end.end());
  std::vector<TriangleIndices> cloth = s.triangles, mesh;
  for (TriangleIndices t : other.triangles) mesh.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  for (std::size_t t = 0, n = mesh.size(); t < n; t += 7) mesh.push_back(mesh[t]);  // duplicated faces
  std::vector<Aabb> cloth_boxes, mesh_boxes;
  for (const auto& t : cloth) cloth_boxes.push_back(swept_box(t, s.start, s.end, 0.05));
  for (const auto& t : mesh) mesh_boxes.push_back(swept_box(t, s.start, s.end, 0.05));
  BoxTree a, b;
  a.update(cloth_boxes);
  b.update(mesh_boxes);
  const Pairs pairs = a.pairs_with(b);
  ASSERT_GT(pairs.size(), 8192u);  // parallel chunks at 2 threads
  const auto volumes = vertex_volumes(s.start, s.end, 0.05);
  const FeatureOwners cloth_owners = feature_owners(cloth), mesh_owners = feature_owners(mesh);
  std::vector<std::uint8_t> moved(s.start.size(), 0);
  for (std::size_t v = 0; v < moved.size(); v += 5) moved[v] = 1;
  for (const bool restricted : {false, true}) {
    const std::span<const std::uint8_t> flags = restricted ? std::span<const std::uint8_t>(moved) : std::span<const std::uint8_t>{};
    const Candidates sorted = feature_pairs(cloth, mesh, pairs, volumes, 1, flags);
    ASSERT_GT(sorted.vertex_face.size(), 100u);
    ASSERT_GT(sorted.edge_edge.size(), 100u);
    for (int threads : {1, 2}) {
      Candidates once = feature_pairs(cloth, mesh, pairs, cloth_owners, mesh_owners, volumes, threads, flags);
      std::sort(once.vertex_face.begin(), once.vertex_face.end(), [](const auto& x, const auto& y) {
        return std::tie(x.vertex, x.face) < std::tie(y.vertex, y.face);
      });
      std::sort(once.edge_edge.begin(), once.edge_edge.end(), [](const auto& x, const auto& y) {
        return std::tie(x.edge_a, x.edge_b) < std::tie(y.edge_a, y.edge_b);
      });
      ASSERT_EQ(once.vertex_face.size(), sorted.vertex_face.size()) << threads << " threads, restricted " << restricted;
      ASSERT_EQ(once.edge_edge.size(), sorted.edge_edge.size()) << threads << " threads, restricted " << restricted;
      for (std::size_t i = 0; i < once.vertex_face.size(); ++i)
        ASSERT_TRUE(once.vertex_face[i].vertex == sorted.vertex_face[i].vertex && once.vertex_face[i].face == sorted.vertex_face[i].face);
      for (std::size_t i = 0; i < once.edge_edge.size(); ++i)
        ASSERT_TRUE(once.edge_edge[i].edge_a == sorted.edge_edge[i].edge_a && once.edge_edge[i].edge_b == sorted.edge_edge[i].edge_b);
    }
  }
}

namespace {

// Tests as sortable keys: (vertex, face) and (edge, edge).
std::vector<std::array<std::int32_t, 5>> keys(const Candidates& c) {
  std::vector<std::array<std::int32_t, 5>> out;
  for (const auto& t : c.vertex_face) out.push_back({0, t.vertex, t.face[0], t.face[1], t.face[2]});
  for (const auto& t : c.edge_edge) out.push_back({1, t.edge_a[0], t.edge_a[1], t.edge_b[0], t.edge_b[1]});
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(PatchTree, OrphanSetsGiveTheTestsOfAdjacentPairsWithoutListingThem) {
  // With orphans, no listed pair shares a vertex, and the listed pairs' owned tests plus the
  // orphans kept by their volumes are exactly the owned tests of the pairs listed without
  // orphans: on crumpled sheets, on a large wavy one culled in parts (parallel tasks at 2
  // threads), with and without moved vertices.
  std::mt19937_64 rng(5);
  std::normal_distribution<Scalar> wobble(0, 1);
  // 48 x 48, gently waved but crumpled where u < 12.
  std::vector<Sheet> sheets{crumpled(1, 14, 12, 0.5, 0.4, {0.8, 0.6}), crumpled(2, 14, 12, 0.5, 0.4, {0.8, 0.6}),
                            grid(48, 48, [&](Scalar u, Scalar v) {
                              const Scalar w = u < 12 ? 0.5 : 0.01;
                              const Vec3 p(u + w * wobble(rng), v + w * wobble(rng), std::sin(u * 0.3) + w * wobble(rng));
                              return std::pair{p, Vec3(p + w * Vec3(wobble(rng), wobble(rng), wobble(rng)))};
                            })};
  for (std::size_t k = 0; k < sheets.size(); ++k) {
    const Sheet& s = sheets[k];
    const FeatureOwners owners = feature_owners(s.triangles);
    const auto volumes = vertex_volumes(s.start, s.end, 0.02);
    std::vector<std::uint8_t> moved(s.start.size(), 0);
    for (std::size_t v = 0; v < moved.size(); v += 5) moved[v] = 1;
    PatchTree tree(s.triangles, s.start);
    for (const bool restricted : {false, true})
      for (int threads : {1, 2}) {
        const std::span<const std::uint8_t> flags = restricted ? std::span<const std::uint8_t>(moved) : std::span<const std::uint8_t>{};
        SelfCullCounters counters;
        const Pairs listed = tree.self_pairs(s.start, s.end, 0.02, threads, &counters, flags);
        const auto expected = keys(feature_pairs(s.triangles, s.triangles, listed, owners, owners, volumes, 1, flags));
        Candidates orphans;
        const Pairs fewer = tree.self_pairs(s.start, s.end, 0.02, threads, nullptr, flags, &orphans);
        std::size_t adjacent = 0;
        for (const auto& [i, j] : fewer)
          for (std::int32_t v : s.triangles[std::size_t(i)]) adjacent += v == s.triangles[std::size_t(j)][0] ||
                                                                          v == s.triangles[std::size_t(j)][1] ||
                                                                          v == s.triangles[std::size_t(j)][2];
        EXPECT_EQ(adjacent, 0u) << "sheet " << k;
        EXPECT_LT(fewer.size(), listed.size()) << "sheet " << k;
        keep_overlapping(orphans, volumes);
        Candidates all = feature_pairs(s.triangles, s.triangles, fewer, owners, owners, volumes, 1, flags);
        all.vertex_face.insert(all.vertex_face.end(), orphans.vertex_face.begin(), orphans.vertex_face.end());
        all.edge_edge.insert(all.edge_edge.end(), orphans.edge_edge.begin(), orphans.edge_edge.end());
        EXPECT_GT(expected.size(), 100u) << "sheet " << k;
        EXPECT_EQ(keys(all), expected) << "sheet " << k << " restricted " << restricted << " threads " << threads;
        if (k == 2) {
          EXPECT_GT(counters.triangles_culled, 0) << "culled in parts";
          EXPECT_LT(counters.triangles_culled, long(s.triangles.size()));
        }
      }
  }
}
