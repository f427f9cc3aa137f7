// PatchTree's construction (patch_tree.h): the hierarchy of patches over the rest shape, their
// star contours, and the orphan sets of adjacent triangle pairs. The per-step traversal is in
// patch_tree.cpp.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

#include "drape/ccd/patch_tree.h"

namespace drape::ccd {

PatchTree::PatchTree(std::span<const TriangleIndices> triangles, std::span<const Vec3> reference)
    : triangles_(triangles.begin(), triangles.end()) {
  const auto n = std::int32_t(triangles_.size());
  if (n == 0) return;
  // Neighbours across consistently oriented manifold edges: edge i runs from corner i to i + 1.
  struct HalfEdge {
    std::int32_t low, high, triangle, corner;
    bool forward;  // runs low -> high
  };
  std::vector<HalfEdge> half;
  half.reserve(std::size_t(n) * 3);
  for (std::int32_t t = 0; t < n; ++t)
    for (std::int32_t i = 0; i < 3; ++i) {
      const std::int32_t a = triangles_[t][i], b = triangles_[t][(i + 1) % 3];
      half.push_back({std::min(a, b), std::max(a, b), t, i, a < b});
    }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.low, x.high, x.triangle, x.corner) < std::tie(y.low, y.high, y.triangle, y.corner);
  });
  BuildScratch scratch;
  scratch.neighbours.assign(std::size_t(n), {-1, -1, -1});
  scratch.stamp.assign(std::size_t(n), -1);
  scratch.position.assign(std::size_t(n), 0);
  std::int32_t highest = 0;
  for (const TriangleIndices& t : triangles_) highest = std::max({highest, t[0], t[1], t[2]});
  scratch.vertex_seen.assign(std::size_t(highest) + 1, -1);
  scratch.boundary_stamp.assign(std::size_t(highest) + 1, -1);
  scratch.boundary_next.assign(std::size_t(highest) + 1, 0);
  auto& neighbours = scratch.neighbours;
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].low == half[i].low && half[j].high == half[i].high) ++j;
    const HalfEdge &x = half[i], &y = half[j - 1];
    if (j - i == 2 && x.low != x.high && x.forward != y.forward && x.triangle != y.triangle) {
      neighbours[x.triangle][x.corner] = y.triangle;
      neighbours[y.triangle][y.corner] = x.triangle;
    }
    i = j;
  }
  std::vector<std::int32_t> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), 0);
  order_.reserve(std::size_t(n));
  build(all, scratch, reference);
  for (std::size_t i = 0; i < nodes_.size(); ++i)
    if (nodes_[i].right < 0) {
      leaves_.push_back(std::int32_t(i));
      leaf_first_.push_back(nodes_[i].first);
      leaf_count_.push_back(nodes_[i].count);
    }
  ordered_.reserve(order_.size());
  for (const std::int32_t t : order_) ordered_.push_back(triangles_[std::size_t(t)]);
  build_orphans();
}

