#pragma once
/// \file
/// A run: frames of steps, each frame's mesh and statistics written when done.
///
/// A run: frames of steps, each frame's mesh and statistics row written as soon as it is done,
/// so a run that stops keeps everything finished before it.

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "drape/core/integrator.h"

namespace drape {

/// One row of stats.csv. Columns, in order: see stats_header().
struct FrameStats {
  int frame = 0;
  Scalar sim_time = 0;
  double wall_ms = 0;          ///< the frame's steps, output excluded
  double solve_ms = 0;         ///< linear solves only
  long solver_iterations = 0;  ///< summed over the frame's steps (1 per CHOLMOD solve)
  Scalar kinetic_energy = 0;
  Scalar potential_energy = 0;
  Scalar max_stretch = 1;
  std::optional<Scalar> min_distance_obstacle;  ///< empty when the scene has no obstacle
  int obstacle_contacts = 0;   ///< vertices projected out of spheres and planes and faces pushed out of spheres, summed
  int solver_warnings = 0;     ///< cg solves that stopped at the iteration cap
  CollisionCounters collisions;  ///< the collision pipeline, summed over the frame's steps
  std::optional<int> penetrations;  ///< intersecting triangle pairs by the independent check, when enabled
  Scalar external_work = 0;    ///< J, summed since the start: the sources' work (StepReport::external_work)
  Scalar energy_excess = 0;    ///< J: kinetic plus potential energy less (its start plus external_work)
  int step_halvings = 0;       ///< summed StepReport::step_halvings: log2 of the parts each step's kept attempt took
  long strain_limited = 0;     ///< strain limiting's corrections, summed (StepReport::strain_limited)
  double strain_ms = 0;        ///< and their time
  int warnings = 0;            ///< limits passed this frame: energy, stretch (0 to 2)
  std::vector<std::string> messages;  ///< what each warning says, for the terminal (not a column)
};

std::string stats_header();
std::string stats_row(const FrameStats& stats);

struct RunSettings {
  std::filesystem::path out;  ///< output folder (created)
  int frames = 0;             ///< frames to simulate after frame 0 (the initial state)
  bool write_meshes = true;
  int threads = 1;            ///< threads of the narrow phase and the projective solver (results do not depend on it)
  bool check_penetrations = false;  ///< run the independent intersection check on every frame
  bool overwrite = false;     ///< replace an earlier run's files in out (else refuse)
};

/// A run that cannot start: the output folder cannot be created or listed, holds another run
/// (without overwrite), or the scene and its meshes cannot be copied into it. Bad input.
class RunSetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class RunEnd { Completed, Stopped, Interrupted };

struct RunOutcome {
  RunEnd end = RunEnd::Completed;
  int frames_done = 0;  ///< frames simulated and written (frame 0 not counted)
  std::string message;  ///< for Stopped and Interrupted: which frame and why
};

/// Output files of a run folder.
std::filesystem::path mesh_path(const std::filesystem::path& out, int frame, const std::string& format);
inline std::filesystem::path stats_path(const std::filesystem::path& out) { return out / "stats.csv"; }

/// Removes a run folder: drape's files in it (as --overwrite would), then the folder itself.
/// Throws RunSetupError, removing nothing, when it holds anything else.
void remove_run_folder(const std::filesystem::path& out);

/// Simulates and writes frame 0 (the initial state) then settings.frames frames: the meshes,
/// stats.csv, and a copy of the scene (scene.json, its mesh paths pointing at copies of the
/// meshes in meshes/, so the folder is complete by itself). An earlier run's files in the
/// folder are removed first with settings.overwrite, else the run refuses. interrupt is
/// polled between steps; on_frame is called after each frame is written. A write that fails
/// during the run (a full disk) stops it, RunEnd::Stopped naming the file, with every earlier
/// frame and row whole. Throws RunSetupError when the run cannot start.
RunOutcome run_simulation(const Model& model, const RunSettings& settings, const std::atomic<bool>& interrupt,
                          const std::function<void(const FrameStats&)>& on_frame);

}  // namespace drape
