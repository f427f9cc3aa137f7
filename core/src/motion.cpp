#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "drape/core/scene.h"

// The scene's placements and scripted rigid motions (of handles and obstacles).
namespace drape {

Vec3 Transform::apply(const Vec3& x) const {
  const Scalar radians = rotate_degrees * M_PI / 180.0;
  return Eigen::AngleAxis<Scalar>(radians, rotate_axis.normalized()) * (scale * x) + translate;
}

namespace {

Eigen::Matrix<Scalar, 3, 3> rotation(const Vec3& angular_velocity, Scalar duration) {
  const Scalar rate = angular_velocity.norm();
  if (rate == 0) return Eigen::Matrix<Scalar, 3, 3>::Identity();
  return Eigen::AngleAxis<Scalar>(rate * duration, angular_velocity / rate).toRotationMatrix();
}

}  // namespace

Vec3 Motion::position(const Vec3& x, Scalar t) const {
  const Scalar tau = std::clamp(t, start, end) - start;
  if (!(tau > 0)) return x;
  return center + velocity * tau + rotation(angular_velocity, tau) * (x - center);
}

Vec3 Motion::velocity_at(const Vec3& x, Scalar t) const {
  if (t < start || t >= end) return Vec3::Zero();
  const Scalar tau = t - start;
  const Vec3 centre_now = center + velocity * tau;
  return velocity + angular_velocity.cross(position(x, t) - centre_now);
}

}  // namespace drape
