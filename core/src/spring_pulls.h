#pragma once
// Internal to core/: the projective solver's springs, many at a time (spring_pulls.cpp).

#include <cstddef>
#include <cstdint>
#include <vector>

namespace drape {

/// One L-BFGS evaluation's springs as structure of arrays, an entry a spring, every array
/// holding a whole number of SPRING_LANES entries (the padding any finite spring).
struct SpringPullInput {
  const double *zx, *zy, *zz;     ///< z = x_i - x_j now
  const double *sx, *sy, *sz;     ///< z at the step's start
  const double *d0x, *d0y, *d0z;  ///< its unit direction there
  const double *rest, *elastic, *viscous;  ///< rest length (m), h^2 k, h c
  std::size_t count = 0;                   ///< entries, a multiple of SPRING_LANES
};

/// Each spring's pull on its end i (-pull on j) and its energy.
struct SpringPullOutput {
  double *px, *py, *pz, *energy;
};

/// Entries are taken this many at a time; the arrays are padded to a multiple of it.
inline constexpr std::size_t SPRING_LANES = 8;

/// pull = h^2 k (|z| - r) d + h c ((z - z0) . d0) d0 with d = z / |z| (d0 for a spring of zero
/// length), and the energy h^2 k (|z| - r)^2 / 2 + h c ((z - z0) . d0)^2 / 2: the damping
/// along the direction at the step's start (docs/solvers.md). The vectors of the widest
/// instruction set the machine runs (Highway), each operation the scalar formula's in its
/// order, so every instruction set gives the same bits (no fused multiply-add; a Vec3's sums
/// as (a + b) + c, Eigen's order on its vectorised path, which SSE2 and NEON give every build
/// here; tests/core/test_spring_pulls.cpp compares them with Eigen compiled the same way).
void spring_pulls(const SpringPullInput& in, const SpringPullOutput& out);

/// The instruction sets spring_pulls was compiled for that this machine runs, best first, as
/// Highway's target bits (for the tests: hwy::SetSupportedTargetsForTest chooses one).
std::vector<std::int64_t> spring_pull_targets();

}  // namespace drape
