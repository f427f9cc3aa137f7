#include "drape/ccd/broad_phase.h"

#include <BulletCollision/BroadphaseCollision/btDbvt.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "sorted_pairs.h"

namespace drape::ccd {

namespace {
// Triangle pairs (or triangles) a parallel task takes at once in feature_pairs.
constexpr std::size_t PAIR_CHUNK = 4096;
}  // namespace

Aabb swept_box(const std::array<std::int32_t, 3>& triangle, std::span<const Vec3> start, std::span<const Vec3> end,
               Scalar margin) {
  Aabb box{start[triangle[0]], start[triangle[0]]};
  for (int k = 0; k < 3; ++k) {
    box.min = box.min.cwiseMin(start[triangle[k]]).cwiseMin(end[triangle[k]]);
    box.max = box.max.cwiseMax(start[triangle[k]]).cwiseMax(end[triangle[k]]);
  }
  box.min.array() -= margin;
  box.max.array() += margin;
  return box;
}

std::vector<FeatureVolume> vertex_volumes(std::span<const Vec3> start, std::span<const Vec3> end, Scalar margin) {
  const Scalar diagonal_margin = margin * std::sqrt(Scalar(2));
  std::vector<FeatureVolume> volumes(start.size());
  for (std::size_t v = 0; v < start.size(); ++v) {
    const auto project = [](const Vec3& p) {
      return std::array<Scalar, FeatureVolume::AXES>{p.x(),         p.y(),         p.z(),
                                                     p.x() + p.y(), p.x() - p.y(), p.x() + p.z(),
                                                     p.x() - p.z(), p.y() + p.z(), p.y() - p.z()};
    };
    const auto a = project(start[v]), b = project(end[v]);
    for (int k = 0; k < FeatureVolume::AXES; ++k) {
      const Scalar grow = k < 3 ? margin : diagonal_margin;
      volumes[v].min[k] = std::min(a[k], b[k]) - grow;
      volumes[v].max[k] = std::max(a[k], b[k]) + grow;
    }
  }
  return volumes;
}

bool overlap_within(const FeatureVolume& a, const FeatureVolume& b, Scalar shrink) {
  const Scalar straight = 2 * shrink, diagonal = straight * std::sqrt(Scalar(2));
  bool apart = false;
  for (int k = 0; k < FeatureVolume::AXES; ++k) {
    const Scalar s = k < 3 ? straight : diagonal;
    apart |= (a.min[k] + s > b.max[k]) | (b.min[k] + s > a.max[k]);
  }
  return !apart;
}

namespace {

// How far a test's volumes may be shrunk (RestGaps) when the least rest distance between a
// vertex of one feature and one of the other is sqrt(least_squared): none from the distance
// at which the gap is the whole thickness on; below it, the margin less its share.
class Shrink {
 public:
  explicit Shrink(const RestGaps& rest)
      : whole_squared_(rest.thickness * rest.thickness / (rest.fraction * rest.fraction)),
        per_distance_(rest.margin * rest.fraction / rest.thickness),
        margin_(rest.margin) {}
  Scalar operator()(Scalar least_squared) const {
    return least_squared < whole_squared_ ? margin_ - per_distance_ * std::sqrt(least_squared) : 0;
  }

