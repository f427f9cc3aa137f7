#pragma once
/// \file
/// The integrator's constants and per-run workspace (internal to core), shared by
/// integrator.cpp (the step), integrator_linearised.cpp (the linearised backward Euler: assembly,
/// CHOLMOD or CG, the response spread) and integrator_projective.cpp (the projective solver's
/// step and spread).

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <vector>

#include "drape/core/integrator.h"
#include "projective.h"
#include "strain_limit.h"

namespace drape {

// The penalty that holds a contact vertex to the velocity the collision response gave it while
// the response is spread through the implicit system: its diagonal block's largest entry times
// this, added to the block, so it follows its target to about 1 / RESPONSE_HOLD of its change.
inline constexpr Scalar RESPONSE_HOLD = 1e8;
// The penalty that holds a contact of the cloth with itself in the linearised solve, times the
// largest diagonal entry of its vertices (as RESPONSE_HOLD): it leaves about a thousandth of the
// two sides' approach, which the response's proximity impulses then take. Its pushes are equal
// and opposite, but the solve keeps the momentum only to rounding, and that rounding grows
// with the penalty: two layers stopped by 1e8 changed their momentum by 2 %, by 1e3 by 4e-7
// (SelfContactsInTheSolve); the pile's first 30 frames ran alike from 1e2 to 1e8.
inline constexpr Scalar SELF_CONTACT_HOLD = 1e3;
// The linearised solve holds a cloth vertex against an obstacle (Integrator::find_contacts) when
// it starts within this many thicknesses of it: a little more than one, since the response
// leaves a resting vertex at the thickness.
inline constexpr Scalar CONTACT_REACH = 1.1;

// A change of the step's motion smaller than this fraction of the thickness is negligible: a
// vertex the response moved by less is not held for the re-solve, and a held contact that would
// pull its vertex by less is not released (Integrator::advance, solve_linearised).
inline constexpr Scalar NEGLIGIBLE_MOTION = 1e-2;
// m/s: a contact vertex slipping slower than this across its obstacle sticks (the friction in
// Integrator::solve_linearised).
inline constexpr Scalar FRICTION_SLIP = 1e-4;
// The matrix's pattern keeps the blocks of earlier self contacts while they are at most this
// many times the current contacts' (Integrator::find_contacts); beyond, it is built again from
// the current ones.
inline constexpr std::size_t EXTRA_BLOCKS_KEPT = 4;
// The projective solve keeps the cloth this many thicknesses from spheres and planes: a held
// contact yields a little (its penalty's force needs a depth), and within this margin it
// yields outside the thickness, where the response after the solve has nothing to do.
inline constexpr Scalar HELD_GAP = 1.05;

// A step may end with at most this fraction of the scene's energy scale (energy_scale) more
// than it started with, plus the sources' work; beyond it the step is taken again in 2, 4, ...
// parts, at most 2^solver.max_halvings. The tolerance covers what the analytic obstacles'
// projection out of the thickness adds (m g times a step's sag, far below it).
inline constexpr Scalar STEP_ENERGY_TOLERANCE = 1e-3;
// Strain limiting's sweeps over the limited springs a step, at most.
inline constexpr int STRAIN_LIMIT_SWEEPS = 200;
// A limited spring past (1 + STRAIN_SLACK) times its limit after the response sends the step's
// motion through the limit and the response again, at most STRAIN_RESPONSE_ROUNDS times.
inline constexpr Scalar STRAIN_SLACK = 0.002;
inline constexpr int STRAIN_RESPONSE_ROUNDS = 16;
// In those rounds a vertex the step's response has moved (a contact's) weighs 1 / HELD_WEIGHT
// times its mass in the limit's sweeps: what holds it (an obstacle, another layer) bears the
// pull of the cloth hanging from it. At its own mass the limit pulled it back into the contact
// and the response pushed it out again, round after round (a knit caught on a needle's tip
// ran out of rounds in every step). Not infinitely heavy: a spring between two such vertices,
// which the response has stretched, must still be brought back.
inline constexpr Scalar HELD_WEIGHT = 0.01;
// A step that still ends with a limited spring past (1 + STRAIN_RETAKE) times what its limit
// allows it (Integrator::limit_excess; the rounds ran out) is taken again in parts, and then
// without friction (Integrator::step).
inline constexpr Scalar STRAIN_RETAKE = 0.005;

// A contact, the same from step to step: its cloth vertices and its kind (the cloth with
// itself: a vertex and a face have one positive weight, two edges two; 2: an obstacle's, whose
// contacts with the same vertices differ by their normals).
inline std::array<int, 5> contact_key(const SolveContact& c) {
  return {c.vertex[0], c.vertex[1], c.vertex[2], c.vertex[3], c.self ? (c.weight[1] < 0 ? 0 : 1) : 2};
}

// The system matrix over the free vertices, with the place of every 3x3 block in its
// compressed storage: a block (a, b) occupies rows 3a..3a+2 of columns 3b..3b+2, and the three
// rows of one column are contiguous, so the offset of row 3a in each column is enough.
// Also the step's forces, contacts and scratch vectors, kept from step to step.
struct Integrator::Workspace {
  std::vector<int> free_index;               // vertex -> free vertex index, or -1 if pinned
  int free_count = 0;
  std::vector<int> limited_springs;          // the springs with a strain limit (Spring::limit), in order
  std::vector<Scalar> inverse_mass;          // 1 / mass of each free vertex, 0 of a pinned one
  StrainSweepRecord strain_sweeps;           // limit_strain's record, its memory reused
  SparseMatrix matrix;
  std::vector<std::array<int, 3>> diagonal;  // free vertex -> offsets of its (a, a) block
  struct SpringBlocks {
    std::array<int, 3> ij{-1, -1, -1}, ji{-1, -1, -1};
  };
  std::vector<SpringBlocks> spring_blocks;
  std::vector<std::array<std::array<std::array<int, 3>, 4>, 4>> hinge_blocks;  // [hinge][i][j]: block (v_i, v_j)
  std::vector<std::array<std::array<std::array<int, 3>, 3>, 3>> membrane_blocks;  // [triangle][i][j]: block (v_i, v_j)
  VectorX rhs, solution;
  std::vector<Vec3> forces;
  // The projective step's start velocities and explicit forces (gravity, wind), kept for the
  // response's spread.
  std::vector<Vec3> start_velocities, explicit_forces;
  ProjectiveContacts projective_contacts;  // what the projective step holds in its solve
  // The contacts the linearised solve keeps, and the impulse (N s, along the normal) each
  // applied; zero for the ones released.
  std::vector<SolveContact> contacts;
  using ContactBlocks = std::array<std::array<std::array<int, 3>, 4>, 4>;
  std::vector<ContactBlocks> contact_blocks;  // [contact][i][j]: block (vertex i, vertex j)
  std::vector<std::pair<int, int>> extra_blocks;  // free vertex pairs (a < b) the pattern joins for self contacts, sorted
  std::vector<std::vector<int>> base_columns;     // per block column b, the rows a of the springs', hinges' and membranes' blocks, sorted
  // With extra blocks: the base pattern alone (base_columns' blocks) for the response's spread,
  // each of its entries' offset in matrix, and per entry of matrix whether the base pattern
  // holds it. Empty without extra blocks (the matrix is then the base pattern).
  SparseMatrix spread_matrix;
  std::vector<int> spread_source;
  std::vector<char> in_base;
  std::vector<Scalar> contact_holds, contact_impulses;
  std::vector<char> contact_held;  // per contact: neither released nor found pulling in the solve
  std::vector<Scalar> assembled;   // the matrix's values before the contacts' penalties and friction
  struct FrictionBlock {
    int vertex;
    Mat3 block;
    bool analytic;  // against a sphere or plane
  };
  std::vector<FrictionBlock> friction_blocks;  // the solve's friction terms
  std::vector<Scalar> scale;  // per free vertex: its diagonal block's largest entry before penalties
  Scalar contact_work = 0;           // J: what the held contacts did at moving obstacles in the last solve
  // What the last solve's contacts pushed with, for the next step's lagged friction (a step
  // taken again in parts starts each attempt from the step before's, and keeps the kept
  // attempt's).
  struct Lagged {
    std::vector<Scalar> normal_force;  // per vertex, N: what its obstacle contacts pushed with
    // What each of the cloth's contacts with itself pushed with (those that pushed), by
    // contact_key: its impulse (N s) and that solve's step (s).
    std::map<std::array<int, 5>, std::pair<Scalar, Scalar>> self_impulses;
    // The contacts that pulled when the step's solves ended (and a moving obstacle's released
    // for its last solve), to be released in the next: each one's contact_key and normal,
    // sorted by key.
    std::vector<std::pair<std::array<int, 5>, Vec3>> released;
    bool is_released(const SolveContact& c) const {
      const std::array<int, 5> key = contact_key(c);
      auto at = std::lower_bound(released.begin(), released.end(), key, [](const auto& r, const auto& k) { return r.first < k; });
      for (; at != released.end() && at->first == key; ++at)
        if (at->second.dot(c.normal) > SAME_DIRECTION) return true;
      return false;
    }
  };
  Lagged lagged;

