#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "collision_pipeline.h"
#include "drape/ccd/distance.h"
#include "drape/core/obstacle.h"

namespace drape {

namespace {

// A closest point's weight inside its feature, not at its rim (INNER_WEIGHT).
bool inner(Scalar w) { return w > INNER_WEIGHT && w < 1 - INNER_WEIGHT; }

// A point's projection on a triangle's plane: the plane's unit normal (by the corners' order),
// the point's height over it and the projection's weights of the corners (signed: negative
// beyond the edge opposite a corner). None for a triangle without area.
struct PlaneProjection {
  Vec3 unit;
  Scalar height;
  std::array<Scalar, 3> weight;
};
std::optional<PlaneProjection> project_on_plane(const Vec3& point, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 across = (b - a).cross(c - a);
  const Scalar twice_area = across.norm();
  if (!(twice_area > 0)) return std::nullopt;
  PlaneProjection out;
  out.unit = across / twice_area;
  out.height = (point - a).dot(out.unit);
  const Vec3 q = point - out.height * out.unit;
  out.weight = {(b - q).cross(c - q).dot(out.unit) / twice_area, (c - q).cross(a - q).dot(out.unit) / twice_area, 0};
  out.weight[2] = 1 - out.weight[0] - out.weight[1];
  return out;
}

}  // namespace

std::vector<SolveContact> CollisionPipeline::mesh_contacts(const std::vector<Vec3>& start, Scalar t, Scalar h,
                                                           Scalar reach, CollisionCounters& counters) {
  Impl& m = *impl_;
  std::vector<SolveContact> out;
  if (m.obstacles.empty()) return out;
  for (int v = 0; v < m.cloth_vertices; ++v) m.start[v] = m.end[v] = start[v];
  m.pose_obstacles(t, h);
  ccd::Candidates c = m.candidates(reach, counters, false);
  // In a whole round's order (feature_pairs' owners leave the tests unsorted): which of several
  // nearly equal contacts is kept depends on it.
  const auto vf_key = [&](const ccd::VertexFacePair& p) {
    const std::array<int, 4> v{p.vertex, p.face[0], p.face[1], p.face[2]};
    return std::make_pair(m.source(v), v);
  };
  const auto ee_key = [&](const ccd::EdgeEdgePair& p) {
    const std::array<int, 4> v{p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]};
    return std::make_pair(m.source(v), v);
  };
  std::sort(c.vertex_face.begin(), c.vertex_face.end(), [&](const auto& a, const auto& b) { return vf_key(a) < vf_key(b); });
  std::sort(c.edge_edge.begin(), c.edge_edge.end(), [&](const auto& a, const auto& b) { return ee_key(a) < ee_key(b); });
  // Per cloth feature (its vertices), its nearest obstacle points in distinct directions.
  std::map<std::array<int, 4>, std::vector<std::pair<Scalar, SolveContact>>> near;
  const auto free = [&](int v) { return v < m.cloth_vertices && m.inverse_mass[std::size_t(v)] > 0; };
  const auto velocity = [&](int v) -> Vec3 { return (m.end[v] - m.start[v]) / h; };
  // offset: from the obstacle's point to the cloth's; obstacle_velocity: of the obstacle's point.
  const auto add = [&](SolveContact contact, const Vec3& offset, const Vec3& obstacle_velocity) {
    const Scalar distance = offset.norm();
    if (!(distance < reach) || !(distance > 0)) return;
    contact.normal = offset / distance;
    contact.distance = distance;
    contact.surface_velocity = obstacle_velocity;
    contact.target = contact.normal.dot(obstacle_velocity);
    std::array<int, 4> key = contact.vertex;
    std::sort(key.begin(), key.end());
    auto& list = near[key];
    for (auto& [d, known] : list)
      if (known.normal.dot(contact.normal) > SAME_DIRECTION) {
        if (distance < d) d = distance, known = contact;
        return;
      }
    list.emplace_back(distance, contact);
  };
  const auto& x = m.start;
  for (const auto& p : c.vertex_face) {
    const auto& f = p.face;
    const auto closest = ccd::closest_point_triangle<Scalar>(x[p.vertex], x[f[0]], x[f[1]], x[f[2]]);
    const Scalar wb = closest.weight_b, wc = closest.weight_c, wa = 1 - wb - wc;
    SolveContact contact;
    if (free(p.vertex)) {  // a cloth vertex and an obstacle's triangle
      contact.vertex = {p.vertex, -1, -1, -1};
      contact.weight = {1, 0, 0, 0};
      add(contact, x[p.vertex] - closest.point, wa * velocity(f[0]) + wb * velocity(f[1]) + wc * velocity(f[2]));
    } else if (p.vertex >= m.cloth_vertices && (free(f[0]) || free(f[1]) || free(f[2]))) {
      // An obstacle's vertex and a cloth triangle (pinned corners allowed), its closest point
      // inside the triangle; or its projection on the triangle's plane within INNER_WEIGHT of
      // an edge, inside the edge: that edge's contact, which the triangles on both sides find
      // alike (beyond INNER_WEIGHT on either side, that side's triangle holds it). It is no
      // edge-edge contact either (its closest point is the end of the obstacle's edges): the
      // support's rim vertices right under the edges of a disc cut from a grid along the
      // support's axes were left to the response, which stopped those edges in every step.
      const std::array<Scalar, 3> w{wa, wb, wc};
      const int on_rim = int(!inner(wa)) + int(!inner(wb)) + int(!inner(wc));
      if (on_rim == 0) {
        contact.vertex = {f[0], f[1], f[2], -1};
        contact.weight = {wa, wb, wc, 0};
        contact.count = 3;
        add(contact, closest.point - x[p.vertex], velocity(p.vertex));
      } else if (on_rim == 1) {
        int k = 0;  // the corner off the edge
        while (inner(w[std::size_t(k)])) ++k;
        const std::size_t ia = std::size_t((k + 1) % 3), ib = std::size_t((k + 2) % 3);
        const int a = f[ia], b = f[ib];
        const auto projection = project_on_plane(x[p.vertex], x[f[0]], x[f[1]], x[f[2]]);
        if ((free(a) || free(b)) && projection && std::abs(projection->weight[std::size_t(k)]) <= INNER_WEIGHT) {
          const bool ordered = a < b;  // one key for the edge from either triangle
          contact.vertex = {ordered ? a : b, ordered ? b : a, -1, -1};
          const Scalar sum = w[ia] + w[ib];
          contact.weight = {(ordered ? w[ia] : w[ib]) / sum, (ordered ? w[ib] : w[ia]) / sum, 0, 0};
          contact.count = 2;
          add(contact, closest.point - x[p.vertex], velocity(p.vertex));
        }
      }
    }
  }
  for (const auto& p : c.edge_edge) {  // edge_a is the cloth's (its indices are the smaller)
    if (!free(p.edge_a[0]) && !free(p.edge_a[1])) continue;  // a pinned end allowed
    const auto closest = ccd::closest_segment_segment<Scalar>(x[p.edge_a[0]], x[p.edge_a[1]], x[p.edge_b[0]], x[p.edge_b[1]]);
    if (!inner(closest.s) || !inner(closest.u)) continue;  // a vertex's contact, found as such
    SolveContact contact;
    contact.vertex = {p.edge_a[0], p.edge_a[1], -1, -1};
    contact.weight = {1 - closest.s, closest.s, 0, 0};
    contact.count = 2;
    add(contact, closest.point_a - closest.point_b,
        (1 - closest.u) * velocity(p.edge_b[0]) + closest.u * velocity(p.edge_b[1]));
  }
  // An edge's or triangle's contact whose every free vertex has its own contact in that
  // direction (a pinned one holds itself) would over-determine the solve (penalties with
  // different targets fighting): dropped.
  std::map<int, std::vector<Vec3>> vertex_normals;
  for (const auto& [key, list] : near)
    for (const auto& [d, contact] : list)
      if (contact.count == 1) vertex_normals[contact.vertex[0]].push_back(contact.normal);
  const auto has_own = [&](int v, const Vec3& normal) {
    const auto found = vertex_normals.find(v);
    if (found == vertex_normals.end()) return false;
    return std::any_of(found->second.begin(), found->second.end(),
                       [&](const Vec3& n) { return n.dot(normal) > SAME_DIRECTION; });
  };
  for (const auto& [key, list] : near)
    for (const auto& [d, contact] : list) {
      bool covered = contact.count > 1;
      for (int i = 0; i < contact.count && covered; ++i) covered = !free(contact.vertex[i]) || has_own(contact.vertex[i], contact.normal);
      if (!covered) out.push_back(contact);
    }
  return out;
}

