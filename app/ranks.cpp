// Ranks: MPI (Open MPI) when launched by mpirun or srun, a single process otherwise.
#include "ranks.h"

#include <fcntl.h>
#include <mpi.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace drape::app {
namespace {

// Message tags: a rank asks for work (its int says whether it stopped), rank 0 answers with
// the run's index or -1 for none.
constexpr int TAG_ASK = 1, TAG_GIVE = 2;
constexpr int ASK_MORE = 0, ASK_STOPPED = 1;
// How often rank 0's serving thread looks for a request. A blocking receive in Open MPI spins
// a core, which on a small machine would take it from the runs.
constexpr auto SERVE_INTERVAL = std::chrono::milliseconds(5);

// A task that throws counts as stopped (after saying why): a rank never leaves the hand-out
// without telling rank 0, and rank 0's own thread never ends the process.
bool guarded(const std::function<bool(std::size_t)>& task, std::size_t i, const std::string& prefix) {
  try {
    return task(i);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%sdrape: run %zu: %s; this rank takes no more runs\n", prefix.c_str(), i, e.what());
    return false;
  }
}

bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(name)) return true;
  return false;
}

}  // namespace

Ranks::Ranks() {
  if (!launched_by_mpi()) return;
  int provided = 0;
  // Funneled: only the main thread calls MPI; rank 0's runs go on another thread.
  if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
    throw std::runtime_error("MPI could not start");
  mpi_ = true;
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw std::runtime_error("the MPI library does not allow a second thread (MPI_THREAD_FUNNELED)");
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

Ranks::~Ranks() {
  if (mpi_) MPI_Finalize();
}

std::string Ranks::prefix() const {
  return mpi_ ? "rank " + std::to_string(rank_) + "/" + std::to_string(size_) + ": " : "";
}

void Ranks::run(const std::vector<std::size_t>& pending, const std::function<bool(std::size_t)>& task) const {
  if (!mpi_ || size_ == 1) {
    for (const std::size_t i : pending)
      if (!guarded(task, i, prefix())) break;
    return;
  }
  if (rank_ != 0) {
    int ask = ASK_MORE;
    for (;;) {
      MPI_Send(&ask, 1, MPI_INT, 0, TAG_ASK, MPI_COMM_WORLD);
      long long index = -1;
      MPI_Recv(&index, 1, MPI_LONG_LONG, 0, TAG_GIVE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      if (index < 0 || ask == ASK_STOPPED) break;
      if (!guarded(task, std::size_t(index), prefix())) ask = ASK_STOPPED;
    }
    return;
  }
  // Rank 0: a thread runs its own share while this one answers the others.
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stopped{false};
  const auto take = [&]() -> long long {
    if (stopped.load()) return -1;
    const std::size_t k = next.fetch_add(1);
    return k < pending.size() ? static_cast<long long>(pending[k]) : -1;
  };
  std::thread own([&] {
    for (long long i = take(); i >= 0; i = take())
      if (!guarded(task, std::size_t(i), prefix())) {
        stopped.store(true);
        break;
      }
  });
  int working = size_ - 1;
  while (working > 0) {
    int waiting = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, TAG_ASK, MPI_COMM_WORLD, &waiting, &status);
    if (!waiting) {
      std::this_thread::sleep_for(SERVE_INTERVAL);
      continue;
    }
    int ask = ASK_MORE;
    MPI_Recv(&ask, 1, MPI_INT, status.MPI_SOURCE, TAG_ASK, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (ask == ASK_STOPPED) stopped.store(true);
    const long long index = ask == ASK_STOPPED ? -1 : take();
    MPI_Send(&index, 1, MPI_LONG_LONG, status.MPI_SOURCE, TAG_GIVE, MPI_COMM_WORLD);
    if (index < 0) --working;
  }
  own.join();
}

std::string claim_output_folder(const std::filesystem::path& folder, const std::string& lock_name) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error || !std::filesystem::is_directory(folder))
    return folder.string() + ": cannot create the output folder" + (error ? ": " + error.message() : "");
  const std::filesystem::path lock_file = folder / lock_name;
  const int fd = ::open(lock_file.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (fd < 0) return lock_file.string() + ": cannot open the lock file: " + std::strerror(errno);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int why = errno;
    ::close(fd);
    if (why == EWOULDBLOCK)
      return lock_file.parent_path().string() + ": another drape batch or sweep is running on this folder (" +
             lock_file.filename().string() + " is locked); wait for it, or give another --out";
    return lock_file.string() + ": cannot lock: " + std::strerror(why);
  }
  return "";  // the descriptor stays open, and the lock held, until the process ends
}

int Ranks::broadcast(int value) const {
  if (mpi_) MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return value;
}

}  // namespace drape::app