  std::array<int, 3> block(int a, int b) const {
    std::array<int, 3> offsets{};
    for (int c = 0; c < 3; ++c) {
      const int column = 3 * b + c;
      const auto* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column];
      const auto* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column + 1];
      offsets[c] = int(std::lower_bound(begin, end, 3 * a) - matrix.innerIndexPtr());
    }
    return offsets;
  }
  // The offsets of block (a, b) when the pattern holds it.
  std::optional<std::array<int, 3>> find_block(int a, int b) const {
    const int column = 3 * b;
    const auto* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column];
    const auto* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column + 1];
    const auto* found = std::lower_bound(begin, end, 3 * a);
    if (found == end || *found != 3 * a) return std::nullopt;
    return block(a, b);
  }
  void add_block(const std::array<int, 3>& offsets, const Mat3& value) {
    Scalar* values = matrix.valuePtr();
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) values[offsets[c] + r] += value(r, c);
  }
  // Contact k's penalty along its normal, hold times its weights' outer product, into the
  // matrix (the solve holds its contacts with it; the response's spread keeps some of them).
  void add_contact_hold(std::size_t k, Scalar hold) {
    const SolveContact& c = contacts[k];
    const Mat3 nn = c.normal * c.normal.transpose();
    for (int i = 0; i < c.count; ++i)
      for (int j = 0; j < c.count; ++j) add_block(contact_blocks[k][i][j], hold * c.weight[i] * c.weight[j] * nn);
  }
};

// Each vertex's obstacle contact of largest weight among contacts (-1: none), for its friction
// (the cloth's contacts with itself have theirs in the response).
inline std::vector<int> strongest_contacts(const std::vector<SolveContact>& contacts, int n) {
  std::vector<int> strongest(std::size_t(n), -1);
  std::vector<Scalar> weight(std::size_t(n), 0);
  for (std::size_t k = 0; k < contacts.size(); ++k)
    for (int i = 0; i < contacts[k].count && !contacts[k].self; ++i) {
      const std::size_t v = std::size_t(contacts[k].vertex[i]);
      if (contacts[k].weight[i] > weight[v]) weight[v] = contacts[k].weight[i], strongest[v] = int(k);
    }
  return strongest;
}

}  // namespace drape
