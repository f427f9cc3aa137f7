#include "drape/core/obstacle.h"

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

}  // namespace drape
