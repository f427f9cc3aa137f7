#pragma once
// Runs the drape program for the end-to-end tests.
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../temp_root.h"

namespace drape::testing {

struct Outcome {
  int status = -1;     // exit status, or -1 when killed by a signal
  std::string output;  // stdout and stderr together
};

/// A shell command line (sh -c), its stdout and stderr together.
inline Outcome run_shell(const std::string& command_line) {
  const std::string command = command_line + " 2>&1";
  Outcome run;
  FILE* pipe = popen(command.c_str(), "r");
  std::array<char, 4096> buffer{};
  while (std::size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) run.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

inline Outcome run_drape(const std::string& arguments) { return run_shell(std::string(DRAPE_EXECUTABLE) + " " + arguments); }

/// The environment that makes a run's bits the same on every x86-64 machine: CHOLMOD's
/// supernodal factorisation calls the BLAS, and OpenBLAS picks its kernels for the processor it
/// runs on (different sums, different rounding: the default scene's kinetic energy parted at
/// frame 10 in the sixth digit between an AVX-512 Intel kernel and AMD's). Pinned to the
/// Nehalem kernels, which every x86-64-v2 processor runs. tools/update-golden.sh sets the same.
inline constexpr const char* REPRODUCIBLE_BLAS = "OPENBLAS_CORETYPE=Nehalem";

/// run_drape with the BLAS kernels pinned (REPRODUCIBLE_BLAS), for results compared with
/// files recorded on another machine.
inline Outcome run_drape_reproducibly(const std::string& arguments) {
  return run_shell(std::string("env ") + REPRODUCIBLE_BLAS + " " + DRAPE_EXECUTABLE + " " + arguments);
}

/// The file's lines, without their line ends.
inline std::vector<std::string> lines(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

/// A fresh path name under the system's temporary folder, unique to this test process
/// (suite names the test file); its parent exists, the path itself does not.
inline std::filesystem::path fresh_temp_path(const std::string& suite, const std::string& name) {
  const auto dir = temp_root(suite) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir.parent_path());
  return dir;
}

}  // namespace drape::testing
