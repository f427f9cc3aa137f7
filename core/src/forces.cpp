#include "drape/core/forces.h"

namespace drape {

SpringEvaluation evaluate_spring(const Vec3& xi, const Vec3& xj, const Vec3& vi, const Vec3& vj, Scalar rest_length,
                                 Scalar stiffness, Scalar damping, Scalar compression) {
  SpringEvaluation out;
  const Vec3 delta = xi - xj;
  const Scalar length = delta.norm();
  out.length = length;
  if (!(length > 0)) return out;  // coincident particles: no direction, no force
  const Vec3 d = delta / length;
  const Scalar stretch = length - rest_length;
  stiffness = spring_constant(stiffness, stretch, compression);
  const Mat3 ddT = d * d.transpose();
  out.energy = 0.5 * stiffness * stretch * stretch;
  out.force = -stiffness * stretch * d - damping * (vi - vj).dot(d) * d;
  const Scalar transverse = std::max<Scalar>(0, 1 - rest_length / length);  // dropped in compression
  out.d_force_d_x = -stiffness * (ddT + transverse * (Mat3::Identity() - ddT));
  out.d_force_d_v = -damping * ddT;
  return out;
}

}  // namespace drape
