#pragma once
/// \file
/// The state of a run and the implicit step, by the scene's solver.
///
/// The state of a run and the implicit step, by one of two solvers (the scene's solver.type):
/// - linearised backward Euler (Baraff and Witkin, "Large steps in cloth simulation",
///   SIGGRAPH 1998), the accurate reference:
///       (M - h dF/dv - h^2 dF/dx) dv = h (F + h dF/dx v),   v += dv,   x += h v,
///   with a sparse Cholesky factorisation (or conjugate gradient) of its 3n x 3n matrix every step;
/// - the projective solver (projective.h): backward Euler's minimisation by local-global
///   iterations, one factorisation of an n x n matrix for the run.
/// Pinned and scripted vertices are eliminated from either system (their motion is prescribed).
/// The linearised solve also holds the contacts with obstacles the step starts with, along
/// their normals, with their friction (docs/collisions.md, "Contacts held in the solve"); then
/// the contact response: analytic obstacles and the collision pipeline, spread through the
/// system.

#include <memory>
#include <string>

#include "drape/core/collision.h"
#include "drape/core/linear_solver.h"
#include "drape/core/model.h"

namespace drape {

struct State {
  std::vector<Vec3> positions;
  std::vector<Vec3> velocities;
  Scalar time = 0;
  long steps = 0;
};

/// Everything at rest at the initial positions, time 0.
State initial_state(const Model& model);

/// Strain limiting: the share of a spring's excess over its limit at a step's start (the
/// collision response may leave one) that the step takes back (docs/materials.md).
inline constexpr Scalar STRAIN_RECOVERY = 0.5;

struct StepReport {
  bool ok = true;
  std::string failure;        ///< why the run must stop, when !ok
  int solver_iterations = 0;
  bool solver_converged = true;
  double solve_ms = 0;        ///< assembly excluded
  int obstacle_contacts = 0;  ///< vertices projected out of spheres and planes, and faces pushed out of spheres
  CollisionCounters collisions;  ///< the collision pipeline's work (zero when not needed)
  /// J: energy the scene's sources may have put into the cloth this step, each source's work
  /// counted when positive: the handles (the force that keeps each pinned vertex on its path,
  /// times its displacement), the wind (drag and air damping towards the wind's velocity),
  /// and moving obstacles (the kinetic energy their contacts added). Gravity is not here: its
  /// potential is part of potential_energy. A run's energy stays below its start plus the sum
  /// of these (docs/scenes.md, "limits").
  Scalar external_work = 0;
  /// How many times the step was halved because it made energy (Integrator::step): its kept
  /// attempt took 2^step_halvings parts.
  int step_halvings = 0;
  /// Strain limiting (Material::strain_limit): the corrections made (a spring brought back to
  /// its limit, counted each time), and their time.
  int strain_limited = 0;
  double strain_ms = 0;
  /// Adds another step's report: counts, times and work summed, the first failure kept.
  void add(const StepReport& other);
};

/// The scene's energy scale, J: the kinetic energy at the start plus the total mass times
/// gravity times the diagonal of everything's extent at the start (a fall across the scene).
/// Tolerances on energy are fractions of it.
Scalar energy_scale(const Model& model);

class ProjectiveSolver;
struct HeldVertices;
struct ProjectiveContacts;

/// Holds what a run reuses from step to step: for the linearised solve, the system's sparsity
/// pattern with each spring's place in it and the linear solver (whose symbolic analysis
/// CHOLMOD keeps); for the projective solver, its factorisations.
class Integrator {
 public:
  /// The scene's solver; threads: for the collision pipeline's narrow phase and feature pairs
  /// and the projective solver's passes (results do not depend on it).
  explicit Integrator(const Model& model, int threads = 1);
  ~Integrator();
  /// One step of the scene's timestep: forces -> implicit solve -> analytic obstacles ->
  /// collision pipeline (broad phase, narrow phase, response) -> positions -> checks. A step
  /// that ends with more energy than it began with plus its sources' work (beyond a
  /// tolerance) is taken again in 2, 4, ... equal parts, at most 2^solver.max_halvings, while
  /// that excess keeps falling by half at least; the attempt with the least excess is kept.
  StepReport step(State& state);
  /// Symbolic analyses of the solver's sparse factorisations so far (0 for cg).
  int analyses() const;
  /// Numeric factorisations of the linearised solver's matrices so far (0 for cg and projective).
  int factorisations() const;
  /// The collision pipeline, or nullptr when the scene needs none.
  CollisionPipeline* collisions() { return collisions_.get(); }

