// The projective solver (core/src/projective.cpp): exact free fall, convergence to the
// linearised backward Euler reference as its iterations grow, one factorisation for a run,
// handles followed exactly, the response spread with the cloth held.
#include <gtest/gtest.h>

#include "drape/core/integrator.h"
#include "projective.h"

using namespace drape;

namespace {

Model model_of(const std::string& json) { return build_model(parse_scene(json, "inline.json")); }

// A 1 m cloth pinned at two corners swinging down, with the given solver section.
Model hanging(const std::string& solver) {
  return model_of(R"({"frame_time": 0.04, "frame_steps": 4,
    "cloths": [{"grid": {"size": [1, 1], "resolution": [10, 10]}, "material": {"damping": 0.01, "air_damping": 1.0}}],
    "handles": [{"corners": ["top-left", "top-right"]}], "solver": )" + solver + "}");
}

// The largest distance between the vertices of two runs of the same cloth.
Scalar largest_distance(const State& a, const State& b) {
  Scalar worst = 0;
  for (std::size_t v = 0; v < a.positions.size(); ++v) worst = std::max(worst, (a.positions[v] - b.positions[v]).norm());
  return worst;
}

State run(const Model& model, int steps, Integrator* integrator = nullptr) {
  State state = initial_state(model);
  Integrator own(model);
  Integrator& stepper = integrator ? *integrator : own;
  for (int k = 0; k < steps; ++k) EXPECT_TRUE(stepper.step(state).ok) << "step " << k;
  return state;
}

}  // namespace

TEST(Projective, FreeFallIsBackwardEulerExactly) {
  // No pins, no air, springs at rest: every iteration returns the inertial prediction, so
  // after n steps of h, v = n h g and z = h^2 g n (n + 1) / 2, as backward Euler gives (to
  // rounding: v is a difference of positions over h).
  const Model model = model_of(R"({"frame_time": 0.01, "frame_steps": 2, "cloths": [{"grid": {"resolution": [6, 6]},
    "material": {"air_damping": 0}}], "solver": {"type": "projective", "iterations": 3, "history": 0, "chebyshev": 0}})");
  const int n = 40;
  const State state = run(model, n);
  const Scalar h = model.scene.timestep(), g = model.scene.gravity.z();
  for (std::size_t v = 0; v < state.positions.size(); ++v) {
    EXPECT_NEAR(state.velocities[v].z(), n * h * g, 1e-10);
    EXPECT_NEAR(state.positions[v].z() - model.initial_positions[v].z(), h * h * g * n * (n + 1) / 2, 1e-12);
    EXPECT_NEAR(state.positions[v].x(), model.initial_positions[v].x(), 1e-11);
  }
}

TEST(Projective, MoreIterationsComeCloserToTheLinearisedReference) {
  // Converged, the projective solver is backward Euler itself, the reference its linearisation
  // (their difference shrinks with the step); a few iterations leave the springs soft. Plain
  // local-global iterations (history 0), with and without Chebyshev acceleration.
  const State reference = run(hanging(R"({"type": "cholmod"})"), 25);
  const Scalar few = largest_distance(reference, run(hanging(R"({"type": "projective", "iterations": 3, "history": 0, "chebyshev": 0})"), 25));
  const Scalar many =
      largest_distance(reference, run(hanging(R"({"type": "projective", "iterations": 300, "history": 0, "chebyshev": 0})"), 25));
  const Scalar plain = largest_distance(reference, run(hanging(R"({"type": "projective", "iterations": 10, "history": 0, "chebyshev": 0})"), 25));
  const Scalar accelerated =
      largest_distance(reference, run(hanging(R"({"type": "projective", "iterations": 10, "history": 0, "chebyshev": 0.9})"), 25));
  EXPECT_LT(many, 0.2 * few) << few << " m with 3 iterations, " << many << " m with 300";
  EXPECT_LT(accelerated, plain) << "10 iterations: " << plain << " m plain, " << accelerated << " m accelerated";
}

// The step's objective (the backward Euler energy projective.h minimises) after one step of
// the hanging cloth with the given solver section, from the state five reference steps give.
std::pair<Scalar, int> objective_after_one_step(const std::string& solver) {
  const Model model = hanging(solver);
  const State start = run(hanging(R"({"type": "cholmod"})"), 5);
  std::vector<int> free_index(model.vertex_count(), -1);
  int free_count = 0;
  for (std::size_t v = 0; v < model.vertex_count(); ++v)
    if (model.pin_of_vertex[v] < 0) free_index[v] = free_count++;
  ProjectiveSolver solver_of(model, free_index, free_count);
  const Scalar h = model.scene.timestep();
  std::vector<Vec3> forces(model.vertex_count()), positions(model.vertex_count());
  for (std::size_t v = 0; v < model.vertex_count(); ++v) {
    forces[v] = model.masses[v] * model.scene.gravity;
    positions[v] = start.positions[v] + h * start.velocities[v] + (free_index[v] >= 0 ? Vec3(h * h * model.scene.gravity) : Vec3::Zero());
  }
  std::string error;
  EXPECT_TRUE(solver_of.solve({h, &start.positions, &start.velocities, &forces}, positions, error)) << error;
  return {solver_of.objective(), solver_of.iterations_done()};
}

