#include <algorithm>
#include <cmath>

#include "collision_pipeline.h"
#include "drape/ccd/distance.h"
#include "drape/core/obstacle.h"

namespace drape {

int CollisionPipeline::Impl::impulses(ContactSet& set, Scalar h, std::vector<Vec3>& motion) const {
  const auto apply = [&](std::size_t i, const Vec3& change) {
    const Contact& c = set.contacts[i];
    for (int k = 0; k < 4; ++k)
      if (c.vertex[k] < cloth_vertices) motion[c.vertex[k]] += c.weight[k] * inverse_mass[c.vertex[k]] / set.denominator[i] * change;
  };
  const Scalar tolerance = IMPULSE_TOLERANCE * model.scene.collisions.thickness / h;
  for (int sweep = 0; sweep < IMPULSE_SWEEPS; ++sweep) {
    Scalar largest = 0;
    for (std::size_t i = 0; i < set.contacts.size(); ++i) {
      if (!(set.denominator[i] > 0)) continue;
      const Contact& c = set.contacts[i];
      const Scalar change = std::max<Scalar>(-set.pushed[i], set.target[i] - relative_velocity(c, h, motion).dot(c.normal));
      // A contact starts pushing only for an approach beyond the tolerance: a resting contact
      // that the solve held approaches by rounding, and an impulse there would set off the
      // response's re-solve for nothing.
      if (change == 0 || (set.pushed[i] == 0 && change < tolerance)) continue;
      set.pushed[i] += change;
      largest = std::max(largest, std::abs(change));
      apply(i, change * c.normal);
    }
    if (!(largest > tolerance)) break;
  }
  int count = 0;
  for (std::size_t i = 0; i < set.contacts.size(); ++i) {
    if (!(set.pushed[i] > 0)) continue;
    ++count;
    const Contact& c = set.contacts[i];
    const Vec3 relative = relative_velocity(c, h, motion);
    const Vec3 tangential = relative - relative.dot(c.normal) * c.normal;
    const Scalar slide = tangential.norm();
    const Scalar rub = std::min(friction * set.pushed[i] - set.rubbed[i], slide);
    if (!(rub > 0)) continue;
    set.rubbed[i] += rub;
    apply(i, -rub * tangential / slide);
  }
  return count;
}

Contact CollisionPipeline::Impl::contact(bool vertex_face, const std::array<int, 4>& v, const ccd::Result& hit) const {
  const auto at = [&](int k, Scalar s) -> Vec3 { return start[v[k]] + s * (end[v[k]] - start[v[k]]); };
  const Scalar toc = hit.toc;
  Contact c;
  c.vertex_face = vertex_face;
  c.vertex = v;
  if (vertex_face) {
    const Scalar wb = hit.params[0], wc = hit.params[1];
    c.weight = {1, -(1 - wb - wc), -wb, -wc};
    Vec3 n = (at(2, toc) - at(1, toc)).cross(at(3, toc) - at(1, toc));
    const Vec3 offset_at_start = at(0, 0) - ccd::closest_point_triangle<Scalar>(at(0, 0), at(1, 0), at(2, 0), at(3, 0)).point;
    if (!(n.norm() > 0)) n = offset_at_start;
    if (n.dot(offset_at_start) < 0) n = -n;
    c.normal = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::UnitZ();
  } else {
    const Scalar s = hit.params[0], u = hit.params[1];
    c.weight = {1 - s, s, -(1 - u), -u};
    Vec3 n = (at(1, toc) - at(0, toc)).cross(at(3, toc) - at(2, toc));
    const auto at_start = ccd::closest_segment_segment<Scalar>(at(0, 0), at(1, 0), at(2, 0), at(3, 0));
    const Vec3 offset_at_start = at_start.point_a - at_start.point_b;
    if (!(n.squaredNorm() > 1e-12 * (at(1, toc) - at(0, toc)).squaredNorm() * (at(3, toc) - at(2, toc)).squaredNorm()))
      n = offset_at_start;
    if (n.dot(offset_at_start) < 0) n = -n;
    c.normal = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::UnitZ();
  }
  return c;
}

void CollisionPipeline::Impl::keep_out_of_analytic_obstacles(Scalar t_next, Scalar h, std::vector<Vec3>& motion) const {
  if (!model.scene.collisions.obstacles) return;
  drape::keep_out_of_analytic_obstacles(model, start, t_next, h, ANALYTIC_KEEP_OUT * model.scene.collisions.thickness, 0,
                                        motion, nullptr);
}

Scalar CollisionPipeline::Impl::kept_gap(bool vertex_face, const std::array<int, 4>& v, CollisionCounters& counters) const {
  const Scalar thickness = model.scene.collisions.thickness;
  for (int k = 0; k < 4; ++k)
    if (v[k] >= cloth_vertices || cloth_of_vertex[std::size_t(v[k])] != cloth_of_vertex[std::size_t(v[0])]) return thickness;
  const auto& r = model.initial_positions;
  const auto p = [&](int k) -> const Vec3& { return r[std::size_t(v[k])]; };
  const Scalar rest_squared = vertex_face ? ccd::closest_point_triangle<Scalar>(p(0), p(1), p(2), p(3)).distance_squared
                                          : ccd::closest_segment_segment<Scalar>(p(0), p(1), p(2), p(3)).distance_squared;
  const Scalar f = REST_FRACTION;
  if (f * f * rest_squared >= thickness * thickness) return thickness;
  ++counters.rest_clamped_pairs;
  return f * std::sqrt(rest_squared);
}

std::vector<Contact> CollisionPipeline::Impl::near_contacts(const ccd::Candidates& c, CollisionCounters& counters,
                                                            std::vector<std::array<int, 4>>* clamped) const {
  const Scalar thickness = model.scene.collisions.thickness;
  std::vector<Contact> near;
  const auto push = [&](bool vertex_face, Contact contact, const Vec3& offset) {
    const Scalar distance = offset.norm();
    if (!(distance < thickness) || !(distance > 0)) return;
    const long clamped_before = counters.rest_clamped_pairs;
    const Scalar gap = kept_gap(vertex_face, contact.vertex, counters);
    if (clamped && counters.rest_clamped_pairs != clamped_before) clamped->push_back(contact.vertex);
    if (!(distance < gap)) return;
    contact.vertex_face = vertex_face;
    contact.normal = offset / distance;
    near.push_back(contact);
  };
  for (const auto& p : c.vertex_face) {
    const auto closest = ccd::closest_point_triangle<Scalar>(start[p.vertex], start[p.face[0]], start[p.face[1]], start[p.face[2]]);
    Contact contact;
    contact.vertex = {p.vertex, p.face[0], p.face[1], p.face[2]};
    contact.weight = {1, -(1 - closest.weight_b - closest.weight_c), -closest.weight_b, -closest.weight_c};
    push(true, contact, start[p.vertex] - closest.point);
  }
  for (const auto& p : c.edge_edge) {
    const auto closest = ccd::closest_segment_segment<Scalar>(start[p.edge_a[0]], start[p.edge_a[1]], start[p.edge_b[0]], start[p.edge_b[1]]);
    Contact contact;
    contact.vertex = {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]};
    contact.weight = {1 - closest.s, closest.s, -(1 - closest.u), -closest.u};
    push(false, contact, closest.point_a - closest.point_b);
  }
  // The tests come unsorted (feature_pairs' owners): the contacts in a whole round's order.
  std::sort(near.begin(), near.end(), [&](const Contact& a, const Contact& b) { return listed_before(a, b); });
  return near;
}

