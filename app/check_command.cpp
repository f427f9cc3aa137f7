// drape check: the independent penetration check over every saved frame of a run.
#include <iostream>
#include <limits>

#include "commands.h"
#include "drape/core/mesh_io.h"
#include "drape/core/penetration.h"
#include "drape/core/run.h"
#include "run_folder.h"

namespace drape::app {
namespace {

namespace fs = std::filesystem;

int check(const std::string& folder_name, std::size_t max_pairs) {
  const fs::path folder(folder_name);
  std::optional<RunFolder> run = open_run_folder(folder, "check");
  if (!run) return EXIT_BAD_INPUT;
  const Model& model = run->model;
  const auto& frames = run->frames;
  const TriangleMesh topology = model.cloth_mesh(model.initial_positions);
  int bad_frames = 0;
  for (const auto& [frame, path] : frames) {
    std::vector<Vec3> positions;
    try {
      positions = load_frame_positions(path, topology);
    } catch (const MeshFileError& e) {
      std::cerr << "drape check: " << e.what() << "\n";
      return EXIT_BAD_INPUT;
    }
    const auto found = find_penetrations(model, positions, frame * model.scene.frame_time, max_pairs);
    if (found.empty()) continue;
    ++bad_frames;
    std::cout << "frame " << frame << ": " << found.size() << (found.size() >= max_pairs ? "+" : "") << " intersecting pairs\n";
    for (std::size_t i = 0; i < std::min<std::size_t>(found.size(), 10); ++i) std::cout << "  " << found[i].describe() << "\n";
  }
  std::cout << folder.string() << ": " << frames.size() << " frames checked, " << bad_frames << " with intersections\n";
  return bad_frames ? EXIT_CHECK_FAILED : EXIT_OK;
}

}  // namespace

Command add_check_command(CLI::App& app) {
  auto folder = std::make_shared<std::string>();
  auto limit = std::make_shared<int>(1000);
  CLI::App* cmd = app.add_subcommand("check", "Check every saved frame of a run for intersecting triangles.");
  cmd->footer(
      "Tests every pair of non-adjacent cloth triangles, cloth against mesh obstacles, and cloth\n"
      "vertices against spheres and planes, with code independent of the CCD pipeline. Prints the\n"
      "frames and pairs that intersect; exit status 1 when any do, 0 when none, 2 on bad input.\n\n"
      "Example:\n  drape run scenes/cloth_fold.json && drape check out/cloth_fold");
  cmd->add_option("folder", *folder, "A run's output folder")->required()->check(CLI::ExistingDirectory);
  // At least one pair: with none to look for, every frame would pass unchecked. An int range,
  // since CLI11 wraps a negative value into a huge unsigned one.
  cmd->add_option("--max-pairs", *limit, "Pairs to look for per frame before moving on")
      ->check(CLI::Range(1, std::numeric_limits<int>::max()))
      ->capture_default_str();
  return [folder, limit] { return check(*folder, std::size_t(*limit)); };
}

}  // namespace drape::app
