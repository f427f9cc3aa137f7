#pragma once
// One measurement in a child process, so that its peak resident memory is its own and a crash
// loses only it. The result travels back through a pipe, so it must be plain data. The parent
// must not have started OpenMP or BLAS threads before it forks (a child may then hang).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <type_traits>

namespace drape::bench {

struct ChildRun {
  bool returned = false;  ///< the child sent its whole result
  int status = 0;         ///< its wait status
  long peak_kib = 0;      ///< its peak resident memory
};

/// Runs run() in a child and copies its result into result.
template <class Result, class Run>
ChildRun run_in_child(Run run, Result& result) {
  static_assert(std::is_trivially_copyable_v<Result>, "the result crosses a pipe");
  ChildRun child_run;
  int channel[2];
  if (pipe(channel) != 0) return child_run;
  const pid_t child = fork();
  if (child == 0) {
    close(channel[0]);
    const Result r = run();
    const ssize_t written = write(channel[1], &r, sizeof r);
    _exit(written == sizeof r ? 0 : 1);
  }
  close(channel[1]);
  const ssize_t got = read(channel[0], &result, sizeof result);
  close(channel[0]);
  rusage usage{};
  wait4(child, &child_run.status, 0, &usage);
  child_run.returned = got == sizeof result;
  child_run.peak_kib = usage.ru_maxrss;
  return child_run;
}

}  // namespace drape::bench
