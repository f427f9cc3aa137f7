#pragma once
// The temporary folder of one test process, removed when the process exits.
#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <system_error>

namespace drape::testing {

/// drape_<suite>_<pid> under the system's temporary folder (suite names the test file): every
/// such folder a process asked for is removed with what it holds when the process exits, so
/// that test runs (a process per test under ctest) leave nothing behind.
inline std::filesystem::path temp_root(const std::string& suite) {
  struct Roots {
    std::mutex mutex;
    std::set<std::filesystem::path> paths;
    ~Roots() {
      std::error_code ignored;  // a folder already gone, or one a child process holds open
      for (const auto& path : paths) std::filesystem::remove_all(path, ignored);
    }
  };
  static Roots roots;
  auto path = std::filesystem::temp_directory_path() / ("drape_" + suite + "_" + std::to_string(::getpid()));
  const std::lock_guard<std::mutex> lock(roots.mutex);
  roots.paths.insert(path);
  return path;
}

}  // namespace drape::testing
