#pragma once
/// \file
/// The scalar and vector types of the whole code base (precision chosen once).
///
/// Precision is chosen once for the whole code base.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace drape {

using Scalar = double;
using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
using Vec3 = Eigen::Matrix<Scalar, 3, 1>;

/// Unit roundoff of Scalar (2^-53 for double): the relative error of one rounded operation.
inline constexpr Scalar UNIT_ROUNDOFF = 0.5 * 2.220446049250313e-16;

}  // namespace drape
