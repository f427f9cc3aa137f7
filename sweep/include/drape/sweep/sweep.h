#pragma once
/// \file
/// The speed-accuracy sweep: a scene over a grid of accuracy settings against a reference.
///
/// The speed-accuracy trade: a scene run over a grid of accuracy settings, each run compared
/// with a reference run at the most accurate setting (drape sweep; docs/sweep.md).

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "drape/core/scene.h"

namespace drape {

/// One point of the grid: the scene's accuracy knobs.
struct SweepSetting {
  int frame_steps = 0;           ///< implicit steps per frame
  SolverSpec solver;             ///< cholmod, or cg at a tolerance
  ccd::Method method = ccd::Method::Vincent;
  Scalar thickness = 0;          ///< m
  int max_impulse_iterations = 0;
  int max_zone_iterations = 0;
  bool self_in_solve = true;     ///< collisions.self_in_solve: self contacts held in the linearised solve
  /// "steps=10 solver=cg:1e-06 ccd=vincent thickness=0.005 impulses=8 zones=16 self_in_solve=on"
  std::string label() const;
};

/// The scene's own setting.
SweepSetting setting_of(const Scene& scene);

/// The values tried for each knob; the grid is their Cartesian product.
struct SweepGrid {
  std::vector<int> frame_steps;
  std::vector<SolverSpec> solvers;
  std::vector<ccd::Method> methods;
  std::vector<Scalar> thickness;
  std::vector<int> max_impulse_iterations;
  std::vector<int> max_zone_iterations;
  std::vector<bool> self_in_solve;
  std::vector<SweepSetting> settings() const;
};

/// Parses "cholmod" or "cg:TOLERANCE" (cg alone: the scene's tolerance). Throws
/// std::invalid_argument with what was expected.
SolverSpec parse_solver_setting(const std::string& text, const SolverSpec& scene_default);

/// What one run did, against the reference.
struct SweepResult {
  SweepSetting setting;
  bool reference = false;
  bool failed = false;           ///< stopped before the last frame
  std::string failure;           ///< why, when failed
  int frames_done = 0;
  double wall_ms_per_frame = 0;  ///< mean over the frames done, output excluded
  double rms_error = 0;          ///< m: vertex positions against the reference, over vertices and frames done
  double max_error = 0;          ///< m: the largest vertex distance from the reference at any frame done
  double energy_error = 0;       ///< J: the largest |E - E_reference| at any frame (E = kinetic + potential)
  double energy_drift = 0;       ///< J: E at the last frame done minus E at frame 0
  long penetrations = 0;         ///< intersecting triangle pairs (independent check), summed over frames
  bool pareto = false;           ///< on the front: no other successful run is both faster and closer
};

/// A sweep's runs and where they are kept: run 0 is the reference, run i > 0 settings[i - 1].
/// Each run keeps its trajectory (positions and energy at every frame) and its result in
/// out/runs/run_NNN/, which appears whole by rename, so a sweep started again on the same
/// output skips the runs already done, and the runs can be done in any order by any process.
struct SweepPlan {
  Scene scene;
  SweepSetting reference;
  std::vector<SweepSetting> settings;
  int frames = 0;
  std::filesystem::path out;
  std::size_t size() const { return settings.size() + 1; }
  const SweepSetting& setting(std::size_t run) const { return run == 0 ? reference : settings[run - 1]; }
};

/// Throws SceneError when the scene with one of the plan's settings is invalid (a thickness
/// too large for its cloth, say), before anything runs.
void check_sweep_plan(const SweepPlan& plan);

/// Whether run `run` is kept in plan.out for this plan (the same setting, frames and scene text).
bool sweep_run_done(const SweepPlan& plan, std::size_t run);

/// Simulates run `run` for plan.frames frames, with the independent penetration check on every
/// frame, and keeps it in plan.out. Its result has no comparison yet (gather_sweep makes it).
/// Returns nullopt when interrupt is set before the run ends (nothing kept). Throws
/// std::runtime_error when the scene with the setting is invalid or the run cannot be kept.
std::optional<SweepResult> run_sweep_run(const SweepPlan& plan, std::size_t run, const std::atomic<bool>& interrupt);

/// The kept runs, the reference first, each compared with the reference and the Pareto front
/// marked; runs not kept are missing. When the reference stopped early its result alone:
/// there is nothing to compare the others with. Empty without the reference.
std::vector<SweepResult> gather_sweep(const SweepPlan& plan);

/// Marks the Pareto front of time against RMS error among the runs that did not fail and have
/// no penetration (the reference is not a candidate).
void mark_pareto_front(std::vector<SweepResult>& results);

std::string sweep_csv_header();
std::string sweep_csv_row(const SweepResult& r);
/// Writes the CSV (header and a row per result). Throws std::runtime_error.
void write_sweep_csv(const std::filesystem::path& path, const std::vector<SweepResult>& results);

/// Draws time per frame against RMS error (log-log), the front joined and its points named,
/// with gnuplot into png. Returns "" on success, else why not (gnuplot missing or failing).
std::string plot_sweep(const std::filesystem::path& png, const std::vector<SweepResult>& results, const std::string& title);

}  // namespace drape
