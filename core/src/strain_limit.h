// Strain limiting's sweeps, apart from the integrator so that tests can hold them against a
// plain Gauss-Seidel sweep: docs/materials.md.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "drape/core/model.h"

namespace drape {

/// What the sweeps did: corrections made, and the work pinned ends did through the springs.
struct StrainSweeps {
  long corrections = 0;
  Scalar work = 0;
};

/// When each vertex's motion last changed and each limited spring (and block of them) was last
/// looked at, and how long each may end, kept between calls so that its memory is reused.
struct StrainSweepRecord {
  std::vector<long> changed, checked;              ///< per vertex, per limited spring
  std::vector<long> block_changed, block_checked;  ///< per block of STRAIN_BLOCK limited springs
  std::vector<Scalar> longest;                     ///< per limited spring: longest_allowed at the step's start
  std::vector<std::array<int, 2>> ends;            ///< the limited springs' ends the lists below were made for
  std::vector<int> first, at;                      ///< per vertex, the blocks of its springs: at[first[v]] ...
};

/// Limited springs, in the sweeps' order, passed over together when none of their ends moved.
inline constexpr std::size_t STRAIN_BLOCK = 64;

/// The longest a limited spring may end a step whose start found it `start` long: its limit,
/// or STRAIN_RECOVERY of its excess shorter when it started past it.
Scalar longest_allowed(const Spring& s, Scalar start);

/// What the sweeps read.
struct StrainSweepInput {
  std::span<const Spring> springs;
  std::span<const int> limited;          ///< indices into springs, swept in this order
  std::span<const Vec3> positions;       ///< at the step's start
  std::span<const Scalar> inverse_mass;  ///< per vertex, 0 at a pinned one
  Scalar h = 0;                          ///< the step, s
  int max_sweeps = 0;
  std::span<const char> held = {};       ///< per vertex, or empty: 1 where a contact holds it (HELD_WEIGHT)
};

/// Gauss-Seidel sweeps over the limited springs, at most max_sweeps, until one corrects
/// nothing: a spring whose length at the step's end (positions + h motion) passes
/// longest_allowed gets equal and opposite changes of its ends' motion along it by inverse
/// mass (a held vertex's times HELD_WEIGHT), which end it there; `also`, when given, gets the
/// same changes. A spring none of whose ends moved since it was last looked at is passed over
/// (its length is the one found then): the corrections and their order are those of looking at
/// every spring in every sweep.
StrainSweeps limit_strain_sweeps(const StrainSweepInput& in, std::vector<Vec3>& motion, std::vector<Vec3>* also,
                                 StrainSweepRecord& record);

}  // namespace drape
