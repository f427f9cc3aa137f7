// The speed-accuracy sweep: the grid, the solver setting parser, the Pareto front, and runs
// compared with the reference.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>

#include "drape/sweep/sweep.h"
#include "../temp_root.h"

using namespace drape;

namespace {

SweepResult result(double ms, double rms, bool failed = false, long penetrations = 0) {
  SweepResult r;
  r.wall_ms_per_frame = ms;
  r.rms_error = rms;
  r.failed = failed;
  r.penetrations = penetrations;
  return r;
}

}  // namespace

TEST(Sweep, GridIsTheProductOfTheKnobs) {
  SweepGrid grid;
  grid.frame_steps = {5, 10, 20};
  SolverSpec projective;
  projective.kind = SolverKind::Projective;
  grid.solvers = {SolverSpec{}, SolverSpec{SolverKind::ConjugateGradient, 1e-4, 100}, projective};
  grid.methods = {ccd::Method::Vincent, ccd::Method::Conservative};
  grid.thickness = {0.005};
  grid.max_impulse_iterations = {4, 8};
  grid.max_zone_iterations = {16};
  grid.self_in_solve = {true, false};
  const auto settings = grid.settings();
  EXPECT_EQ(settings.size(), 3u * 3 * 2 * 1 * 2 * 1 * 2);
  EXPECT_EQ(settings.front().label(), "steps=5 solver=cholmod:release_solves=1 ccd=vincent thickness=0.005 impulses=4 zones=16 self_in_solve=on");
  EXPECT_EQ(settings.back().label(), "steps=20 solver=projective:iterations=10:history=5:tolerance=1e-08:chebyshev=0.99 ccd=conservative thickness=0.005 impulses=8 zones=16 self_in_solve=off");
}

