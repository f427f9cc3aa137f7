#include "drape/core/obstacle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>

#include "drape/ccd/distance.h"

namespace drape {

namespace {
// m: how far a box may lie beyond the nearest triangle found and still be searched, as its
// distance and the triangle's are both rounded (about 1e-16 of the coordinates: a nanometre
// covers scenes up to a million metres across).
constexpr Scalar BOX_DISTANCE_SLACK = 1e-9;
}  // namespace

Vec3 body_velocity(const Motion& motion, const Vec3& x_now, Scalar t) {
  if (t < motion.start || t >= motion.end) return Vec3::Zero();
  const Vec3 centre_now = motion.center + motion.velocity * (t - motion.start);
  return motion.velocity + motion.angular_velocity.cross(x_now - centre_now);
}

PosedShape pose_shape(const Obstacle& obstacle, Scalar t) {
  const ObstacleSpec& s = obstacle.spec;
  if (s.kind == ObstacleSpec::Kind::Sphere) return {&obstacle, true, s.motion.position(s.center, t), Vec3::UnitZ(), s.radius};
  const Vec3 point = s.motion.position(s.point, t);
  return {&obstacle, false, point, (s.motion.position(s.point + s.normal, t) - point).normalized(), 0};
}

SurfaceContact analytic_contact(const PosedShape& shape, Scalar t, const Vec3& x) {
  SurfaceContact out;
  std::tie(out.signed_distance, out.normal) = shape.distance(x);
  out.surface_velocity = body_velocity(shape.obstacle->spec.motion, x - out.signed_distance * out.normal, t);
  return out;
}


std::vector<Vec3> posed_vertices(const Obstacle& obstacle, Scalar t) {
  std::vector<Vec3> out;
  out.reserve(obstacle.mesh.vertices.size());
  for (const Vec3& v : obstacle.mesh.vertices) out.push_back(obstacle.spec.motion.position(v, t));
  return out;
}

Scalar distance_to_obstacle(const Obstacle& obstacle, Scalar t, const std::vector<Vec3>& points) {
  Scalar best = std::numeric_limits<Scalar>::infinity();
  if (obstacle.spec.kind != ObstacleSpec::Kind::Mesh) {
    const PosedShape shape = pose_shape(obstacle, t);
    for (const Vec3& p : points) best = std::min(best, shape.distance(p).first);
    return best;
  }
  // Every point against every triangle cost a Cusick drape's frame 7 %: a point or triangle
  // whose box lies farther than the nearest found so far is skipped. The box's distance is a
  // lower bound of the triangle's, up to rounding, which BOX_DISTANCE_SLACK covers: the
  // minimum is the same number as from every pair.
  const std::vector<Vec3> v = posed_vertices(obstacle, t);
  const auto box_distance_squared = [](const Vec3& p, const Vec3& lo, const Vec3& hi) {
    return (lo - p).cwiseMax(p - hi).cwiseMax(0).squaredNorm();
  };
  Scalar reach2 = best;  // the squared distance within which a box is searched
  const auto beyond = [&](Scalar d2) { return d2 > reach2; };
  std::vector<std::array<Vec3, 2>> boxes;
  boxes.reserve(obstacle.mesh.triangles.size());
  Vec3 lo = Vec3::Constant(std::numeric_limits<Scalar>::infinity()), hi = -lo;
  for (const Triangle& tri : obstacle.mesh.triangles) {
    const Vec3 a = v[tri[0]].cwiseMin(v[tri[1]]).cwiseMin(v[tri[2]]), b = v[tri[0]].cwiseMax(v[tri[1]]).cwiseMax(v[tri[2]]);
    boxes.push_back({a, b});
    lo = lo.cwiseMin(a), hi = hi.cwiseMax(b);
  }
  for (const Vec3& p : points) {
    if (beyond(box_distance_squared(p, lo, hi))) continue;
    for (std::size_t k = 0; k < boxes.size(); ++k) {
      if (beyond(box_distance_squared(p, boxes[k][0], boxes[k][1]))) continue;
      const Triangle& tri = obstacle.mesh.triangles[k];
      const Scalar d2 = ccd::closest_point_triangle<Scalar>(p, v[tri[0]], v[tri[1]], v[tri[2]]).distance_squared;
      if (d2 < best) best = d2, reach2 = (std::sqrt(d2) + BOX_DISTANCE_SLACK) * (std::sqrt(d2) + BOX_DISTANCE_SLACK);
    }
  }
  return std::sqrt(best);
}

std::optional<SurfaceContact> push_out(const PosedShape& shape, Scalar t_next, const Vec3& start, Scalar h, Scalar depth,
                                       Vec3& motion) {
  const Vec3 predicted = start + h * motion;
  if (!(shape.distance(predicted).first < depth)) return std::nullopt;
  const SurfaceContact c = analytic_contact(shape, t_next, predicted);
  motion = (predicted + (depth - c.signed_distance) * c.normal - start) / h;
  return c;
}

namespace {

// Sweeps over the triangles against a sphere, each pushing out the faces it reaches, until one
// moves none: neighbouring faces share corners, and a push may bring the next face back in.
constexpr int FACE_SWEEPS = 8;

// A face's push is made only where the corners that may move hold at least this much of the
// point's weight: at most twice the point's change for one free corner.
constexpr Scalar MIN_FREE_WEIGHT = 0.5;

// A face within this fraction of the depth short of it is not pushed (what a push leaves by
// rounding; pushed again, a face resting on a sphere counted twice a step and ran every sweep).
constexpr Scalar FACE_PUSH_TOLERANCE = 1e-6;

// The projection's friction on one cloth point's motion and velocity (the point in contact:
// a vertex, or a triangle's closest point to a sphere, by its weights), changed in place: from
// the normal change the projection made to the motion (pushed, m/s), Coulomb friction on the
// motion's slide relative to the surface; the velocity loses its approaching normal part and
// feels Coulomb friction from that.
void projection_friction(const SurfaceContact& c, Scalar mu, Scalar pushed, Vec3& motion, Vec3& velocity) {
  // Friction on the motion too: without it the projection slides a vertex along the surface
  // by the tangential part of its whole step (a cloth landing on a sphere spread outward, its
  // springs stretched: energy grew).
  const Vec3 slide = motion - c.surface_velocity;
  const Vec3 slide_tangential = slide - slide.dot(c.normal) * c.normal;
  const Scalar slide_speed = slide_tangential.norm();
  if (slide_speed > 0 && pushed > 0) motion -= slide_tangential * std::min<Scalar>(1, mu * pushed / slide_speed);
  const Vec3 relative = velocity - c.surface_velocity;
  const Scalar normal_speed = relative.dot(c.normal);
  if (normal_speed >= 0) return;  // already separating
  Vec3 tangential = relative - normal_speed * c.normal;
  const Scalar speed = tangential.norm();
  if (speed > 0) tangential *= std::max<Scalar>(0, 1 - mu * -normal_speed / speed);
  velocity = c.surface_velocity + tangential;
}

// A sphere between a cloth triangle's corners (all of them outside it): the triangle's
// closest point to the centre at the step's end, when it lies within depth of the surface
// (outside the corners: theirs are the vertex projection's), moves out to depth along the
// direction from the centre, its corners sharing the change by weight and inverse mass as an
// impulse would (Bridson, Fedkiw and Anderson 2002, section 7.2); friction as a vertex's.
// The side is the one the point was on at the step's start. Returns whether it moved.
bool push_face_out(const Model& model, const PosedShape& at_start, const PosedShape& shape, Scalar t_next,
                   const std::vector<Vec3>& start, Scalar h, Scalar depth, Scalar friction, const Triangle& tri,
                   std::vector<Vec3>& motion, std::vector<Vec3>* velocities) {
  std::array<Vec3, 3> end;
  std::array<Scalar, 3> inverse_mass{};
  Scalar longest = 0;
  for (int k = 0; k < 3; ++k) {
    const std::size_t v = std::size_t(tri[k]);
    end[k] = start[v] + h * motion[v];
    if (model.pin_of_vertex[v] < 0) inverse_mass[k] = 1 / model.masses[v];
  }
  for (int k = 1; k < 3; ++k) longest = std::max(longest, (end[k] - end[0]).norm());
  const Scalar reach = shape.radius + depth;
  if ((end[0] - shape.point).norm() - longest >= reach) return false;  // every point of it is farther
  const auto closest = ccd::closest_point_triangle<Scalar>(shape.point, end[0], end[1], end[2]);
  const std::array<Scalar, 3> w{1 - closest.weight_b - closest.weight_c, closest.weight_b, closest.weight_c};
  if (!(closest.distance_squared < reach * reach) || std::max({w[0], w[1], w[2]}) >= 1) return false;
  Scalar share = 0;  // sum w_k^2 / m_k
  Scalar free_weight = 0;  // of the corners that may move
  for (int k = 0; k < 3; ++k) {
    share += w[k] * w[k] * inverse_mass[k];
    if (inverse_mass[k] > 0) free_weight += w[k];
  }
  // A point nearer a triangle's pinned corners than its free ones is the handle's to hold: the
  // free corners would move 1 / free_weight times as far as the point (a lever).
  if (!(share > 0) || free_weight < MIN_FREE_WEIGHT) return false;
  // The side: the closest point's at the start, from the centre then.
  const auto before = ccd::closest_point_triangle<Scalar>(at_start.point, start[std::size_t(tri[0])],
                                                          start[std::size_t(tri[1])], start[std::size_t(tri[2])]);
  const Vec3 side = before.point - at_start.point;
  Vec3 offset = closest.point - shape.point;
  const Scalar distance = offset.norm();
  Vec3 normal = distance > 0 ? Vec3(offset / distance) : Vec3(side.normalized());
  if (!(normal.squaredNorm() > 0.5)) return false;  // the centre on the triangle at both ends: no side
  if (normal.dot(side) < 0) normal = -normal;
  const Scalar along = offset.dot(normal);  // negative where the centre crossed the triangle
  // What the last push left within rounding of the depth is not pushed again.
  if (!(reach - along > FACE_PUSH_TOLERANCE * depth)) return false;
  const Scalar push = (reach - along) / h;  // the closest point's normal motion change, m/s
  if (!std::isfinite(push)) return false;
  SurfaceContact c;
  c.signed_distance = along - shape.radius;
  c.normal = normal;
  c.surface_velocity = body_velocity(shape.obstacle->spec.motion, shape.point + shape.radius * normal, t_next);
  Vec3 point_motion = Vec3::Zero(), point_velocity = Vec3::Zero();
  for (int k = 0; k < 3; ++k) point_motion += w[k] * motion[std::size_t(tri[k])];
  const Vec3 motion_before = point_motion;
  point_motion += push * normal;
  Vec3 velocity_change = Vec3::Zero();
  if (velocities) {
    for (int k = 0; k < 3; ++k) point_velocity += w[k] * (*velocities)[std::size_t(tri[k])];
    const Vec3 velocity_before = point_velocity;
    projection_friction(c, friction, push, point_motion, point_velocity);
    velocity_change = point_velocity - velocity_before;
  }
  const Vec3 motion_change = point_motion - motion_before;
  // The point's change d is made by corner changes w_k / m_k * d / share.
  for (int k = 0; k < 3; ++k) {
    const std::size_t v = std::size_t(tri[k]);
    const Scalar part = w[k] * inverse_mass[k] / share;
    motion[v] += part * motion_change;
    if (velocities) (*velocities)[v] += part * velocity_change;
  }
  return true;
}

}  // namespace

int keep_out_of_analytic_obstacles(const Model& model, const std::vector<Vec3>& start, Scalar t_next, Scalar h,
                                   Scalar depth, Scalar friction, std::vector<Vec3>& motion, std::vector<Vec3>* velocities) {
  int contacts = 0;
  for (const Obstacle& obstacle : model.obstacles) {
    if (obstacle.spec.kind == ObstacleSpec::Kind::Mesh) continue;  // the collision pipeline's
    const PosedShape shape = pose_shape(obstacle, t_next);
    for (std::size_t v = 0; v < model.vertex_count(); ++v) {
      if (model.pin_of_vertex[v] >= 0) continue;
      const Vec3 before = motion[v];
      const auto contact = push_out(shape, t_next, start[v], h, depth, motion[v]);
      if (!contact) continue;
      ++contacts;
      if (!velocities) continue;
      projection_friction(*contact, friction, (motion[v] - before).dot(contact->normal), motion[v], (*velocities)[v]);
    }
    // A sphere can pass between the corners of a triangle; a plane cannot (a triangle's
    // deepest point below it is a corner). Sweeps, since neighbouring faces share corners.
    if (!shape.sphere) continue;
    const PosedShape at_start = pose_shape(obstacle, t_next - h);
    std::vector<char> pushed(model.triangles.size(), 0);  // each face counted once
    for (int sweep = 0; sweep < FACE_SWEEPS; ++sweep) {
      bool moved = false;
      for (std::size_t f = 0; f < model.triangles.size(); ++f)
        if (push_face_out(model, at_start, shape, t_next, start, h, FACE_DEPTH_FRACTION * depth, friction, model.triangles[f],
                          motion, velocities)) {
          moved = true;
          contacts += !pushed[f];
          pushed[f] = 1;
        }
      if (!moved) break;
    }
  }
  return contacts;
}

}  // namespace drape
