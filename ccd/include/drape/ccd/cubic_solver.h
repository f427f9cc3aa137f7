#pragma once
/// \file
/// The standard closed-form cubic solver: the paper's unfiltered baseline.
///
/// A standard closed-form solver for the real roots of a cubic: the baseline of the paper
/// ("the standard cubic solver without any filters").

#include <array>

#include "drape/ccd/bernstein.h"

namespace drape::ccd {

/// Relative size below which a leading coefficient is dropped on [0, 1]: the dropped term
/// changes the polynomial there by at most this fraction of its largest coefficient.
inline constexpr Scalar LEADING_COEFFICIENT_RATIO = 1e-12;

/// Relative size below which a discriminant counts as zero, so that a double root (a tangential
/// contact) rounded into a complex pair is still returned.
inline constexpr Scalar DOUBLE_ROOT_RATIO = 1e-10;

/// Real roots of a0 + a1 t + a2 t^2 + a3 t^3 in ascending order, each polished by Newton's
/// method; returns how many were written to roots. A polynomial whose coefficients are all
/// zero returns -1 (every t is a root).
int solve_cubic(const Power3& a, std::array<Scalar, 3>& roots);

}  // namespace drape::ccd