TEST(Projective, QuasiNewtonConvergesFasterThanLocalGlobal) {
  // The same step's objective after 10, 20 and 40 iterations: L-BFGS (the default, history 5)
  // below local-global, plain or Chebyshev-accelerated (which need not beat plain). The stiff
  // springs of this cloth (h^2 k / m about 1e6) converge slowly in all three (docs/solvers.md).
  for (int iterations : {10, 20, 40}) {
    const std::string count = std::to_string(iterations);
    const Scalar quasi_newton = objective_after_one_step(R"({"type": "projective", "tolerance": 1e-12, "iterations": )" + count + "}").first;
    const Scalar accelerated = objective_after_one_step(
        R"({"type": "projective", "history": 0, "iterations": )" + count + "}").first;
    const Scalar plain = objective_after_one_step(
        R"({"type": "projective", "history": 0, "chebyshev": 0, "iterations": )" + count + "}").first;
    EXPECT_LT(quasi_newton, accelerated) << iterations << " iterations";
    EXPECT_LT(quasi_newton, plain) << iterations << " iterations";
  }
}

TEST(Projective, ATolerenceStopsTheIterationsEarly) {
  // The share of an edge that an iteration must move some vertex by to go on: looser, fewer
  // iterations and a higher objective; the count the solver reports is what it did.
  const auto [loose, loose_count] = objective_after_one_step(R"({"type": "projective", "iterations": 500, "tolerance": 1e-2})");
  const auto [tight, tight_count] = objective_after_one_step(R"({"type": "projective", "iterations": 500, "tolerance": 1e-5})");
  EXPECT_LT(loose_count, tight_count);
  EXPECT_LT(tight_count, 500);
  EXPECT_LT(tight, loose);
  const auto [capped, capped_count] = objective_after_one_step(R"({"type": "projective", "iterations": 3, "tolerance": 1e-5})");
  EXPECT_EQ(capped_count, 3);
  EXPECT_GT(capped, tight);
}

TEST(Projective, OneFactorisationServesTheWholeRun) {
  // One per step size: without the step's halving (which takes a step in parts), one.
  const Model model = hanging(R"({"type": "projective", "max_halvings": 0})");
  Integrator integrator(model);
  run(model, 100, &integrator);
  EXPECT_EQ(integrator.analyses(), 1);
}

TEST(Projective, EverySolverRunsAClothWhoseVerticesAreAllPinned) {
  // Nothing free: an empty system, which CHOLMOD refuses to factorise (it crashed the run).
  for (const char* solver : {"cholmod", "cg", "projective"}) {
    const Model model = model_of(std::string(R"({"frame_time": 0.04, "frame_steps": 4,
      "cloths": [{"grid": {"size": [1, 1], "resolution": [1, 1]}}],
      "handles": [{"corners": ["top-left", "top-right", "bottom-left", "bottom-right"], "motion": {"velocity": [0, 0, 1]}}],
      "solver": {"type": ")") + solver + R"("}})");
    const State state = run(model, 8);
    for (std::size_t v = 0; v < state.positions.size(); ++v)
      EXPECT_NEAR(state.positions[v].z(), model.initial_positions[v].z() + state.time, 1e-12) << solver;
  }
}

TEST(Projective, HandlesFollowTheirMotionExactly) {
  const Model model = model_of(R"({"frame_time": 0.04, "frame_steps": 4, "cloths": [{"grid": {"resolution": [6, 6]}}],
    "handles": [{"corners": ["top-left", "top-right"], "motion": {"velocity": [0, 0, 0.5], "angular_velocity": [0, 0, 1]}}],
    "solver": {"type": "projective"}})");
  const State state = run(model, 30);
  for (const Pin& pin : model.pins) {
    const Vec3 expected = model.scene.handles[pin.handle].motion.position(model.initial_positions[pin.vertex], state.time);
    EXPECT_LT((state.positions[pin.vertex] - expected).norm(), 1e-12);
  }
}

TEST(Projective, EnergyStaysBelowItsStartWithoutInputWhenConverged) {
  // Converged, it is backward Euler, which dissipates. (With its default 10 iterations the
  // stiff springs of this cloth stay stretched and the energy rises above the start: the
  // solver's open problem, docs/solvers.md.)
  const Model model = hanging(R"({"type": "projective", "iterations": 300, "tolerance": 1e-12, "max_halvings": 0})");
  State state = initial_state(model);
  Integrator integrator(model);
  const Scalar start = kinetic_energy(model, state) + potential_energy(model, state);
  for (int k = 0; k < 200; ++k) {
    ASSERT_TRUE(integrator.step(state).ok);
    EXPECT_LE(kinetic_energy(model, state) + potential_energy(model, state), start) << "step " << k;
  }
}