void PatchTree::build_orphans() {
  const std::size_t nodes = nodes_.size();
  // Each triangle's leaf, and each node's parent and depth (a left child follows its parent).
  std::vector<std::int32_t> parent(nodes, -1), depth(nodes, 0), leaf_of(triangles_.size(), 0);
  for (std::size_t i = 0; i < nodes; ++i) {
    const Node& node = nodes_[i];
    if (node.right < 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) leaf_of[std::size_t(order_[std::size_t(k)])] = std::int32_t(i);
      continue;
    }
    for (std::size_t child : {i + 1, std::size_t(node.right)}) parent[child] = std::int32_t(i), depth[child] = depth[i] + 1;
  }
  const auto common = [&](std::int32_t a, std::int32_t b) {
    while (depth[std::size_t(a)] > depth[std::size_t(b)]) a = parent[std::size_t(a)];
    while (depth[std::size_t(b)] > depth[std::size_t(a)]) b = parent[std::size_t(b)];
    while (a != b) a = parent[std::size_t(a)], b = parent[std::size_t(b)];
    return a;
  };
  // The pairs of triangles sharing a vertex, once each (i < j), by their lowest common node.
  std::int32_t highest = -1;
  for (const TriangleIndices& t : triangles_) highest = std::max({highest, t[0], t[1], t[2]});
  std::vector<std::vector<std::int32_t>> around(std::size_t(highest) + 1);
  for (std::size_t t = 0; t < triangles_.size(); ++t)
    for (std::int32_t v : triangles_[t]) around[std::size_t(v)].push_back(std::int32_t(t));
  std::vector<std::tuple<std::int32_t, std::int32_t, std::int32_t>> adjacent;  // (node, i, j)
  std::vector<std::int32_t> others;
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    others.clear();
    for (std::int32_t v : triangles_[t])
      for (std::int32_t u : around[std::size_t(v)])
        if (u > std::int32_t(t)) others.push_back(u);
    std::sort(others.begin(), others.end());
    others.erase(std::unique(others.begin(), others.end()), others.end());
    for (std::int32_t u : others) adjacent.emplace_back(common(leaf_of[t], leaf_of[std::size_t(u)]), std::int32_t(t), u);
  }
  std::sort(adjacent.begin(), adjacent.end());
  // Their tests, node by node, as feature_pairs' owned overload makes them.
  const FeatureOwners owners = feature_owners(triangles_);
  orphan_vf_start_.assign(nodes + 1, 0);
  orphan_ee_start_.assign(nodes + 1, 0);
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  for (std::size_t k = 0, node = 0; node < nodes; ++node) {
    pairs.clear();
    for (; k < adjacent.size() && std::size_t(std::get<0>(adjacent[k])) == node; ++k)
      pairs.emplace_back(std::get<1>(adjacent[k]), std::get<2>(adjacent[k]));
    if (!pairs.empty()) {
      const Candidates tests = feature_pairs(triangles_, triangles_, pairs, owners, owners);
      orphan_vf_.insert(orphan_vf_.end(), tests.vertex_face.begin(), tests.vertex_face.end());
      orphan_ee_.insert(orphan_ee_.end(), tests.edge_edge.begin(), tests.edge_edge.end());
    }
    orphan_vf_start_[node + 1] = std::int32_t(orphan_vf_.size());
    orphan_ee_start_[node + 1] = std::int32_t(orphan_ee_.size());
  }
}

bool PatchTree::lists(const Motion& m, std::int32_t i, std::int32_t j) const {
  if (!m.keeps(i, j) || !overlap(m.triangle_box[std::size_t(i)], m.triangle_box[std::size_t(j)])) return false;
  if (!m.skip_adjacent) return true;
  const TriangleIndices &a = ordered_[std::size_t(i)], &b = ordered_[std::size_t(j)];
  for (std::int32_t v : a)
    if (v == b[0] || v == b[1] || v == b[2]) return false;  // sharing a corner: the orphan sets' tests
  return true;
}

