#pragma once
// A run's output folder: its scene copy and its saved frames (shared by check and render).
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <utility>
#include <vector>

#include "drape/core/scene.h"

namespace drape::app {

/// The run's scene: its copy, read as if from where it came so that mesh paths resolve.
inline Scene run_folder_scene(const std::filesystem::path& folder) {
  const std::filesystem::path copy = folder / "scene.json";
  if (!std::filesystem::exists(copy)) throw SceneError(copy.string() + ": not found: is this a drape run folder?");
  std::ifstream in(copy);
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::path origin = copy;
  if (std::ifstream where{folder / "scene_path.txt"}; where) {
    std::string line;
    std::getline(where, line);
    if (!line.empty() && std::filesystem::exists(line)) origin = line;
  }
  return parse_scene(text.str(), origin);
}

/// The saved frames frame_NNNNN.<mesh extension>, by frame number.
inline std::vector<std::pair<int, std::filesystem::path>> run_folder_frames(const std::filesystem::path& folder) {
  std::vector<std::pair<int, std::filesystem::path>> frames;
  const std::regex name(R"(frame_(\d+)\.(obj|ply|stl|gltf|glb|dae))");
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    std::smatch match;
    const std::string file = entry.path().filename().string();
    if (std::regex_match(file, match, name)) frames.emplace_back(std::stoi(match[1]), entry.path());
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

}  // namespace drape::app
