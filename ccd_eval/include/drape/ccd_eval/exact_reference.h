#pragma once
/// \file
/// The exact reference for a CCD query, in rational arithmetic (GMP).
///
/// The exact reference: whether two linearly moving features touch at some time of the step,
/// decided in rational arithmetic (GMP) from the query's coordinates, every degenerate
/// configuration included. Slow (tens to hundreds of microseconds a query) and exact: the
/// yardstick the tests and benchmarks hold the CCD methods against.

#include "drape/ccd/query.h"

namespace drape::ccd {

/// Whether the features of the query are at distance exactly zero at some t in [0, 1] (the
/// ground truth of the public query files: zero thickness, closed features, both ends of the
/// step included). Every coordinate is read exactly as the rational its double is.
///
/// The decision (docs/ccd.md, "The exact reference"): four coplanar points touch exactly when
/// every one of the three coordinate projections shows them touching, since one projection is
/// one-to-one on their common plane (or line); in a projection, touching is a sign condition on
/// 2D orientations (quadratic in t) and on coordinate differences (linear in t), with the
/// coplanarity cubic zero. The set of times where the condition holds is closed, so it is empty
/// unless it holds at t = 0, t = 1 or a root of one of those polynomials; each candidate is an
/// algebraic number (a square-free polynomial with an isolating interval) at which every sign
/// is evaluated exactly (a common factor decides zero; else the interval is halved until the
/// polynomial's Bernstein coefficients share one sign).
bool exact_contact(QueryKind kind, const Query& query);

}  // namespace drape::ccd