 private:
  Scalar whole_squared_, per_distance_, margin_;
};

std::int32_t group_of(const RestGaps& rest, std::int32_t v) {
  return std::size_t(v) < rest.group.size() ? rest.group[std::size_t(v)] : -1;
}

// The shrink for a test with vertices v: 0 unless all four belong to one group; then shrink's
// for the least rest distance between the first first_count of v and the others'.
Scalar rest_shrink(const RestGaps& rest, const Shrink& shrink, const std::array<std::int32_t, 4>& v, int first_count) {
  const std::int32_t g = group_of(rest, v[0]);
  if (g < 0 || group_of(rest, v[1]) != g || group_of(rest, v[2]) != g || group_of(rest, v[3]) != g) return 0;
  Scalar least = std::numeric_limits<Scalar>::infinity();
  for (int i = 0; i < first_count; ++i)
    for (int j = first_count; j < 4; ++j)
      least = std::min(least, (rest.rest[std::size_t(v[i])] - rest.rest[std::size_t(v[j])]).squaredNorm());
  return shrink(least);
}

// The squared rest distances between the corners of two triangles of one group (RestGaps),
// corner i of the first against corner j of the second at [i][j]; rested false for others.
struct CornerDistances {
  bool rested = false;
  std::array<std::array<Scalar, 3>, 3> squared;
};

CornerDistances corner_distances(const RestGaps* rest, const TriangleIndices& a, const TriangleIndices& b) {
  CornerDistances d;
  if (!rest) return d;
  const std::int32_t g = group_of(*rest, a[0]);
  if (g < 0) return d;
  for (int k = 0; k < 3; ++k)
    if (group_of(*rest, a[k]) != g || group_of(*rest, b[k]) != g) return d;
  d.rested = true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d.squared[i][j] = (rest->rest[std::size_t(a[i])] - rest->rest[std::size_t(b[j])]).squaredNorm();
  return d;
}

btDbvtVolume volume_of(const Aabb& box) {
  return btDbvtVolume::FromMM(btVector3(box.min.x(), box.min.y(), box.min.z()),
                              btVector3(box.max.x(), box.max.y(), box.max.z()));
}

// Collects the leaf indices (stored in the leaves' data) of overlapping pairs.
struct PairCollector : btDbvt::ICollide {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  bool self = false;
  void Process(const btDbvtNode* a, const btDbvtNode* b) override {
    auto i = static_cast<std::int32_t>(reinterpret_cast<std::intptr_t>(a->data));
    auto j = static_cast<std::int32_t>(reinterpret_cast<std::intptr_t>(b->data));
    if (self && i > j) std::swap(i, j);
    pairs.emplace_back(i, j);
  }
};

// Bullet's incremental optimisation passes after each update (tree quality against cost).
constexpr int OPTIMIZE_PASSES = 1;

}  // namespace

struct BoxTree::Impl {
  btDbvt tree;
  std::vector<btDbvtNode*> leaves;
  std::vector<btDbvtNode*> inner, stack;  // refit's work lists, kept between calls