namespace {

// A 1 m cloth dropped 0.1 m onto a 0.5 m sphere standing on the ground.
Model landing_on_a_sphere() {
  return model_of(R"({"frame_time": 0.04, "frame_steps": 8,
    "cloths": [{"grid": {"size": [1, 1], "resolution": [16, 16]}, "transform": {"translate": [0, 0, 1.1]}}],
    "obstacles": [{"sphere": {"center": [0, 0, 0.5], "radius": 0.5}}, {"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
    "solver": {"type": "projective"}})");
}

}  // namespace

TEST(Projective, AClothLandingOnASphereStaysOutsideItAndAtRest) {
  // 3.6 s: it lands at about 0.2 s and settles, swaying; its kinetic energy falls unevenly
  // (2-6x up and down from frame to frame: 9e-5 J at 1.6 s, 1.9e-4 J at 2 s, 1.1e-4 J at 2.4 s,
  // 1.9e-5 J at 3.6 s; a first guess without the air's damping gave 6e-4, 1e-4, 4.6e-5 and
  // 1.7e-5 J), so it is checked after 3.6 s, not 2.4 s.
  const Model model = landing_on_a_sphere();
  State state = initial_state(model);
  Integrator integrator(model);
  const Scalar start = kinetic_energy(model, state) + potential_energy(model, state);
  for (int k = 0; k < 8 * 90; ++k) {
    const StepReport r = integrator.step(state);
    ASSERT_TRUE(r.ok) << r.failure;
    EXPECT_LE(kinetic_energy(model, state) + potential_energy(model, state), start) << "step " << k;
    for (const Vec3& x : state.positions) EXPECT_GE((x - Vec3(0, 0, 0.5)).norm(), 0.5 + 0.005 - 1e-9);
  }
  // It rests on the sphere: the top vertex within the held gap (1.05 thicknesses) plus a tenth.
  Scalar closest = 1;
  for (const Vec3& x : state.positions) closest = std::min(closest, (x - Vec3(0, 0, 0.5)).norm() - 0.5);
  EXPECT_LT(closest, 0.005 * 1.15);
  EXPECT_LT(kinetic_energy(model, state), 1e-4);
  EXPECT_LT(max_stretch(model, state), 1.05);
}

TEST(Projective, TheSolveHoldsARestingClothOnASphereAndTheResponseHasNothingToDo) {
  // The spheres and planes are constraints of L-BFGS's iterates: at rest (after 1.2 s) every
  // step is one solve and no vertex ends within the thickness (the response moves none).
  const Model model = landing_on_a_sphere();
  State state = initial_state(model);
  Integrator integrator(model);
  for (int k = 0; k < 8 * 30; ++k) ASSERT_TRUE(integrator.step(state).ok);
  for (int k = 0; k < 8 * 10; ++k) {
    const StepReport r = integrator.step(state);
    ASSERT_TRUE(r.ok) << r.failure;
    EXPECT_LE(r.solver_iterations, model.scene.solver.iterations) << "step " << k;
    EXPECT_EQ(r.obstacle_contacts, 0) << "step " << k;
    for (const Vec3& x : state.positions) EXPECT_GE((x - Vec3(0, 0, 0.5)).norm() - 0.5, 0.005 - 1e-12);
  }
}

TEST(Projective, TheSameBitsForAnyThreadCount) {
  // L-BFGS's passes over springs and vertices run in parallel (several blocks of springs
  // here): one, two and three threads give the same positions to the last bit.
  const Model model = model_of(R"({"frame_time": 0.04, "frame_steps": 8,
    "cloths": [{"grid": {"size": [1, 1], "resolution": [48, 48]}, "transform": {"translate": [0, 0, 1.02]}}],
    "obstacles": [{"sphere": {"center": [0, 0, 0.5], "radius": 0.5}}], "solver": {"type": "projective"}})");
  ASSERT_GT(model.vertex_count(), 2048u);  // more than one block of vertices and of springs
  ASSERT_GT(model.springs.size(), 2u * 2048);
  std::vector<State> states;
  for (int threads : {1, 2, 3}) {
    State state = initial_state(model);
    Integrator integrator(model, threads);
    for (int k = 0; k < 24; ++k) ASSERT_TRUE(integrator.step(state).ok);
    states.push_back(state);
  }
  for (std::size_t t = 1; t < states.size(); ++t)
    for (std::size_t v = 0; v < states[0].positions.size(); ++v) ASSERT_EQ(states[t].positions[v], states[0].positions[v]) << v;
}
