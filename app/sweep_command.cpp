// drape sweep: a scene over a grid of accuracy settings against a reference run (sweep/sweep.h).
#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "drape/sweep/sweep.h"
#include "ranks.h"

namespace drape::app {
namespace {

struct SweepArguments {
  std::string scene;
  int frames = 30;
  std::vector<int> steps;
  std::vector<std::string> solvers{"cholmod", "cg:1e-3", "cg:1e-6"};
  std::vector<std::string> methods{"vincent", "conservative"};
  std::vector<double> thickness;
  std::vector<int> impulses;
  std::vector<int> zones;
  std::vector<std::string> self_in_solve;
  int reference_steps = 0;
  std::string out;
  bool plot = true;
};

std::atomic<bool> sweep_interrupted{false};
extern "C" void on_sweep_interrupt(int) { sweep_interrupted.store(true); }

int sweep(const SweepArguments& args, const Ranks& ranks) {
  Scene scene;
  try {
    scene = load_scene(args.scene);
  } catch (const SceneError& e) {
    std::cerr << "drape sweep: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  SweepGrid grid;
  grid.frame_steps = args.steps;
  if (grid.frame_steps.empty())
    grid.frame_steps = {std::max(1, scene.frame_steps / 2), scene.frame_steps, 2 * scene.frame_steps};
  std::sort(grid.frame_steps.begin(), grid.frame_steps.end());  // a scene of 1 step: {1, 1, 2}
  grid.frame_steps.erase(std::unique(grid.frame_steps.begin(), grid.frame_steps.end()), grid.frame_steps.end());
  try {
    for (const std::string& s : args.solvers) grid.solvers.push_back(parse_solver_setting(s, scene.solver));
  } catch (const std::invalid_argument& e) {
    std::cerr << "drape sweep: --solvers " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  for (const std::string& m : args.methods) grid.methods.push_back(*ccd::parse_method(m));
  for (double t : args.thickness) grid.thickness.push_back(t);
  if (grid.thickness.empty()) grid.thickness = {scene.collisions.thickness};
  grid.max_impulse_iterations = args.impulses;
  if (grid.max_impulse_iterations.empty()) grid.max_impulse_iterations = {scene.collisions.max_impulse_iterations};
  grid.max_zone_iterations = args.zones;
  if (grid.max_zone_iterations.empty()) grid.max_zone_iterations = {scene.collisions.max_zone_iterations};
  for (const std::string& held : args.self_in_solve) grid.self_in_solve.push_back(held == "on");
  if (grid.self_in_solve.empty()) grid.self_in_solve = {scene.collisions.self_in_solve};

  // The reference: the most accurate setting the knobs allow.
  SweepSetting reference = setting_of(scene);
  reference.frame_steps = args.reference_steps > 0
                              ? args.reference_steps
                              : 2 * *std::max_element(grid.frame_steps.begin(), grid.frame_steps.end());
  reference.solver.kind = SolverKind::Cholmod;
  for (const SolverSpec& tried : grid.solvers)
    if (tried.kind == SolverKind::Cholmod) reference.solver.release_solves = std::max(reference.solver.release_solves, tried.release_solves);
  reference.method = ccd::Method::Conservative;
  reference.max_impulse_iterations =
      std::max(scene.collisions.max_impulse_iterations,
               *std::max_element(grid.max_impulse_iterations.begin(), grid.max_impulse_iterations.end()));
  reference.max_zone_iterations =
      std::max(scene.collisions.max_zone_iterations,
               *std::max_element(grid.max_zone_iterations.begin(), grid.max_zone_iterations.end()));

  const std::string name = std::filesystem::path(args.scene).stem().string();
  SweepPlan plan;
  plan.scene = scene;
  plan.reference = reference;
  plan.settings = grid.settings();
  plan.frames = args.frames;
  plan.out = args.out.empty() ? std::filesystem::path("out") / (name + "_sweep") : std::filesystem::path(args.out);
  std::vector<std::size_t> pending;
  if (ranks.rank() == 0) {
    if (const std::string why = claim_output_folder(plan.out, "sweep.lock"); !why.empty()) {
      std::cerr << "drape sweep: " << why << "\n";
      return ranks.broadcast(EXIT_BAD_INPUT);
    }
    try {
      check_sweep_plan(plan);
    } catch (const SceneError& e) {
      std::cerr << "drape sweep: " << e.what() << "\n";
      return ranks.broadcast(EXIT_BAD_INPUT);
    }
    for (std::size_t i = 0; i < plan.size(); ++i)
      if (!sweep_run_done(plan, i)) pending.push_back(i);
    // The longest first (the most steps a frame): the last runs to finish are short ones.
    std::stable_sort(pending.begin(), pending.end(),
                     [&](std::size_t a, std::size_t b) { return plan.setting(a).frame_steps > plan.setting(b).frame_steps; });
    std::printf("drape sweep %s: %zu settings and the reference (%s), %d frames each; %zu runs kept already, %zu to run on "
                "%d %s\n",
                args.scene.c_str(), plan.settings.size(), reference.label().c_str(), args.frames, plan.size() - pending.size(),
                pending.size(), ranks.size(), ranks.size() == 1 ? "process" : "MPI ranks");
    std::fflush(stdout);
  }
  if (ranks.broadcast(EXIT_OK) != EXIT_OK) return EXIT_BAD_INPUT;

  std::signal(SIGINT, on_sweep_interrupt);
  std::signal(SIGTERM, on_sweep_interrupt);
  std::string error_message;
  ranks.run(pending, [&](std::size_t i) {
    std::optional<SweepResult> r;
    try {
      r = run_sweep_run(plan, i, sweep_interrupted);
    } catch (const std::runtime_error& e) {  // a scene a setting makes invalid, or a run that cannot be kept
      std::fprintf(stderr, "%sdrape sweep: %s\n", ranks.prefix().c_str(), e.what());
      return true;  // missing from the table; the others go on
    }
    if (!r) return false;
    std::printf("%s[run %zu/%zu] %-72s %9.1f ms/frame  pen %ld%s%s\n", ranks.prefix().c_str(), i, plan.size() - 1,
                (i == 0 ? "reference " + r->setting.label() : r->setting.label()).c_str(), r->wall_ms_per_frame,
                r->penetrations, r->failed ? "  FAILED: " : "", r->failure.c_str());
    std::fflush(stdout);
    return true;
  });
  if (ranks.rank() != 0) return ranks.broadcast(EXIT_OK);

  // Rank 0: every kept run against the reference, in the grid's order.
  std::vector<SweepResult> results;
  try {
    results = gather_sweep(plan);
    write_sweep_csv(plan.out / "sweep.csv", results);
  } catch (const std::runtime_error& e) {
    std::cerr << "drape sweep: " << e.what() << "\n";
    return ranks.broadcast(EXIT_BAD_INPUT);
  }
  const std::filesystem::path out = plan.out;
  if (results.empty() || results.front().failed) {
    std::cerr << "drape sweep: "
              << (results.empty() ? std::string("the reference run was not done") : "the reference run stopped at " + results.front().failure)
              << "; nothing to compare with (" << (out / "sweep.csv").string() << " holds what it did)\n";
    return ranks.broadcast(EXIT_RUN_STOPPED);
  }
  if (results.size() < plan.size()) {
    std::cerr << "drape sweep: " << plan.size() - results.size()
              << " runs not done (interrupted, or a run that could not be kept); start the same command again to run only "
                 "those\n";
    ranks.broadcast(EXIT_RUN_STOPPED);
    return EXIT_RUN_STOPPED;
  }
  for (const SweepResult& r : results)
    std::printf("%-82s %9.1f ms/frame  rms %.3e m  max %.3e m  pen %ld%s%s\n",
                (r.reference ? "reference " + r.setting.label() : r.setting.label()).c_str(), r.wall_ms_per_frame, r.rms_error,
                r.max_error, r.penetrations, r.failed ? "  FAILED: " : "", r.failure.c_str());
  ranks.broadcast(EXIT_OK);
  std::printf("\nPareto front (fastest first; no other run is both faster and closer to the reference):\n");
  std::vector<const SweepResult*> front;
  for (const SweepResult& r : results)
    if (r.pareto) front.push_back(&r);
  std::sort(front.begin(), front.end(), [](auto* a, auto* b) { return a->wall_ms_per_frame < b->wall_ms_per_frame; });
  for (const SweepResult* r : front)
    std::printf("  %-72s %9.1f ms/frame  rms %.3e m\n", r->setting.label().c_str(), r->wall_ms_per_frame, r->rms_error);
  std::printf("table: %s\n", (out / "sweep.csv").c_str());
  if (args.plot) {
    const std::string why = plot_sweep(out / "sweep.png", results, "drape sweep " + name + ": time against error, " +
                                                                       std::to_string(args.frames) + " frames");
    if (why.empty()) std::printf("plot: %s\n", (out / "sweep.png").c_str());
    else std::fprintf(stderr, "drape sweep: warning: no plot: %s (the table is written)\n", why.c_str());
  }
  return EXIT_OK;
}

}  // namespace

Command add_sweep_command(CLI::App& app) {
  auto args = std::make_shared<SweepArguments>();
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "Run a scene over a grid of accuracy settings and compare each run with a reference at the most accurate "
      "setting: time per frame, vertex error (RMS and max), energy, penetrations, failures. Writes sweep.csv and a "
      "plot of time against error with the Pareto front (sweep.png, gnuplot).");
  cmd->add_option("scene", args->scene, "Scene file (JSON)")->required()->check(EXISTING_FILE);
  cmd->add_option("--frames", args->frames, "Frames per run")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--steps", args->steps, "Steps per frame to try (default: half, once and twice the scene's)")
      ->delimiter(',')
      ->check(CLI::Range(1, 10000));
  cmd->add_option("--solvers", args->solvers, "Solvers to try: cholmod or cholmod:release_solves=N, cg or cg:TOLERANCE, projective or projective:NAME=VALUE[:NAME=VALUE...] with iterations, history, tolerance, chebyshev (docs/sweep.md)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--methods", args->methods, "CCD methods to try")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::IsMember({"cubic", "dnf", "vincent", "conservative"}));
  cmd->add_option("--thickness", args->thickness, "Collision thicknesses to try, m (default: the scene's)")
      ->delimiter(',')
      ->check(FINITE_NUMBER)
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--impulses", args->impulses, "max_impulse_iterations values to try (default: the scene's)")
      ->delimiter(',')
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--zones", args->zones, "max_zone_iterations values to try (default: the scene's)")
      ->delimiter(',')
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--self-in-solve", args->self_in_solve,
                  "collisions.self_in_solve values to try: on (self contacts held in the cholmod solve), off (the "
                  "response alone); default: the scene's")
      ->delimiter(',')
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--reference-steps", args->reference_steps,
                  "Steps per frame of the reference run (default: twice the most tried); the reference also uses "
                  "cholmod, the conservative CCD method, the scene's thickness and self_in_solve, and the most impulse and zone "
                  "rounds")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--out", args->out, "Output folder (default: out/<scene>_sweep)");
  cmd->add_flag("!--no-plot", args->plot, "Write the table only");
  cmd->footer(
      "Example:\n"
      "  drape sweep scenes/cloth_fold.json --frames 30 --steps 5,10,20 --solvers cholmod,cg:1e-3,cg:1e-6\n"
      "Runs that stop count as failed; a run is on the Pareto front when it did not fail, has no penetration, and no\n"
      "other such run is both faster and closer to the reference. docs/sweep.md explains how to read the result.");
  return [args] {
    try {
      const Ranks ranks;
      const int status = sweep(*args, ranks);
      return status;
    } catch (const std::runtime_error& e) {
      std::cerr << "drape sweep: " << e.what() << "\n";
      return EXIT_BAD_INPUT;
    }
  };
}

}  // namespace drape::app