  // Every inner node's box made the union of its two children's, children first.
  void refit() {
    inner.clear(), stack.clear();
    if (tree.m_root) stack.push_back(tree.m_root);
    while (!stack.empty()) {
      btDbvtNode* node = stack.back();
      stack.pop_back();
      if (node->isleaf()) continue;
      inner.push_back(node);  // before its children: walked backwards, after them
      stack.push_back(node->childs[0]), stack.push_back(node->childs[1]);
    }
    for (auto node = inner.rbegin(); node != inner.rend(); ++node)
      Merge((*node)->childs[0]->volume, (*node)->childs[1]->volume, (*node)->volume);
  }
};

BoxTree::BoxTree() : impl_(std::make_unique<Impl>()) {}
BoxTree::~BoxTree() = default;
BoxTree::BoxTree(BoxTree&&) noexcept = default;
BoxTree& BoxTree::operator=(BoxTree&&) noexcept = default;

void BoxTree::update(std::span<const Aabb> boxes) {
  Impl& m = *impl_;
  if (m.leaves.size() != boxes.size()) {
    m.tree.clear();
    m.leaves.clear();
    for (std::size_t i = 0; i < boxes.size(); ++i)
      m.leaves.push_back(m.tree.insert(volume_of(boxes[i]), reinterpret_cast<void*>(static_cast<std::intptr_t>(i))));
    return;
  }
  // Each leaf takes its new box in place and the inner nodes are refitted, the tree's shape
  // kept: a cloth's triangles were inserted where they lay on the sheet, and neighbours on the
  // mesh stay neighbours however it moves. Removing and inserting every leaf (btDbvt::update)
  // cost a quarter of a 120 x 120 cloth's falling frames, for the same pairs: the pairs are
  // the overlapping leaves whatever the shape.
  for (std::size_t i = 0; i < boxes.size(); ++i) m.leaves[i]->volume = volume_of(boxes[i]);
  m.refit();
  m.tree.optimizeIncremental(OPTIMIZE_PASSES);
}

std::size_t BoxTree::size() const { return impl_->leaves.size(); }

std::vector<std::pair<std::int32_t, std::int32_t>> BoxTree::self_pairs() const {
  PairCollector collector;
  collector.self = true;
  impl_->tree.collideTT(impl_->tree.m_root, impl_->tree.m_root, collector);
  sort_pairs(collector.pairs);
  return std::move(collector.pairs);
}

std::vector<std::pair<std::int32_t, std::int32_t>> BoxTree::pairs_with(const BoxTree& other) const {
  PairCollector collector;
  impl_->tree.collideTT(impl_->tree.m_root, other.impl_->tree.m_root, collector);
  sort_pairs(collector.pairs);
  return std::move(collector.pairs);
}

std::vector<std::pair<std::int32_t, std::int32_t>> BoxTree::pairs_with_boxes(std::span<const Aabb> boxes,
                                                                             std::span<const std::int32_t> which) const {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  const btDbvtNode* root = impl_->tree.m_root;
  if (!root) return pairs;
  // Down from the root through every node whose box meets the query's (btDbvt's own test, as
  // collideTT makes it between two trees' leaves).
  std::vector<const btDbvtNode*> stack;
  for (const std::int32_t i : which) {
    const btDbvtVolume query = volume_of(boxes[std::size_t(i)]);
    stack.assign(1, root);
    while (!stack.empty()) {
      const btDbvtNode* node = stack.back();
      stack.pop_back();
      if (!Intersect(node->volume, query)) continue;
      if (node->isinternal()) {
        stack.push_back(node->childs[0]), stack.push_back(node->childs[1]);
        continue;
      }
      pairs.emplace_back(i, static_cast<std::int32_t>(reinterpret_cast<std::intptr_t>(node->data)));
    }
  }
  sort_pairs(pairs);
  return pairs;
}

FeatureOwners feature_owners(std::span<const TriangleIndices> triangles) {
  FeatureOwners owners;
  owners.bits.assign(triangles.size(), 0);
  std::int32_t highest = -1;
  for (const TriangleIndices& t : triangles) highest = std::max({highest, t[0], t[1], t[2]});
  std::vector<std::int32_t> vertex_owner(std::size_t(highest + 1), -1);
  struct Edge {
    std::int32_t low, high, triangle, side;
  };
  std::vector<Edge> edges;
  edges.reserve(triangles.size() * 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = triangles[t][k], w = triangles[t][(k + 1) % 3];
      if (vertex_owner[std::size_t(v)] < 0) {
        vertex_owner[std::size_t(v)] = std::int32_t(t);
        owners.bits[t] |= std::uint8_t(1u << k);
      }
      edges.push_back({std::min(v, w), std::max(v, w), std::int32_t(t), k});
    }
  std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) {
    return std::tie(a.low, a.high, a.triangle, a.side) < std::tie(b.low, b.high, b.triangle, b.side);
  });
  for (std::size_t i = 0; i < edges.size(); ++i)
    if (i == 0 || edges[i].low != edges[i - 1].low || edges[i].high != edges[i - 1].high)
      owners.bits[std::size_t(edges[i].triangle)] |= std::uint8_t(1u << (3 + edges[i].side));
  // A face answers for itself unless an earlier triangle has the same corners (a duplicated
  // face, as some exported meshes hold): its vertex-face tests are the first one's.
  std::vector<std::pair<TriangleIndices, std::int32_t>> faces(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    TriangleIndices corners = triangles[t];
    std::sort(corners.begin(), corners.end());
    faces[t] = {corners, std::int32_t(t)};
  }
  std::sort(faces.begin(), faces.end());
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (i == 0 || faces[i].first != faces[i - 1].first) owners.bits[std::size_t(faces[i].second)] |= std::uint8_t(1u << 6);
  return owners;
}