 private:
  struct Workspace;
  // The step's system (the workspace's matrix and right-hand side) solved into its solution;
  // time and iterations added to report, and on failure report says so (failure, then why).
  // With again, solves for that right-hand side with the last solve's matrix instead. With
  // spread, the response's spread system (the workspace's spread_matrix) by its own solver.
  bool solve(StepReport& report, const std::string& failure, const VectorX* again = nullptr, bool spread = false);
  // The collision response spread through the step: the system as the solve assembled it
  // (without mesh contacts' penalties and friction; with the solve's held sphere and plane
  // contacts and their friction on vertices not held here), solved with each held vertex (those the
  // response moved by more than a negligible distance) kept by a penalty at its new motion,
  // then (the same factorisation) at its new velocity, from the solve's velocities (solved);
  // motion and velocities of the others receive the results, and report says why when the
  // solve fails.
  void spread_response(const std::vector<Vec3>& solved, const std::vector<char>& held, std::vector<Vec3>& motion,
                       std::vector<Vec3>& velocities, StepReport& report);
  // The linearised system's matrix M (1 + h a) - h dF/dv - h^2 dF/dx over the free vertices,
  // assembled at positions x and velocities v into the workspace; the springs' forces added to
  // forces, and when asked dF/dx v into stiffness_times_v and the matrix's coupling to the
  // prescribed dv of the pinned vertices into coupling.
  void assemble(const std::vector<Vec3>& x, const std::vector<Vec3>& v, std::vector<Vec3>& forces,
                std::vector<Vec3>* stiffness_times_v = nullptr, const std::vector<Vec3>* pinned_dv = nullptr,
                std::vector<Vec3>* coupling = nullptr);
  // The contacts of the free cloth vertices with the obstacles at the state (the workspace's
  // contacts), for the linearised solve to hold; with self-collision and the linearised solver,
  // the cloth's contacts with itself too (their broad phase counted in report).
  void find_contacts(const State& state, const std::vector<Vec3>& pinned_dv, StepReport& report);
  // The system matrix's pattern (the workspace's): the free vertices' diagonal blocks, the
  // blocks the springs and hinges join, and extra pairs (a, b) of free vertices, a < b,
  // unique (both blocks); the offsets of the springs' and hinges' blocks found again.
  void build_pattern(const std::vector<std::pair<int, int>>& extra);
  // Strain limiting after the solve (Provot 1995, on velocities as Bridson, Fedkiw and
  // Anderson 2002): each limited spring whose length at the step's end (positions + h motion)
  // would pass its limit gets equal and opposite changes of its ends' motion along it (by
  // inverse mass; pinned ends keep theirs), also made to also when given, in sweeps over the
  // springs until none passes or the sweeps run out. A spring longer than its limit at the
  // step's start may end STRAIN_RECOVERY of its excess shorter. Returns the work the handles
  // did through it (J).
  Scalar limit_strain(const std::vector<Vec3>& positions, std::vector<Vec3>& motion, std::vector<Vec3>* also,
                      StepReport& report, std::span<const char> held = {});
  // Whether a limited spring (structural, or a diagonal under a shear locking angle) ends the
  // step (positions + h motion) past its limit by more than STRAIN_SLACK.
  bool past_limit(const std::vector<Vec3>& positions, const std::vector<Vec3>& motion) const;
  // The largest length of a limited spring at the end of a step over what the limit allows it
  // from the step's start (its limit, or STRAIN_RECOVERY of its excess less when it started
  // past it), less 1 (0 with none limited or none past); springs pinned at both ends are their
  // handles' (as in limit_strain).
  Scalar limit_excess(const std::vector<Vec3>& start, const std::vector<Vec3>& end) const;
  // The linearised system assembled at the state (forces into the workspace) and solved:
  // the state's velocities advanced; false (report says why) when the solve failed.
  bool solve_linearised(State& state, const std::vector<Vec3>& pinned_dv, StepReport& report);
  // The projective solver's step from the state: its velocities advanced (the pinned ones by
  // pinned_dv); the handles' springs' forces added to the workspace's forces for the ledger.
  bool solve_projective(State& state, const std::vector<Vec3>& pinned_dv, StepReport& report);
  // The projective solver's iterations for this step from start (positions: first guess in,
  // end of the step out), with held vertices when given; timed into report, which says why
  // (failure, then the reason) when they fail.
  bool iterate_projective(const std::vector<Vec3>& start, std::vector<Vec3>& positions, StepReport& report,
                          const std::string& failure, const HeldVertices* held = nullptr,
                          const ProjectiveContacts* contacts = nullptr);
  // spread_response's counterpart for the projective solver: the step solved again with the
  // contact vertices held to their new end positions (the motion), then to where their new
  // velocities would take them (the velocities); start is the step's start.
  void spread_projective(const std::vector<Vec3>& start, const std::vector<Vec3>& solved, std::vector<Vec3>& motion,
                         std::vector<Vec3>& velocities, StepReport& report);
  // One step of size h_, unchecked.
  StepReport advance(State& state);
  // The response to contact: analytic obstacles, then the collision pipeline; changes motion
  // and the state's velocities.
  void respond(State& state, std::vector<Vec3>& motion, StepReport& report);
  // respond, and with limited springs each free vertex whose motion it changed by more than a
  // negligible share of the thickness marked in held (strain limiting's rounds, HELD_WEIGHT).
  void respond_holding(State& state, std::vector<Vec3>& motion, StepReport& report, std::vector<char>& held);
  // The step's positive work of the handles and of the air (with wind), for the energy ledger
  // (StepReport::external_work); velocities are the solve's.
  Scalar source_work(const std::vector<Vec3>& pinned_dv, const std::vector<Vec3>& air_forces,
                     const std::vector<Vec3>& velocities) const;
  const Model& model_;
  std::unique_ptr<LinearSolver> solver_;         // linearised: cholmod or cg
  // The response's spread when the step's pattern holds the self contacts' blocks: its system
  // has none of them (zero there), so it is factorised over the springs', hinges' and
  // membranes' pattern alone, without the fill the layers' coupling makes.
  std::unique_ptr<LinearSolver> spread_solver_;
  std::unique_ptr<ProjectiveSolver> projective_;  // or projective
  std::unique_ptr<CollisionPipeline> collisions_;  // only when the scene needs it
  std::unique_ptr<Workspace> work_;
  Scalar h_ = 0;                 // the step being taken: the scene's timestep or a part of it
  Scalar energy_tolerance_ = 0;  // J, see STEP_ENERGY_TOLERANCE
  Scalar energy_warning_ = 0;    // J: an excess that would make the run warn (limits.energy_warn)
  // Coulomb's coefficient of the attempt being taken: the scene's, or 0 where a step is taken
  // again sliding (step: friction would hold the cloth past its strain limit).
  Scalar friction_ = 0;
  // The potential energy of the last step's end and the positions it was taken at: the next
  // step's start, when nothing moved the cloth in between.
  Scalar ended_potential_ = 0;
  std::vector<Vec3> ended_positions_;
};

/// Diagnostics for the frame statistics.
Scalar kinetic_energy(const Model& model, const State& state);
/// Spring energy plus gravitational energy (relative to height zero along gravity).
Scalar potential_energy(const Model& model, const State& state);
/// Largest stretch-spring length over rest length (1 when no stretch spring).
Scalar max_stretch(const Model& model, const State& state);

}  // namespace drape
