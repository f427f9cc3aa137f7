#pragma once
/// \file
/// The state of a run and the implicit step: linearised backward Euler (Baraff and Witkin,
/// "Large steps in cloth simulation", SIGGRAPH 1998):
///     (M - h dF/dv - h^2 dF/dx) dv = h (F + h dF/dx v),   v += dv,   x += h v,
/// with pinned and scripted vertices eliminated from the system (their dv is prescribed and
/// moved to the right-hand side), then the analytic obstacles' contact response.

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

struct StepReport {
  bool ok = true;
  std::string failure;        ///< why the run must stop, when !ok
  int solver_iterations = 0;
  bool solver_converged = true;
  double solve_ms = 0;        ///< assembly excluded
  int obstacle_contacts = 0;  ///< vertices projected out of analytic obstacles
  CollisionCounters collisions;  ///< the collision pipeline's work (zero when not needed)
};

/// Holds what a run reuses from step to step: the system's sparsity pattern with each spring's
/// place in it, and the linear solver (whose symbolic analysis CHOLMOD keeps).
class Integrator {
 public:
  /// threads: for the collision pipeline's narrow phase (results do not depend on it).
  Integrator(const Model& model, std::unique_ptr<LinearSolver> solver, int threads = 1);
  ~Integrator();
  /// One step of the scene's timestep: forces -> implicit solve -> analytic obstacles ->
  /// collision pipeline (broad phase, narrow phase, response) -> positions -> checks.
  StepReport step(State& state);
  const LinearSolver& solver() const { return *solver_; }
  /// The collision pipeline, or nullptr when the scene needs none.
  CollisionPipeline* collisions() { return collisions_.get(); }

 private:
  struct Workspace;
  // The step's system (the workspace's matrix and right-hand side) solved into its solution;
  // time and iterations added to report, and on failure report says so (failure, then why).
  bool solve(StepReport& report, const std::string& failure);
  // The collision response (motion - proposed, on the contact vertices) spread through this
  // step's system: the system solved again with those vertices held to their new velocities;
  // motion receives the result. False when the response changed nothing.
  bool spread_response(const std::vector<Vec3>& proposed, std::vector<Vec3>& motion, StepReport& report);
  const Model& model_;
  std::unique_ptr<LinearSolver> solver_;
  std::unique_ptr<CollisionPipeline> collisions_;  // only when the scene needs it
  std::unique_ptr<Workspace> work_;
};

/// Diagnostics for the frame statistics.
Scalar kinetic_energy(const Model& model, const State& state);
/// Spring energy plus gravitational energy (relative to height zero along gravity).
Scalar potential_energy(const Model& model, const State& state);
/// Largest stretch-spring length over rest length (1 when no stretch spring).
Scalar max_stretch(const Model& model, const State& state);

}  // namespace drape