TEST(Sweep, SolverSettings) {
  const SolverSpec scene{SolverKind::Cholmod, 1e-8, 500};
  EXPECT_EQ(parse_solver_setting("cholmod", scene).kind, SolverKind::Cholmod);
  EXPECT_EQ(parse_solver_setting("cholmod", scene).release_solves, scene.release_solves);
  EXPECT_EQ(parse_solver_setting("cholmod:release_solves=0", scene).release_solves, 0);
  EXPECT_EQ(parse_solver_setting("cholmod:release_solves=8", scene).release_solves, 8);
  const SolverSpec cg = parse_solver_setting("cg", scene);
  EXPECT_EQ(cg.kind, SolverKind::ConjugateGradient);
  EXPECT_EQ(cg.tolerance, 1e-8);
  EXPECT_EQ(cg.max_iterations, 500);
  EXPECT_EQ(parse_solver_setting("cg:1e-3", scene).tolerance, 1e-3);
  const SolverSpec projective = parse_solver_setting("projective:iterations=20:chebyshev=0.95:history=0", scene);
  EXPECT_EQ(projective.kind, SolverKind::Projective);
  EXPECT_EQ(projective.iterations, 20);
  EXPECT_EQ(projective.chebyshev, 0.95);
  EXPECT_EQ(projective.history, 0);
  const SolverSpec quasi_newton = parse_solver_setting("projective:tolerance=1e-3:history=8", scene);
  EXPECT_EQ(quasi_newton.tolerance, 1e-3);
  EXPECT_EQ(quasi_newton.history, 8);
  EXPECT_EQ(quasi_newton.iterations, scene.iterations);
  EXPECT_EQ(parse_solver_setting("projective:iterations=5", scene).iterations, 5);
  EXPECT_EQ(parse_solver_setting("projective:iterations=5", scene).chebyshev, scene.chebyshev);
  EXPECT_EQ(parse_solver_setting("projective", scene).iterations, scene.iterations);
  for (const char* bad : {"lu", "cg:", "cg:abc", "cg:0", "cg:2", "cg:1e-3x", "cholmod:1", "cholmod:", "cholmod:release_solves=", "cholmod:release_solves=-1",
                          "cholmod:release_solves=1.5", "cholmod:release_solves=101", "cholmod:iterations=2", "projective:", "projective:0",
                          "projective:10", "projective:10:0.9", "projective:iterations=0", "projective:iterations=2.5",
                          "projective:chebyshev=1", "projective:chebyshev=-0.1", "projective:history=101",
                          "projective:tolerance=2", "projective:iterations=", "projective:speed=3",
                          "projective:iterations=10:", "projectivex"}) {
    try {
      parse_solver_setting(bad, scene);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(Sweep, ParetoFrontKeepsRunsNoOtherBeatsOnBoth) {
  std::vector<SweepResult> r{result(10, 1.0), result(20, 0.5), result(30, 0.6), result(40, 0.1),
                             result(5, 0.01, /*failed=*/true), result(6, 0.01, false, /*penetrations=*/3),
                             result(10, 1.0), result(50, 0.1)};
  r.push_back(result(1, 0));
  r.back().reference = true;
  mark_pareto_front(r);
  const std::vector<bool> expected{true, true, false, true, false, false, true, false, false};
  for (std::size_t i = 0; i < r.size(); ++i) EXPECT_EQ(r[i].pareto, expected[i]) << "run " << i;
}

// A run at the reference's own setting matches it exactly (the simulation is deterministic);
// fewer steps per frame move the cloth elsewhere (without the step's halving, which would take
// the single step of a frame again in the reference's four parts).
TEST(Sweep, RunsAreMeasuredAgainstTheReference) {
  Scene scene = load_scene(DRAPE_SOURCE_DIR "/scenes/hanging.json");
  scene.solver.max_halvings = 0;
  SweepSetting reference = setting_of(scene);
  reference.frame_steps = 4;
  reference.method = ccd::Method::Conservative;
  SweepSetting coarse = reference;
  coarse.frame_steps = 1;
  SweepPlan plan;
  plan.scene = scene;
  plan.reference = reference;
  plan.settings = {reference, coarse};
  plan.frames = 3;
  plan.out = drape::testing::temp_root("sweep_test");
  std::filesystem::remove_all(plan.out);
  const std::atomic<bool> go{false}, stop{true};
  // Interrupted: nothing kept.
  EXPECT_FALSE(run_sweep_run(plan, 2, stop));
  EXPECT_FALSE(sweep_run_done(plan, 2));
  // In any order, each kept when done.
  for (const std::size_t run : {2u, 0u, 1u}) {
    EXPECT_FALSE(sweep_run_done(plan, run));
    ASSERT_TRUE(run_sweep_run(plan, run, go));
    EXPECT_TRUE(sweep_run_done(plan, run));
  }
  const auto results = gather_sweep(plan);
  ASSERT_EQ(results.size(), 3u);
  EXPECT_TRUE(results[0].reference);
  for (const auto& r : results) {
    EXPECT_FALSE(r.failed) << r.failure;
    EXPECT_EQ(r.frames_done, 3);
    EXPECT_GT(r.wall_ms_per_frame, 0);
  }
  EXPECT_EQ(results[1].rms_error, 0.0);
  EXPECT_EQ(results[1].max_error, 0.0);
  EXPECT_GT(results[2].rms_error, 1e-6);
  EXPECT_GE(results[2].max_error, results[2].rms_error);
  EXPECT_GT(results[2].energy_error, 0.0);
  EXPECT_LT(results[0].energy_drift, 0.0);  // a swinging cloth falls: its energy goes to kinetic, then damping
  const std::string row = sweep_csv_row(results[2]), header = sweep_csv_header();
  EXPECT_EQ(std::count(row.begin(), row.end(), ','), std::count(header.begin(), header.end(), ','));
  // A kept run counts only for the same plan: other frames, another setting or an edited scene
  // are run again.
  SweepPlan other = plan;
  other.frames = 4;
  EXPECT_FALSE(sweep_run_done(other, 0));
  other = plan;
  other.settings[1].frame_steps = 2;
  EXPECT_FALSE(sweep_run_done(other, 2));
  EXPECT_TRUE(sweep_run_done(other, 1));
  other = plan;
  other.scene.text += " ";
  EXPECT_FALSE(sweep_run_done(other, 1));
  std::filesystem::remove_all(plan.out);
}
