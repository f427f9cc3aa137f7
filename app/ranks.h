#pragma once
/// \file
/// The processes a batch or a sweep runs on: the ranks of an MPI job when drape was started by
/// mpirun or srun, else this process alone. The runs are handed out one at a time to whichever
/// rank asks next (runs differ in cost by 100x); rank 0 hands them out and also runs its share,
/// on a thread of its own.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace drape::app {

class Ranks {
 public:
  /// Joins the MPI job when the environment says this process is one of its ranks (Open
  /// MPI's mpirun, or a PMI/PMIx launcher such as Slurm's srun); otherwise one rank alone,
  /// without MPI. Throws std::runtime_error when MPI cannot start.
  Ranks();
  ~Ranks();  ///< leaves the MPI job
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool mpi() const { return mpi_; }
  /// "rank 1/4: " under MPI, "" alone: a prefix for progress lines.
  std::string prefix() const;

  /// Runs task(i) for every i of pending (meaningful on rank 0; the other ranks take what it
  /// hands them). task returns false when interrupted: that rank takes no more, and rank 0
  /// hands out no more. Returns on every rank once every rank has finished its last task.
  void run(const std::vector<std::size_t>& pending, const std::function<bool(std::size_t)>& task) const;

  /// Rank 0's value, on every rank.
  int broadcast(int value) const;

 private:
  int rank_ = 0, size_ = 1;
  bool mpi_ = false;
};

/// Creates the output folder of a batch or sweep and takes an exclusive lock (flock) on its
/// lock file for the rest of the process: two of them on one folder would remove each other's
/// unfinished runs. Returns "" when done, else why not. The lock goes with the process, killed
/// or not.
std::string claim_output_folder(const std::filesystem::path& folder, const std::string& lock_name);

}  // namespace drape::app