namespace {

// The volume of a feature: its vertices' volumes merged.
FeatureVolume merged_volume(std::span<const FeatureVolume> vertex_volumes, std::span<const std::int32_t> vertices) {
  FeatureVolume volume = vertex_volumes[std::size_t(vertices[0])];
  for (std::size_t k = 1; k < vertices.size(); ++k) volume.merge(vertex_volumes[std::size_t(vertices[k])]);
  return volume;
}

Candidates features_of(std::span<const TriangleIndices> triangles_a, std::span<const TriangleIndices> triangles_b,
                       std::span<const std::pair<std::int32_t, std::int32_t>> pairs, const FeatureOwners* owners_a,
                       const FeatureOwners* owners_b, std::span<const FeatureVolume> vertex_volumes, int threads,
                       std::span<const std::uint8_t> moved, const RestGaps* rest) {
  Candidates out;
  const bool owned = owners_a && owners_b;
  const auto answers = [&](const FeatureOwners* owners, std::int32_t triangle, int bit) {
    return !owned || ((owners->bits[std::size_t(triangle)] >> bit) & 1u);
  };
  const bool cull = !vertex_volumes.empty();
  const auto any_moved = [&](std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) {
    return moved.empty() || moved[std::size_t(a)] || moved[std::size_t(b)] || moved[std::size_t(c)] || moved[std::size_t(d)];
  };
  const auto union_of = [&](std::span<const std::int32_t> vertices) { return merged_volume(vertex_volumes, vertices); };
  // Each triangle's face and edge volumes, once per call (a triangle is in many pairs).
  struct TriangleVolumes {
    FeatureVolume face;
    std::array<FeatureVolume, 3> edge;  // edge i runs from corner i to corner i + 1
  };
  // Runs body(begin, end) over [0, n) in chunks, in parallel when threads > 1.
  const auto chunks = [&](std::size_t n, const auto& body) {
    if (threads <= 1 || n < 2 * PAIR_CHUNK) return body(std::size_t(0), n);
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, PAIR_CHUNK), [&](const auto& r) { body(r.begin(), r.end()); });
    });
  };
  // Only the triangles the pairs hold: a later round's few pairs on a large mesh (a knit
  // caught on a needle) made every triangle's volumes in every call. slot[t]: triangle t's
  // place in volumes, or -1.
  struct Volumes {
    std::vector<std::int32_t> slot;
    std::vector<TriangleVolumes> volumes;
  };
  const bool same_triangles = triangles_a.data() == triangles_b.data() && triangles_a.size() == triangles_b.size();
  const auto volumes_of = [&](std::span<const TriangleIndices> triangles, bool side_a, bool side_b) {
    Volumes v;
    if (!cull) return v;
    v.slot.assign(triangles.size(), -1);
    std::vector<std::int32_t> held;
    const auto hold = [&](std::int32_t t) {
      if (v.slot[std::size_t(t)] < 0) v.slot[std::size_t(t)] = std::int32_t(held.size()), held.push_back(t);
    };
    for (const auto& [ia, ib] : pairs) {
      if (side_a) hold(ia);
      if (side_b) hold(ib);
    }
    v.volumes.resize(held.size());
    chunks(held.size(), [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const TriangleIndices& tri = triangles[std::size_t(held[k])];
        v.volumes[k].face = union_of(tri);
        for (int i = 0; i < 3; ++i) v.volumes[k].edge[i] = union_of(std::array<std::int32_t, 2>{tri[i], tri[(i + 1) % 3]});
      }
    });
    return v;
  };
  const Volumes volumes_a = volumes_of(triangles_a, true, same_triangles);
  const Volumes volumes_b = same_triangles ? Volumes{} : volumes_of(triangles_b, false, true);
  const Volumes& of_b = same_triangles ? volumes_a : volumes_b;
  const Shrink shrink(rest ? *rest : RestGaps{{}, {}, 1, 1, 0});
  using Key = std::array<std::int32_t, 4>;  // (vertex, face corners) and (edge, edge), canonical
  const auto shares = [](std::int32_t v, const TriangleIndices& t) { return v == t[0] || v == t[1] || v == t[2]; };
  // The features of pairs [begin, end) into vf and ee.
  const auto collect = [&](std::size_t begin, std::size_t end, std::vector<Key>& vf, std::vector<Key>& ee) {
    vf.reserve((end - begin) * 6);
    ee.reserve((end - begin) * 9);
    // least(distances(), k): the squared rest distance from corner k of from to the nearest of
    // face's corners.
    const auto add_vertex_face = [&](const TriangleIndices& from, const FeatureOwners* from_owners, std::int32_t from_index,
                                     const TriangleIndices& face, const FeatureOwners* face_owners, std::int32_t face_index,
                                     const FeatureVolume* face_volume, const auto& distances, const auto& least) {
      if (!answers(face_owners, face_index, 6)) return;
      for (int k = 0; k < 3; ++k) {
        const std::int32_t v = from[k];
        if (!answers(from_owners, from_index, k) || shares(v, face) || !any_moved(v, face[0], face[1], face[2])) continue;
        if (cull) {
          if (!overlap(vertex_volumes[v], *face_volume)) continue;
          const CornerDistances& c = distances();
          if (c.rested) {
            const Scalar by = shrink(least(c, k));
            if (by > 0 && !overlap_within(vertex_volumes[v], *face_volume, by)) continue;
          }
        }
        vf.push_back({v, face[0], face[1], face[2]});
      }
    };
    for (std::size_t p = begin; p < end; ++p) {
      const auto& [ia, ib] = pairs[p];
      const TriangleIndices& a = triangles_a[ia];
      const TriangleIndices& b = triangles_b[ib];
      const TriangleVolumes* va = cull ? &volumes_a.volumes[std::size_t(volumes_a.slot[std::size_t(ia)])] : nullptr;
      const TriangleVolumes* vb = cull ? &of_b.volumes[std::size_t(of_b.slot[std::size_t(ib)])] : nullptr;
      // The corners' rest distances, computed when a test first needs them.
      CornerDistances d;
      bool measured = false;
      const auto distances = [&]() -> const CornerDistances& {
        if (!measured) d = corner_distances(rest, a, b), measured = true;
        return d;
      };
      add_vertex_face(a, owners_a, ia, b, owners_b, ib, cull ? &vb->face : nullptr, distances, [](const CornerDistances& c, int k) {
        return std::min({c.squared[k][0], c.squared[k][1], c.squared[k][2]});
      });
      add_vertex_face(b, owners_b, ib, a, owners_a, ia, cull ? &va->face : nullptr, distances, [](const CornerDistances& c, int k) {
        return std::min({c.squared[0][k], c.squared[1][k], c.squared[2][k]});
      });
      for (int i = 0; i < 3; ++i) {
        if (!answers(owners_a, ia, 3 + i)) continue;
        std::array<std::int32_t, 2> e{a[i], a[(i + 1) % 3]};
        if (e[0] > e[1]) std::swap(e[0], e[1]);
        for (int j = 0; j < 3; ++j) {
          if (!answers(owners_b, ib, 3 + j)) continue;
          std::array<std::int32_t, 2> f{b[j], b[(j + 1) % 3]};
          if (f[0] > f[1]) std::swap(f[0], f[1]);
          if (e[0] == f[0] || e[0] == f[1] || e[1] == f[0] || e[1] == f[1] || !any_moved(e[0], e[1], f[0], f[1])) continue;
          if (cull) {
            if (!overlap(va->edge[i], vb->edge[j])) continue;
            const CornerDistances& c = distances();
            const int i1 = (i + 1) % 3, j1 = (j + 1) % 3;
            const auto& q = c.squared;
            if (c.rested) {
              const Scalar by = shrink(std::min({q[i][j], q[i][j1], q[i1][j], q[i1][j1]}));
              if (by > 0 && !overlap_within(va->edge[i], vb->edge[j], by)) continue;
            }
          }
          // The same two edges can come from (a, b) or (b, a): order them.
          if (f < e) ee.push_back({f[0], f[1], e[0], e[1]});
          else ee.push_back({e[0], e[1], f[0], f[1]});
        }
      }
    }
  };
  std::vector<Key> vf, ee;
  if (threads <= 1 || pairs.size() < 2 * PAIR_CHUNK) {
    collect(0, pairs.size(), vf, ee);
  } else {
    // Each chunk into its own lists, joined in chunk order: the sort below makes the order of
    // the chunks irrelevant anyway.
    const std::size_t count = (pairs.size() + PAIR_CHUNK - 1) / PAIR_CHUNK;
    std::vector<std::vector<Key>> chunk_vf(count), chunk_ee(count);
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(std::size_t(0), count, [&](std::size_t c) {
        collect(c * PAIR_CHUNK, std::min(pairs.size(), (c + 1) * PAIR_CHUNK), chunk_vf[c], chunk_ee[c]);
      });
    });
    for (std::size_t c = 0; c < count; ++c) {
      vf.insert(vf.end(), chunk_vf[c].begin(), chunk_vf[c].end());
      ee.insert(ee.end(), chunk_ee[c].begin(), chunk_ee[c].end());
    }
  }
  if (!owned) {  // every test as often as its triangle pairs: sorted, and each kept once
    if (threads > 1) {
      tbb::task_arena arena(threads);
      arena.execute([&] {
        tbb::parallel_sort(vf.begin(), vf.end());
        tbb::parallel_sort(ee.begin(), ee.end());
      });
    } else {
      std::sort(vf.begin(), vf.end());
      std::sort(ee.begin(), ee.end());
    }
    vf.erase(std::unique(vf.begin(), vf.end()), vf.end());
    ee.erase(std::unique(ee.begin(), ee.end()), ee.end());
  }
  out.vertex_face.reserve(vf.size());
  for (const auto& k : vf) out.vertex_face.push_back({k[0], {k[1], k[2], k[3]}});
  out.edge_edge.reserve(ee.size());
  for (const auto& k : ee) out.edge_edge.push_back({{k[0], k[1]}, {k[2], k[3]}});
  return out;
}

}  // namespace

