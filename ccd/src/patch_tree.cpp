#include "drape/ccd/patch_tree.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <numeric>
#include <tuple>

#include "kernels.h"
#include "sorted_pairs.h"

namespace drape::ccd {

namespace {

using detail::CONE_MARGIN;
// A contour edge's signed area around the star's centre must exceed this times the product of
// the two corners' distances from it (far above the rounding error of the determinant).
constexpr Scalar STAR_MARGIN = 1e-9;
// Nodes at least this large are traversed as parallel tasks.
constexpr std::int32_t TASK_TRIANGLES = 2048;

using Pairs = std::vector<std::pair<std::int32_t, std::int32_t>>;

Aabb merged(const Aabb& a, const Aabb& b) { return {a.min.cwiseMin(b.min), a.max.cwiseMax(b.max)}; }

}  // namespace

bool PatchTree::culled(const Motion& m, std::int32_t index, SelfCullCounters& counters) const {
  const Node& node = nodes_[std::size_t(index)];
  if (node.count < 2) return true;
  if (node.contour_count == 0 || !m.cone_ok[std::size_t(index)]) return false;
  ++counters.patches_tested;
  const std::span<const std::int32_t> contour(contours_.data() + node.contour_first, std::size_t(node.contour_count));
  Vec3 centre0 = Vec3::Zero(), centre1 = Vec3::Zero();
  for (std::int32_t v : contour) centre0 += m.start[v], centre1 += m.end[v];
  centre0 /= Scalar(contour.size());
  centre1 /= Scalar(contour.size());
  const Vec3& d = m.axis[std::size_t(index)];
  // u and w span the plane across d. Once every edge is known to turn counter-clockwise about
  // the centre by less than half a turn, the edges whose w goes from negative to non-negative
  // are those crossing the ray along u, and their number is the contour's winding number.
  const Vec3 u = d.cross(std::abs(d.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
  const Vec3 w = d.cross(u);
  int crossings = 0;
  for (std::size_t k = 0; k < contour.size(); ++k) {
    const std::int32_t a = contour[k], b = contour[(k + 1) % contour.size()];
    const Vec3 a0 = m.start[a] - centre0, a1 = m.end[a] - centre1;
    const Vec3 b0 = m.start[b] - centre0, b1 = m.end[b] - centre1;
    // The signed area (a(t) - c(t)) x (b(t) - c(t)) . d in Bernstein form of degree 2.
    const Scalar k0 = a0.cross(b0).dot(d), k2 = a1.cross(b1).dot(d);
    const Scalar k1 = 0.5 * (a0.cross(b1) + a1.cross(b0)).dot(d);
    const Scalar floor = STAR_MARGIN * (a0.norm() + a1.norm()) * (b0.norm() + b1.norm());
    if (!(k0 > floor && k1 > floor && k2 > floor)) return false;
    if (a0.dot(w) < 0 && b0.dot(w) >= 0) ++crossings;
  }
  if (crossings != 1) return false;
  ++counters.patches_culled;
  counters.triangles_culled += node.count;
  return true;
}

void PatchTree::self(const Motion& m, std::int32_t index, Pairs& out, SelfCullCounters& counters) const {
  if (m.holds_moved(index) && !culled(m, index, counters)) own(m, index, out, counters);
}

void PatchTree::own(const Motion& m, std::int32_t index, Pairs& out, SelfCullCounters& counters) const {
  const Node& node = nodes_[std::size_t(index)];
  if (m.skip_adjacent) m.reached[std::size_t(index)] = 1;
  if (node.right < 0) {
    for (std::int32_t i = node.first; i < node.first + node.count; ++i)
      for (std::int32_t j = i + 1; j < node.first + node.count; ++j)
        if (lists(m, i, j))
          out.emplace_back(std::minmax(order_[std::size_t(i)], order_[std::size_t(j)]));
    return;
  }
  self(m, index + 1, out, counters);
  self(m, node.right, out, counters);
  across(m, index + 1, node.right, out);
}

void PatchTree::across(const Motion& m, std::int32_t a, std::int32_t b, Pairs& out) const {
  if ((!m.holds_moved(a) && !m.holds_moved(b)) || !overlap(m.box[std::size_t(a)], m.box[std::size_t(b)])) return;
  const Node &na = nodes_[std::size_t(a)], &nb = nodes_[std::size_t(b)];
  if (na.right < 0 && nb.right < 0) {
    for (std::int32_t i = na.first; i < na.first + na.count; ++i)
      for (std::int32_t j = nb.first; j < nb.first + nb.count; ++j)
        if (lists(m, i, j))
          out.emplace_back(std::minmax(order_[std::size_t(i)], order_[std::size_t(j)]));
    return;
  }
  if (na.right < 0 || (nb.right >= 0 && nb.count > na.count)) {
    across(m, a, b + 1, out);
    across(m, a, nb.right, out);
  } else {
    across(m, a + 1, b, out);
    across(m, na.right, b, out);
  }
}

std::vector<std::pair<std::int32_t, std::int32_t>> PatchTree::self_pairs(std::span<const Vec3> start,
                                                                         std::span<const Vec3> end, Scalar margin,
                                                                         int threads, SelfCullCounters* counters,
                                                                         std::span<const std::uint8_t> moved,
                                                                         Candidates* orphans) {
  Pairs out;
  if (orphans) *orphans = {};
  if (nodes_.empty()) return out;
  Motion& m = motion_;  // kept between calls: its arrays keep their size
  m.start = start;
  m.end = end;
  m.skip_adjacent = orphans != nullptr;
  if (orphans) m.reached.assign(nodes_.size(), 0);
  m.triangle_moved.clear();
  m.node_moved.clear();
  const std::size_t nodes = nodes_.size();
  if (!moved.empty()) {
    m.triangle_moved.resize(order_.size());
    m.node_moved.assign(nodes, 0);
    for (std::size_t i = nodes; i-- > 0;) {
      const Node& node = nodes_[i];
      if (node.right >= 0) {
        m.node_moved[i] = m.node_moved[i + 1] || m.node_moved[std::size_t(node.right)];
        continue;
      }
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        const TriangleIndices& t = ordered_[std::size_t(k)];
        m.triangle_moved[std::size_t(k)] = moved[std::size_t(t[0])] || moved[std::size_t(t[1])] || moved[std::size_t(t[2])];
        m.node_moved[i] = m.node_moved[i] || m.triangle_moved[std::size_t(k)];
      }
    }
    if (!m.node_moved[0]) return out;
  }
  m.sum.resize(nodes);
  m.axis.resize(nodes);
  m.cos.resize(nodes);
  m.sin.resize(nodes);
  m.cone_ok.resize(nodes);
  // body(begin, stop) over ranges of the leaves (of at least CHUNK), in parallel when threads > 1.
  const auto leaf_ranges = [&](const auto& body) {
    if (threads <= 1) return body(std::size_t(0), leaves_.size());
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves_.size(), detail::CHUNK),
                        [&](const auto& r) { body(r.begin(), r.end()); });
    });
  };
  // The leaves' normal cones, a chunk of leaves at a time (kernels_cones.cpp).
  static_assert(LEAF_TRIANGLES <= detail::CONE_LEAF_TRIANGLES, "a leaf's triangles fit the cones' kernel");
  leaf_ranges([&](std::size_t begin, std::size_t stop) {
    detail::ChunkCones cones;
    for (std::size_t b = begin; b < stop; b += detail::CHUNK) {
      const std::size_t n = std::min(detail::CHUNK, stop - b);
      detail::chunk_cones(start.data(), end.data(), ordered_.data(), leaf_first_.data() + b, leaf_count_.data() + b, n, cones);
      for (std::size_t j = 0; j < n; ++j) {
        const std::size_t index = std::size_t(leaves_[b + j]);
        m.sum[index] = Vec3(cones.sum[0][j], cones.sum[1][j], cones.sum[2][j]);
        m.axis[index] = Vec3(cones.axis[0][j], cones.axis[1][j], cones.axis[2][j]);
        m.cos[index] = cones.cos[j];
        m.sin[index] = cones.sin[j];
        m.cone_ok[index] = (cones.ok >> j) & 1;
      }
    }
  });
  // Their triangles' boxes, and the leaves' boxes.
  const auto leaf_boxes = [&](std::size_t begin, std::size_t stop) {
    for (std::size_t i = begin; i < stop; ++i) {
      const Node& node = nodes_[std::size_t(leaves_[i])];
      Aabb box;
      for (std::int32_t k = 0; k < node.count; ++k) {
        Aabb& b = m.triangle_box[std::size_t(node.first + k)];
        b = swept_box(ordered_[std::size_t(node.first + k)], start, end, margin);
        box = k == 0 ? b : merged(box, b);
      }
      m.box[std::size_t(leaves_[i])] = box;
    }
  };
  // The inner nodes, children first (they follow their parent): merged boxes, and a cone about
  // the summed axis wide enough for both children's cones (angles add).
  for (std::size_t i = nodes; i-- > 0;) {
    const Node& node = nodes_[i];
    if (node.right < 0) continue;
    const std::size_t l = i + 1, r = std::size_t(node.right);
    m.sum[i] = m.sum[l] + m.sum[r];
    const Scalar length = m.sum[i].norm();
    bool ok = m.cone_ok[l] && m.cone_ok[r] && length > 0;
    const Vec3 axis = ok ? Vec3(m.sum[i] / length) : Vec3::UnitZ();
    Scalar least = 1;
    for (std::size_t c : {l, r}) {
      if (!ok) break;
      const Scalar cos_apart = m.axis[c].dot(axis), sin_apart = m.axis[c].cross(axis).norm();
      ok = cos_apart > 0;
      least = std::min(least, m.cos[c] * cos_apart - m.sin[c] * sin_apart);
    }
    ok = ok && least > CONE_MARGIN;
    m.axis[i] = axis;
    m.cos[i] = least;
    m.sin[i] = std::sqrt(std::max(Scalar(0), 1 - least * least));
    m.cone_ok[i] = ok;
  }
  SelfCullCounters local;
  const auto report = [&] {
    if (counters) *counters += local;
  };
  // A root proven free (a flat or gently curved sheet) needs no boxes at all.
  if (culled(m, 0, local)) {
    report();
    return out;
  }
  m.triangle_box.resize(order_.size());
  m.box.resize(nodes);
  leaf_ranges(leaf_boxes);
  for (std::size_t i = nodes; i-- > 0;)
    if (nodes_[i].right >= 0) m.box[i] = merged(m.box[i + 1], m.box[std::size_t(nodes_[i].right)]);
  if (threads <= 1) {
    own(m, 0, out, local);
  } else {
    // The top of the tree serially down to nodes of TASK_TRIANGLES, then each such node's own
    // pairs and each pair of such nodes met on the way as a task; joined in task order.
    struct Task {
      std::int32_t a, b;  // b < 0: a's own pairs
    };
    std::vector<Task> tasks;
    const auto split = [&](auto&& split, std::int32_t index) -> void {
      if (index != 0 && (!m.holds_moved(index) || culled(m, index, local))) return;  // the root is known not culled
      const Node& node = nodes_[std::size_t(index)];
      if (node.right < 0 || node.count < TASK_TRIANGLES) {
        tasks.push_back({index, -1});
        return;
      }
      if (m.skip_adjacent) m.reached[std::size_t(index)] = 1;
      split(split, index + 1);
      split(split, node.right);
      tasks.push_back({index + 1, node.right});
    };
    split(split, 0);
    std::vector<Pairs> found(tasks.size());
    std::vector<SelfCullCounters> task_counters(tasks.size());
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(std::size_t(0), tasks.size(), [&](std::size_t k) {
        if (tasks[k].b < 0) own(m, tasks[k].a, found[k], task_counters[k]);
        else across(m, tasks[k].a, tasks[k].b, found[k]);
      });
    });
    for (std::size_t k = 0; k < tasks.size(); ++k) {
      out.insert(out.end(), found[k].begin(), found[k].end());
      local += task_counters[k];
    }
  }
  sort_pairs(out);
  if (orphans) {
    // The reached nodes' orphans, in node order, those with a moved vertex when restricted.
    const auto any_moved = [&](std::initializer_list<std::int32_t> vertices) {
      if (moved.empty()) return true;
      for (std::int32_t v : vertices)
        if (moved[std::size_t(v)]) return true;
      return false;
    };
    for (std::size_t node = 0; node < nodes; ++node) {
      if (!m.reached[node]) continue;
      for (std::int32_t k = orphan_vf_start_[node]; k < orphan_vf_start_[node + 1]; ++k) {
        const VertexFacePair& t = orphan_vf_[std::size_t(k)];
        if (any_moved({t.vertex, t.face[0], t.face[1], t.face[2]})) orphans->vertex_face.push_back(t);
      }
      for (std::int32_t k = orphan_ee_start_[node]; k < orphan_ee_start_[node + 1]; ++k) {
        const EdgeEdgePair& t = orphan_ee_[std::size_t(k)];
        if (any_moved({t.edge_a[0], t.edge_a[1], t.edge_b[0], t.edge_b[1]})) orphans->edge_edge.push_back(t);
      }
    }
  }
  report();
  return out;
}

}  // namespace drape::ccd
