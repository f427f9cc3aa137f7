#pragma once
/// \file
/// Spring forces and their Jacobians: pure functions over two particles.

#include <Eigen/Core>

#include "drape/ccd/types.h"

namespace drape {

using Mat3 = Eigen::Matrix<Scalar, 3, 3>;

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

}  // namespace drape
