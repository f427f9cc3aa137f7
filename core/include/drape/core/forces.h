#pragma once
/// \file
/// Spring and membrane forces and their Jacobians: pure functions over two particles (a
/// spring) or three (a triangle of membrane).

#include <array>

#include <Eigen/Core>

#include "drape/ccd/types.h"

namespace drape {

using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
using Mat2 = Eigen::Matrix<Scalar, 2, 2>;

/// One spring between particles i and j, seen from i (the force on j is the opposite, and the
/// Jacobian blocks are K for (i,i) and (j,j), -K for (i,j) and (j,i)).
struct SpringEvaluation {
  Vec3 force = Vec3::Zero();     ///< on i: elastic -k (l - L) d + damping -c ((vi - vj) . d) d
  Mat3 d_force_d_x = Mat3::Zero();  ///< d force / d x_i of the elastic part, made negative semi-definite
  Mat3 d_force_d_v = Mat3::Zero();  ///< d force / d v_i = -c d d^T
  Scalar energy = 0;                ///< 0.5 k (l - L)^2
  Scalar length = 0;                ///< current length l
};

/// Elastic spring of rest length L, constant k, damping c, d the unit vector from j to i.
///
/// The exact stiffness is -k [d d^T + (1 - L/l)(I - d d^T)]. Under compression (l < L) its
/// second term is positive and the system matrix M - h dF/dv - h^2 dF/dx can lose definiteness;
/// as in Choi and Ko, "Stable but responsive cloth" (SIGGRAPH 2002, section 5), that term is
/// dropped when l < L, which keeps the matrix symmetric positive definite. In tension the
/// Jacobian is exact. The damping force's dependence on x is neglected (Baraff and Witkin 1998).
/// In compression the constant is compression k (Material::compression; 1: a linear spring).
SpringEvaluation evaluate_spring(const Vec3& xi, const Vec3& xj, const Vec3& vi, const Vec3& vj, Scalar rest_length,
                                 Scalar stiffness, Scalar damping, Scalar compression = 1);

/// A spring's constant at a stretch (length - rest length): compression k when compressed.
inline Scalar spring_constant(Scalar stiffness, Scalar stretch, Scalar compression) {
  return stretch < 0 ? stiffness * compression : stiffness;
}

/// One triangle of a fabric's membrane as a constant strain element (Material::membrane_triangles):
/// orthotropic Saint Venant-Kirchhoff in the fabric's warp (1) and weft (2) directions, strain
/// energy area / 2 (c11 E11^2 + c22 E22^2 + 2 c12 E11 E22 + 4 c66 E12^2) of the Green strain
/// E = (F^T F - I) / 2, F = [x1 - x0, x2 - x0] rest_inverse the deformation gradient from the
/// rest triangle in warp and weft coordinates. A shear angle g stores c66 g^2 / 2 a square metre
/// and a stretch e along the warp c11 e^2 / 2, on every triangle shape (edge springs hold a
/// fabric's shear only on right triangles along the warp and weft: docs/materials.md).
struct MembraneMaterial {
  Mat2 rest_inverse = Mat2::Identity();  ///< 1/m: the rest edges x1 - x0 and x2 - x0 (columns, warp and weft coordinates), inverted
  Scalar area = 0;                       ///< m^2, at rest
  Scalar c11 = 0, c22 = 0, c12 = 0, c66 = 0;  ///< N/m
  Scalar damping = 0;                    ///< s: a viscous stress damping times the elastic stress of the strain rate
};

/// A membrane triangle's forces on its corners and their Jacobians (blocks [i][j]: d force_i /
/// d x_j). The elastic Jacobian is exact but for its stress term, which takes the stress's
/// positive part (a compressed triangle's would make the system matrix indefinite; as the
/// springs drop their transverse term in compression). Damping: the viscous stress damping C
/// dE/dt, its dependence on x neglected (as the springs').
struct MembraneEvaluation {
  std::array<Vec3, 3> force{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};  ///< elastic and viscous
  std::array<std::array<Mat3, 3>, 3> d_force_d_x{};  ///< of the elastic force, negative semi-definite
  std::array<std::array<Mat3, 3>, 3> d_force_d_v{};  ///< of the viscous force
  Scalar energy = 0;                                 ///< the strain energy
};

MembraneEvaluation evaluate_membrane(const MembraneMaterial& m, const std::array<Vec3, 3>& x, const std::array<Vec3, 3>& v);

/// A membrane triangle's strain energy at positions x.
Scalar membrane_energy(const MembraneMaterial& m, const std::array<Vec3, 3>& x);

}  // namespace drape