void CollisionPipeline::Impl::repel(const std::vector<Contact>& near, Scalar h, std::vector<Vec3>& motion, ContactSet& set,
                                    CollisionCounters& counters) {
  for (const Contact& contact : near) set.add(contact, 0, inverse_mass);
  counters.proximity_impulses += impulses(set, h, motion);
}

void CollisionPipeline::Impl::apply_zones(Zones& zones, Scalar h, std::vector<Vec3>& motion, CollisionCounters& counters) {
  std::vector<std::vector<int>> members(start.size());
  for (int v = 0; v < int(start.size()); ++v) members[zones.find(v)].push_back(v);
  for (const auto& zone : members) {
    if (zone.size() < 2) continue;
    ++counters.impact_zones;
    Vec3 kinematic_velocity = Vec3::Zero();
    int kinematic = 0;
    Scalar mass = 0;
    Vec3 momentum = Vec3::Zero(), centre = Vec3::Zero();
    for (int v : zone) {
      if (inverse_mass[v] == 0) {
        kinematic_velocity += velocity(v, h, motion);
        ++kinematic;
        continue;
      }
      const Scalar m = 1 / inverse_mass[v];
      mass += m;
      momentum += m * motion[v];
      centre += m * start[v];
    }
    if (kinematic > 0) {
      for (int v : zone)
        if (v < cloth_vertices && inverse_mass[v] > 0) motion[v] = kinematic_velocity / kinematic;
      continue;
    }
    centre /= mass;
    const Vec3 linear = momentum / mass;
    Vec3 angular_momentum = Vec3::Zero();
    Mat3 inertia = Mat3::Zero();
    for (int v : zone) {
      const Scalar m = 1 / inverse_mass[v];
      const Vec3 r = start[v] - centre;
      angular_momentum += m * r.cross(motion[v] - linear);
      inertia += m * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
    }
    const Vec3 omega = inertia.completeOrthogonalDecomposition().solve(angular_momentum);
    for (int v : zone) motion[v] = linear + omega.cross(start[v] - centre);
  }
}

}  // namespace drape