std::vector<SolveContact> CollisionPipeline::self_contacts(const std::vector<Vec3>& start, Scalar reach,
                                                           CollisionCounters& counters) {
  Impl& m = *impl_;
  std::vector<SolveContact> out;
  if (!m.model.scene.collisions.self) return out;
  for (int v = 0; v < m.cloth_vertices; ++v) m.start[v] = m.end[v] = start[v];
  const Scalar thickness = m.model.scene.collisions.thickness;
  const ccd::Candidates c = m.candidates(reach * thickness, counters, true, {}, false);
  const auto free = [&](int v) { return v < m.cloth_vertices && m.inverse_mass[std::size_t(v)] > 0; };
  struct Near {
    Contact contact;
    Scalar distance;
    Scalar inside;  // a vertex and a face: the projection's least weight (inside the face: > 0)
  };
  std::vector<Near> near;
  // A vertex over a triangle (its projection on the triangle's plane inside it, or within
  // INNER_WEIGHT of its rim) is held along the triangle's normal, by the projection's weights
  // (Bridson, Fedkiw and Anderson 2002, section 7.1); two edges only where their closest
  // points lie inside both and they cross (their common perpendicular). A pair's closest
  // points at a feature's rim give a normal tilted towards the rim, along which a layer
  // sliding over another closes: held in the solve, such pairs stopped a cloth sliding on
  // another at once, and left the vertices over the rims to the response, whose impulses the
  // held ones then carried through the springs.
  const auto add = [&](bool vertex_face, Contact contact, const Vec3& offset, Scalar inside) {
    if (!std::all_of(contact.vertex.begin(), contact.vertex.end(), free)) return;  // a pinned side is the response's
    const Scalar distance = offset.norm();
    if (!(distance < reach * thickness) || !(distance > 0)) return;
    if (!(distance < reach * m.kept_gap(vertex_face, contact.vertex, counters))) return;
    contact.vertex_face = vertex_face;
    contact.normal = offset / distance;
    near.push_back({contact, distance, inside});
  };
  const auto& x = m.start;
  for (const auto& p : c.vertex_face) {
    const auto projection = project_on_plane(x[p.vertex], x[p.face[0]], x[p.face[1]], x[p.face[2]]);
    if (!projection) continue;
    std::array<Scalar, 3> w = projection->weight;
    const Scalar inside = *std::min_element(w.begin(), w.end());
    if (!(inside > -INNER_WEIGHT)) continue;
    Scalar sum = 0;
    for (Scalar& v : w) sum += v = std::max<Scalar>(v, 0);
    for (Scalar& v : w) v /= sum;
    Contact contact;
    contact.vertex = {p.vertex, p.face[0], p.face[1], p.face[2]};
    contact.weight = {1, -w[0], -w[1], -w[2]};
    add(true, contact, projection->height * projection->unit, inside);
  }
  for (const auto& p : c.edge_edge) {
    const auto closest = ccd::closest_segment_segment<Scalar>(x[p.edge_a[0]], x[p.edge_a[1]], x[p.edge_b[0]], x[p.edge_b[1]]);
    if (!inner(closest.s) || !inner(closest.u)) continue;
    const Vec3 da = x[p.edge_a[1]] - x[p.edge_a[0]], db = x[p.edge_b[1]] - x[p.edge_b[0]];
    // Nearly parallel edges have no common perpendicular: their vertices' contacts hold them.
    if (!(da.cross(db).squaredNorm() > SELF_EDGE_CROSSING * SELF_EDGE_CROSSING * da.squaredNorm() * db.squaredNorm())) continue;
    Contact contact;
    contact.vertex = {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]};
    contact.weight = {1 - closest.s, closest.s, -(1 - closest.u), -closest.u};
    add(false, contact, closest.point_a - closest.point_b, 0);
  }
  // The tests come unsorted (feature_pairs' owners): the contacts in a whole round's order.
  std::sort(near.begin(), near.end(), [&](const Near& a, const Near& b) { return m.listed_before(a.contact, b.contact); });
  // A vertex over the faces around a mesh vertex or edge lies within INNER_WEIGHT of each: it
  // is held once in a direction, by the face its projection lies most inside. Held by every
  // such face, with weights a rounding apart, the penalties fought (some pushing, some
  // pulling), and a cloth lifted off another by its edge took the one under it along.
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < near.size(); ++k)
    if (near[k].contact.vertex_face) order.push_back(k);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Near &p = near[a], &q = near[b];
    return p.contact.vertex[0] != q.contact.vertex[0] ? p.contact.vertex[0] < q.contact.vertex[0] : p.inside > q.inside;
  });
  std::vector<char> dropped(near.size(), 0);
  for (std::size_t begin = 0, end = 0; begin < order.size(); begin = end) {
    for (end = begin; end < order.size() && near[order[end]].contact.vertex[0] == near[order[begin]].contact.vertex[0];) ++end;
    for (std::size_t i = begin; i < end; ++i)
      for (std::size_t j = begin; j < i && !dropped[order[i]]; ++j)
        if (!dropped[order[j]] && near[order[j]].contact.normal.dot(near[order[i]].contact.normal) > SAME_DIRECTION) dropped[order[i]] = 1;
  }
  out.reserve(near.size());
  for (std::size_t k = 0; k < near.size(); ++k) {
    if (dropped[k]) continue;
    const Contact& n = near[k].contact;
    const Scalar distance = near[k].distance;
    SolveContact contact;
    contact.vertex = n.vertex;
    contact.weight = n.weight;
    contact.count = 4;
    contact.normal = n.normal;
    contact.distance = distance;
    contact.self = true;
    out.push_back(contact);
  }
  return out;
}

}  // namespace drape