std::int32_t PatchTree::build(std::vector<std::int32_t>& set, BuildScratch& scratch, std::span<const Vec3> reference) {
  const auto& neighbours = scratch.neighbours;
  const auto index = std::int32_t(nodes_.size());
  nodes_.push_back({-1, std::int32_t(order_.size()), std::int32_t(set.size()), 0, 0});
  // Membership of the set, for its connectivity and boundary (the parent's is no longer needed).
  for (std::size_t k = 0; k < set.size(); ++k) scratch.stamp[std::size_t(set[k])] = index, scratch.position[std::size_t(set[k])] = std::int32_t(k);
  const auto in_set = [&](std::int32_t t) { return t >= 0 && scratch.stamp[std::size_t(t)] == index; };
  // Connected components through the neighbour links inside the set.
  std::vector<std::int32_t> component(set.size(), -1);
  std::int32_t components = 0;
  for (std::size_t k = 0; k < set.size(); ++k) {
    if (component[k] >= 0) continue;
    std::vector<std::int32_t> stack{std::int32_t(k)};
    component[k] = components;
    while (!stack.empty()) {
      const std::int32_t at = stack.back();
      stack.pop_back();
      for (std::int32_t nb : neighbours[set[std::size_t(at)]])
        if (in_set(nb)) {
          const std::int32_t p = scratch.position[std::size_t(nb)];
          if (component[std::size_t(p)] < 0) component[std::size_t(p)] = components, stack.push_back(p);
        }
    }
    ++components;
  }
  // A disk: connected, its boundary half-edges one cycle through distinct vertices, and Euler
  // characteristic V - E + F = 1 (with one boundary cycle, only a disk has it).
  if (components == 1) {
    // Per vertex, stamped with this node: seen, and the boundary's next vertex after it.
    auto& seen = scratch.vertex_seen;
    auto& next = scratch.boundary_next;
    auto& next_stamp = scratch.boundary_stamp;
    bool simple = true;
    std::size_t boundary = 0;
    std::int64_t v = 0;
    std::int32_t first = -1;  // the boundary's least vertex
    for (std::int32_t t : set) {
      const TriangleIndices& tri = triangles_[std::size_t(t)];
      for (int i = 0; i < 3; ++i) {
        const auto a = std::size_t(tri[i]);
        if (seen[a] != index) seen[a] = index, ++v;
        if (in_set(neighbours[std::size_t(t)][i])) continue;
        ++boundary;
        simple &= next_stamp[a] != index;  // one boundary edge out of each vertex
        next_stamp[a] = index;
        next[a] = tri[(i + 1) % 3];
        first = first < 0 ? tri[i] : std::min(first, tri[i]);
      }
    }
    const auto f = std::int64_t(set.size());
    const std::int64_t e = (3 * f + std::int64_t(boundary)) / 2;
    if (simple && boundary >= 3 && v - e + f == 1) {
      // Started at its least vertex, so that the order of its sums is the same everywhere.
      std::vector<std::int32_t> cycle{first};
      while (cycle.size() <= boundary) {
        const auto at = std::size_t(cycle.back());
        if (next_stamp[at] != index || next[at] == first) break;
        cycle.push_back(next[at]);
      }
      const auto last = std::size_t(cycle.back());
      if (cycle.size() == boundary && next_stamp[last] == index && next[last] == first) {
        nodes_[std::size_t(index)].contour_first = std::int32_t(contours_.size());
        nodes_[std::size_t(index)].contour_count = std::int32_t(cycle.size());
        contours_.insert(contours_.end(), cycle.begin(), cycle.end());
      }
    }
  }
  if (std::int32_t(set.size()) <= LEAF_TRIANGLES) {
    order_.insert(order_.end(), set.begin(), set.end());
    return index;
  }
  // Split: whole components apart when there are several, else at the median of the
  // triangles' centres along the longest side of their box (in the reference shape).
  const auto centre = [&](std::int32_t t) {
    const TriangleIndices& tri = triangles_[std::size_t(t)];
    return Vec3((reference[tri[0]] + reference[tri[1]] + reference[tri[2]]) / 3);
  };
  Vec3 low = centre(set[0]), high = low;
  for (std::int32_t t : set) low = low.cwiseMin(centre(t)), high = high.cwiseMax(centre(t));
  int axis = 0;
  (high - low).maxCoeff(&axis);
  std::vector<std::int32_t> left, right;
  if (components > 1) {
    std::vector<Scalar> position(std::size_t(components), 0);
    std::vector<std::int32_t> size(std::size_t(components), 0);
    for (std::size_t k = 0; k < set.size(); ++k) {
      position[std::size_t(component[k])] += centre(set[k])[axis];
      ++size[std::size_t(component[k])];
    }
    std::vector<std::int32_t> ranked(static_cast<std::size_t>(components));
    std::iota(ranked.begin(), ranked.end(), 0);
    std::sort(ranked.begin(), ranked.end(), [&](std::int32_t a, std::int32_t b) {
      const Scalar pa = position[std::size_t(a)] / size[std::size_t(a)], pb = position[std::size_t(b)] / size[std::size_t(b)];
      return pa != pb ? pa < pb : a < b;
    });
    std::vector<char> to_left(std::size_t(components), 0);
    std::size_t taken = 0;
    for (std::size_t r = 0; r + 1 < ranked.size() && taken < set.size() / 2; ++r) {
      to_left[std::size_t(ranked[r])] = 1;
      taken += std::size_t(size[std::size_t(ranked[r])]);
    }
    for (std::size_t k = 0; k < set.size(); ++k) (to_left[std::size_t(component[k])] ? left : right).push_back(set[k]);
  } else {
    std::vector<std::int32_t> sorted = set;
    const auto middle = sorted.begin() + std::ptrdiff_t(sorted.size() / 2);
    std::nth_element(sorted.begin(), middle, sorted.end(), [&](std::int32_t a, std::int32_t b) {
      const Scalar ca = centre(a)[axis], cb = centre(b)[axis];
      return ca != cb ? ca < cb : a < b;
    });
    left.assign(sorted.begin(), middle);
    right.assign(middle, sorted.end());
  }
  set.clear();
  set.shrink_to_fit();
  build(left, scratch, reference);
  const std::int32_t r = build(right, scratch, reference);
  nodes_[std::size_t(index)].right = r;
  return index;
}

}  // namespace drape::ccd
