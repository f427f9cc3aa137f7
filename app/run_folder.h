#pragma once
// A run's output folder: its scene copy and its saved frames (shared by check and render).
#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <limits>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "drape/ccd/input_file.h"
#include "drape/core/scene.h"

namespace drape::app {

/// A run folder whose frames cannot be listed. what() names the folder or file and the problem.
class RunFolderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The run's scene: its copy, read as if from where it came so that mesh paths resolve.
inline Scene run_folder_scene(const std::filesystem::path& folder) {
  const std::filesystem::path copy = folder / "scene.json";
  std::error_code error;
  const bool found = std::filesystem::exists(copy, error);
  if (error) throw SceneError(copy.string() + ": cannot look for the scene copy: " + error.message());
  if (!found) throw SceneError(copy.string() + ": not found: is this a drape run folder?");
  std::string text;
  try {
    text = ccd::read_input_file(copy, ccd::MAX_SCENE_BYTES, "scene copy");
  } catch (const ccd::InputFileError& e) {
    throw SceneError(e.what());
  }
  // A run folder holds copies of its meshes (meshes/) and reads as itself; one written by an
  // earlier drape names the scene it came from in scene_path.txt instead.
  std::filesystem::path origin = copy;
  if (std::filesystem::exists(folder / "scene_path.txt", error)) {
    std::string line;
    try {
      line = ccd::read_input_file(folder / "scene_path.txt", 4096, "scene path file");
    } catch (const ccd::InputFileError& e) {
      throw SceneError(e.what());
    }
    line = line.substr(0, line.find('\n'));
    if (!line.empty() && std::filesystem::exists(line, error)) origin = line;
  }
  return parse_scene(text, origin);
}

/// The saved frames frame_NNNNN.<mesh extension>, by frame number. Throws RunFolderError when
/// the folder cannot be listed or a frame number does not fit an int.
inline std::vector<std::pair<int, std::filesystem::path>> run_folder_frames(const std::filesystem::path& folder) {
  std::vector<std::pair<int, std::filesystem::path>> frames;
  const std::regex name(R"(frame_(\d+)\.(obj|ply|stl|gltf|glb|dae))");
  try {
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      std::smatch match;
      const std::string file = entry.path().filename().string();
      if (!std::regex_match(file, match, name)) continue;
      // from_chars, not stoi: a number too large for an int is bad input, not an abort.
      const std::string digits = match[1];
      int frame = 0;
      const auto [end, problem] = std::from_chars(digits.data(), digits.data() + digits.size(), frame);
      if (problem != std::errc() || end != digits.data() + digits.size())
        throw RunFolderError(entry.path().string() + ": expected a frame number from 0 to " +
                             std::to_string(std::numeric_limits<int>::max()) + ", found " + digits);
      frames.emplace_back(frame, entry.path());
    }
  } catch (const std::filesystem::filesystem_error& e) {
    const std::filesystem::path where = e.path1().empty() ? folder : e.path1();
    throw RunFolderError(where.string() + ": cannot list the run's frames: " + e.code().message());
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

/// The last frame stats.csv has a row for (a frame number and the comma after it), or -1
/// without the file or a row: a run writes each frame's mesh before its row, so the meshes
/// must reach it.
inline int last_frame_in_stats(const std::filesystem::path& folder) {
  const std::filesystem::path stats = folder / "stats.csv";
  std::error_code error;
  if (!std::filesystem::exists(stats, error)) return -1;
  std::string text;
  try {
    text = ccd::read_input_file(stats, ccd::MAX_MESH_BYTES, "statistics");
  } catch (const ccd::InputFileError& e) {
    throw RunFolderError(e.what());
  }
  int last = -1;
  std::istringstream lines(text);
  std::string line;
  for (std::getline(lines, line); std::getline(lines, line);) {  // the header first
    int frame = 0;
    const auto [end, problem] = std::from_chars(line.data(), line.data() + line.size(), frame);
    if (problem == std::errc() && end != line.data() + line.size() && *end == ',') last = std::max(last, frame);
  }
  return last;
}

/// A run folder opened for reading: its model and its saved frames.
struct RunFolder {
  Model model;
  std::vector<std::pair<int, std::filesystem::path>> frames;
};

/// Opens a run folder, or prints why it cannot (a bad scene copy, a folder that cannot be
/// listed, no frames) after "drape <command>: " and returns nullopt: bad input, status 2.
inline std::optional<RunFolder> open_run_folder(const std::filesystem::path& folder, const std::string& command) {
  RunFolder run;
  int last_in_stats = -1;
  try {
    run.model = build_model(run_folder_scene(folder));
    run.frames = run_folder_frames(folder);
    last_in_stats = last_frame_in_stats(folder);
  } catch (const SceneError& e) {
    std::cerr << "drape " << command << ": " << e.what() << "\n";
    return std::nullopt;
  } catch (const RunFolderError& e) {
    std::cerr << "drape " << command << ": " << e.what() << "\n";
    return std::nullopt;
  }
  if (run.frames.empty()) {
    std::cerr << "drape " << command << ": " << folder.string() << ": no frame_*.* meshes\n";
    return std::nullopt;
  }
  // A run writes frames 0, 1, 2, ... in order and stops at the first it cannot write: a gap
  // means files were lost or mixed in, and checking or rendering around it would mislead.
  std::vector<int> missing;
  int expected = 0;
  for (const auto& [frame, path] : run.frames) {  // sorted; a number twice (two formats) counts once
    while (expected < frame && missing.size() <= 5) missing.push_back(expected++);
    if (missing.size() > 5) break;
    if (frame == expected) ++expected;
  }
  // Frames lost from the end: stats.csv has their rows.
  for (long frame = long(run.frames.back().first) + 1; frame <= last_in_stats && missing.size() <= 5; ++frame)
    missing.push_back(int(frame));
  if (!missing.empty()) {
    std::string list;
    for (std::size_t i = 0; i < std::min<std::size_t>(missing.size(), 5); ++i)
      list += (i ? ", " : "") + std::to_string(missing[i]);
    std::cerr << "drape " << command << ": " << folder.string() << ": frame" << (missing.size() > 1 ? "s " : " ") << list
              << (missing.size() > 5 ? " and more" : "") << " missing (the folder has frames up to "
              << run.frames.back().first;
    if (last_in_stats >= 0) std::cerr << ", stats.csv rows up to " << last_in_stats;
    std::cerr << ")\n";
    return std::nullopt;
  }
  return run;
}

}  // namespace drape::app
