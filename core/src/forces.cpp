#include "drape/core/forces.h"

#include <Eigen/Eigenvalues>

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

namespace {

using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
using Mat32 = Eigen::Matrix<Scalar, 3, 2>;

// The corners' shape gradients: F = sum_i x_i g_i^T.
std::array<Vec2, 3> shape_gradients(const MembraneMaterial& m) {
  const Vec2 g1 = m.rest_inverse.row(0).transpose(), g2 = m.rest_inverse.row(1).transpose();
  return {-g1 - g2, g1, g2};
}

Mat32 gradient_of(const std::array<Vec2, 3>& g, const std::array<Vec3, 3>& x) {
  Mat32 f = Mat32::Zero();
  for (std::size_t i = 0; i < 3; ++i) f += x[i] * g[i].transpose();
  return f;
}

// The second Piola-Kirchhoff stress of a (symmetric) strain e.
Mat2 stress_of(const MembraneMaterial& m, const Mat2& e) {
  Mat2 s;
  s(0, 0) = m.c11 * e(0, 0) + m.c12 * e(1, 1);
  s(1, 1) = m.c12 * e(0, 0) + m.c22 * e(1, 1);
  s(0, 1) = s(1, 0) = 2 * m.c66 * e(0, 1);
  return s;
}

Mat2 green_strain(const Mat32& f) { return 0.5 * (f.transpose() * f - Mat2::Identity()); }

}  // namespace

Scalar membrane_energy(const MembraneMaterial& m, const std::array<Vec3, 3>& x) {
  const Mat2 e = green_strain(gradient_of(shape_gradients(m), x));
  return 0.5 * m.area * (e.cwiseProduct(stress_of(m, e))).sum();
}

MembraneEvaluation evaluate_membrane(const MembraneMaterial& m, const std::array<Vec3, 3>& x, const std::array<Vec3, 3>& v) {
  MembraneEvaluation out;
  const std::array<Vec2, 3> g = shape_gradients(m);
  const Mat32 f = gradient_of(g, x), f_dot = gradient_of(g, v);
  const Mat2 e = green_strain(f);
  const Mat2 e_dot = 0.5 * (f.transpose() * f_dot + f_dot.transpose() * f);
  const Mat2 s = stress_of(m, e);
  out.energy = 0.5 * m.area * e.cwiseProduct(s).sum();
  const Mat32 p = m.area * f * (s + m.damping * stress_of(m, e_dot));  // area times the first Piola-Kirchhoff stress
  for (std::size_t i = 0; i < 3; ++i) out.force[i] = -p * g[i];
  // The stress term area (g_i^T S g_j) I with the stress's positive part.
  const Eigen::SelfAdjointEigenSolver<Mat2> eigen(s);
  const Vec2 positive = eigen.eigenvalues().cwiseMax(0);
  const Mat2 s_plus = eigen.eigenvectors() * positive.asDiagonal() * eigen.eigenvectors().transpose();
  // The material term: moving x_j along axis k changes E by sym(f_k g_j^T) (f_k: row k of F),
  // the stress by C of it, and the force on i by -area F dS g_i.
  for (std::size_t j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) {
      const Vec2 fk = f.row(k).transpose();
      const Mat2 de_half = fk * g[j].transpose();
      const Mat2 ds = stress_of(m, 0.5 * (de_half + de_half.transpose()));
      const Mat32 fds = m.area * f * ds;
      for (std::size_t i = 0; i < 3; ++i) {
        const Vec3 column = fds * g[i];
        out.d_force_d_x[i][j].col(k) = -column;
        out.d_force_d_v[i][j].col(k) = -m.damping * column;
      }
    }
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      out.d_force_d_x[i][j] -= m.area * g[i].dot(s_plus * g[j]) * Mat3::Identity();
  return out;
}

}  // namespace drape
