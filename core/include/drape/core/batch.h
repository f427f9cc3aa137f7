#pragma once
/// \file
/// A batch of scene runs from a manifest, resumable, with one table of outcomes.
///
/// A batch: a list of scene runs from a manifest, each into its own folder, resumable, and one
/// table of their outcomes (drape batch; the app hands the runs out across MPI ranks).
///
/// Every run's outcome is a record file written after the run's folder is complete, so a
/// batch started again on the same output skips the runs with a record and reruns the others
/// from scratch; a run's folder appears by rename, never mixing an old run's frames with a new
/// one's.

#include <atomic>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace drape {

/// A manifest that cannot be read. what() names the file, the place in it and what was expected.
class BatchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One run of a batch.
struct BatchRun {
  std::filesystem::path scene;     ///< the scene file (resolved against the manifest's folder)
  std::string overrides;           ///< a JSON object merged into the scene (RFC 7386 merge patch); "" for none
  int frames = 0;                  ///< frames to simulate; 0: the scene's
  std::filesystem::path out;       ///< the run's folder (resolved against the batch's output folder)
};

struct Batch {
  std::filesystem::path manifest;
  std::filesystem::path out;       ///< the batch's output folder: records/, batch.csv, default run folders
  std::vector<BatchRun> runs;
};

/// Reads a manifest: JSON, {"runs": [{"scene", "frames", "out", "overrides"}, ...]} or the
/// array alone, or CSV with a header naming the columns scene (required), frames, out and
/// overrides (a JSON object, quoted). A run without out goes to out/NNN_<scene name>. Throws
/// BatchError naming the file and the JSON path or CSV line.
Batch load_batch(const std::filesystem::path& manifest, const std::filesystem::path& out);

/// A run's expected cost, to hand out the longest first: vertices times frames times steps a
/// frame (0 for a scene that cannot be read: it fails at once).
double estimated_cost(const BatchRun& run);

/// How a run ended, as drape run's exit status would say it.
enum class BatchStatus { Ok = 0, BadInput = 2, Stopped = 3 };

struct BatchResult {
  std::size_t index = 0;
  BatchStatus status = BatchStatus::Ok;
  std::string message;      ///< why it failed or stopped
  int frames_done = 0;      ///< frames simulated and written (frame 0 not counted)
  double wall_s = 0;        ///< the run's wall time, its output included
  std::string last_stats;   ///< the last row of its stats.csv ("" when none)
};

/// The record of run index when it is complete for this batch (the same scene file's and
/// meshes' bytes, overrides, frames, folder and stats columns), else nullopt: the run has to be
/// done (again). A run that failed for a reason outside its scene (its folder, the disk) is
/// complete only with retryable_too (for the table of the batch that ran it).
std::optional<BatchResult> completed_batch_run(const Batch& batch, std::size_t index, bool retryable_too = false);

/// Runs run index into its folder: into FOLDER.partial (an earlier one removed), renamed into
/// place when it ends, then its record written. A folder already at FOLDER is replaced only
/// when this batch made it (a record or a pending mark of the run) and it holds nothing drape
/// did not write. A bad scene, a run that stops, or a folder or disk in the way is a result,
/// not an exception. Returns nullopt when interrupted: nothing recorded, the partial folder
/// left for the next start to remove. threads: the narrow phase's threads.
std::optional<BatchResult> run_batch_run(const Batch& batch, std::size_t index, int threads,
                                         const std::atomic<bool>& interrupt);

/// batch.csv: a row per run (index, scene, out, status, exit_status, frames, wall_s, message,
/// then the columns of stats.csv from the run's last row). results are indexed like the runs.
std::string batch_csv_header();
void write_batch_csv(const std::filesystem::path& path, const Batch& batch, const std::vector<BatchResult>& results);

}  // namespace drape