Candidates feature_pairs(std::span<const TriangleIndices> triangles_a, std::span<const TriangleIndices> triangles_b,
                         std::span<const std::pair<std::int32_t, std::int32_t>> pairs,
                         std::span<const FeatureVolume> vertex_volumes, int threads, std::span<const std::uint8_t> moved,
                         const RestGaps* rest) {
  return features_of(triangles_a, triangles_b, pairs, nullptr, nullptr, vertex_volumes, threads, moved, rest);
}

Candidates feature_pairs(std::span<const TriangleIndices> triangles_a, std::span<const TriangleIndices> triangles_b,
                         std::span<const std::pair<std::int32_t, std::int32_t>> pairs, const FeatureOwners& owners_a,
                         const FeatureOwners& owners_b, std::span<const FeatureVolume> vertex_volumes, int threads,
                         std::span<const std::uint8_t> moved, const RestGaps* rest) {
  return features_of(triangles_a, triangles_b, pairs, &owners_a, &owners_b, vertex_volumes, threads, moved, rest);
}

void keep_overlapping(Candidates& tests, std::span<const FeatureVolume> vertex_volumes, const RestGaps* rest) {
  const auto merged = [&](std::span<const std::int32_t> vertices) { return merged_volume(vertex_volumes, vertices); };
  const Shrink shrink(rest ? *rest : RestGaps{{}, {}, 1, 1, 0});
  // Whether a and b overlap, within the rest gap's share of the margin for a test of vertices
  // v (first_count of them the first feature's): the rest distances only for those that do.
  const auto keeps = [&](const FeatureVolume& a, const FeatureVolume& b, const std::array<std::int32_t, 4>& v, int first_count) {
    if (!overlap(a, b)) return false;
    if (!rest) return true;
    const Scalar by = rest_shrink(*rest, shrink, v, first_count);
    return by <= 0 || overlap_within(a, b, by);
  };
  std::erase_if(tests.vertex_face, [&](const VertexFacePair& t) {
    return !keeps(vertex_volumes[std::size_t(t.vertex)], merged(t.face), {t.vertex, t.face[0], t.face[1], t.face[2]}, 1);
  });
  std::erase_if(tests.edge_edge, [&](const EdgeEdgePair& t) {
    return !keeps(merged(t.edge_a), merged(t.edge_b), {t.edge_a[0], t.edge_a[1], t.edge_b[0], t.edge_b[1]}, 2);
  });
}

}  // namespace drape::ccd
