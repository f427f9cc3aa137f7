#pragma once
/// \file
/// The speed-accuracy trade: a scene run over a grid of accuracy settings, each run compared
/// with a reference run at the most accurate setting (drape sweep; docs/sweep.md).

#include <filesystem>
#include <functional>
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
  /// "steps=10 solver=cg:1e-06 ccd=vincent thickness=0.005 impulses=8 zones=16"
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

/// Runs the reference (reference_setting) then every setting for frames frames, with the
/// independent penetration check on every frame. on_result is called after each run (the
/// reference first). When the reference stops early only its result is returned: there is
/// nothing to compare the others with.
std::vector<SweepResult> run_sweep(const Scene& scene, const SweepSetting& reference_setting,
                                   const std::vector<SweepSetting>& settings, int frames,
                                   const std::function<void(const SweepResult&, std::size_t done, std::size_t total)>& on_result);

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
