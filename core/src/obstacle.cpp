#include "drape/core/obstacle.h"

#include <algorithm>
#include <limits>
#include <tuple>

#include "drape/ccd/distance.h"

namespace drape {

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
  const std::vector<Vec3> v = posed_vertices(obstacle, t);
  for (const Vec3& p : points) {
    for (const Triangle& tri : obstacle.mesh.triangles)
      best = std::min(best, ccd::closest_point_triangle<Scalar>(p, v[tri[0]], v[tri[1]], v[tri[2]]).distance_squared);
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

int keep_out_of_analytic_obstacles(const Model& model, const std::vector<Vec3>& start, Scalar t_next, Scalar h,
                                   Scalar depth, std::vector<Vec3>& motion, std::vector<Vec3>* velocities) {
  const Scalar mu = model.scene.friction;
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
      const SurfaceContact& c = *contact;
      // Friction on the motion too, from the normal change the projection made: without it
      // the projection slides a vertex along the surface by the tangential part of its whole
      // step (a cloth landing on a sphere spread outward, its springs stretched: energy grew).
      const Scalar pushed = (motion[v] - before).dot(c.normal);
      const Vec3 slide = motion[v] - c.surface_velocity;
      const Vec3 slide_tangential = slide - slide.dot(c.normal) * c.normal;
      const Scalar slide_speed = slide_tangential.norm();
      if (slide_speed > 0 && pushed > 0) motion[v] -= slide_tangential * std::min<Scalar>(1, mu * pushed / slide_speed);
      Vec3& velocity = (*velocities)[v];
      const Vec3 relative = velocity - c.surface_velocity;
      const Scalar normal_speed = relative.dot(c.normal);
      if (normal_speed >= 0) continue;  // already separating
      Vec3 tangential = relative - normal_speed * c.normal;
      const Scalar speed = tangential.norm();
      if (speed > 0) tangential *= std::max<Scalar>(0, 1 - mu * -normal_speed / speed);
      velocity = c.surface_velocity + tangential;
    }
  }
  return contacts;
}

}  // namespace drape
