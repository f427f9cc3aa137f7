// drape measure: the textile laboratory's measurements on a run's saved frames
// (core/textile.h).
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "drape/core/mesh_io.h"
#include "drape/core/textile.h"
#include "run_folder.h"

namespace drape::app {
namespace {

namespace fs = std::filesystem;

struct MeasureArguments {
  std::string test;
  std::string folder;
  int frame = -1;  ///< -1: the last
  double support_radius = 0.09;
  double fabric_radius = 0;  ///< 0: from frame 0
  bool json = false;
};

int measure(const MeasureArguments& args) {
  std::optional<RunFolder> run = open_run_folder(args.folder, "measure");
  if (!run) return EXIT_BAD_INPUT;
  const Model& model = run->model;
  const auto& frames = run->frames;
  const auto chosen = args.frame < 0 ? std::prev(frames.end())
                                     : std::find_if(frames.begin(), frames.end(), [&](const auto& f) { return f.first == args.frame; });
  if (chosen == frames.end()) {
    std::cerr << "drape measure: " << args.folder << " has no frame " << args.frame << "; its frames run from "
              << frames.front().first << " to " << frames.back().first << "\n";
    return EXIT_BAD_INPUT;
  }
  std::vector<Vec3> positions;
  try {
    positions = load_frame_positions(chosen->second, model.cloth_mesh(model.initial_positions));
  } catch (const MeshFileError& e) {
    std::cerr << "drape measure: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  // The axis through the cloth's centre at the start, along gravity; the fabric's radius, its
  // largest distance from the axis at the start (a flat disc's).
  CusickSetup setup;
  setup.down = model.scene.gravity.norm() > 0 ? Vec3(model.scene.gravity.normalized()) : Vec3(-Vec3::UnitZ());
  setup.centre = Vec3::Zero();
  for (const Vec3& x : model.initial_positions) setup.centre += x;
  setup.centre /= Scalar(model.vertex_count());
  Scalar widest = 0;
  for (const Vec3& x : model.initial_positions) {
    const Vec3 d = x - setup.centre;
    widest = std::max(widest, (d - d.dot(setup.down) * setup.down).norm());
  }
  setup.fabric_radius = args.fabric_radius > 0 ? args.fabric_radius : widest;
  setup.support_radius = args.support_radius;
  CusickResult r;
  try {
    r = measure_cusick(positions, model.triangles, setup);
  } catch (const std::invalid_argument& e) {
    std::cerr << "drape measure: --support-radius " << setup.support_radius << ", fabric radius " << setup.fabric_radius << ": "
              << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  if (args.json) {
    std::printf("{\"frame\": %d, \"fabric_radius_m\": %.6g, \"support_radius_m\": %.6g, \"shadow_area_m2\": %.6g, "
                "\"drape_coefficient\": %.4f, \"nodes\": %d}\n",
                chosen->first, double(setup.fabric_radius), double(setup.support_radius), double(r.shadow_area),
                double(r.drape_coefficient), r.nodes);
  } else {
    std::printf("%s, frame %d: Cusick drape coefficient %.4f, %d nodes (shadow %.2f cm^2; fabric disc radius %.2f cm%s, "
                "support %.2f cm)\n",
                args.folder.c_str(), chosen->first, double(r.drape_coefficient), r.nodes, double(r.shadow_area) * 1e4,
                double(setup.fabric_radius) * 100, args.fabric_radius > 0 ? "" : " from frame 0", double(setup.support_radius) * 100);
  }
  return EXIT_OK;
}

}  // namespace

Command add_measure_command(CLI::App& app) {
  auto args = std::make_shared<MeasureArguments>();
  CLI::App* cmd = app.add_subcommand("measure", "Measure a run as the textile laboratory would (the Cusick drape test).");
  cmd->add_option("test", args->test, "The test: cusick")->required()->check(CLI::IsMember({"cusick"}));
  cmd->add_option("folder", args->folder, "A run's output folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--frame", args->frame, "The frame to measure (default the last)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--support-radius", args->support_radius, "The support disc's radius, m")
      ->capture_default_str()
      ->check(FINITE_NUMBER)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--fabric-radius", args->fabric_radius, "The fabric disc's radius, m (default: the cloth's at frame 0)")
      ->check(FINITE_NUMBER)
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", args->json, "One JSON object");
  cmd->footer(
      "cusick (BS 5058, ISO 9073-9): the shadow of the draped cloth cast along gravity, against\n"
      "the fabric disc and the support disc (18 cm across by default). Drape coefficient =\n"
      "(shadow - support disc) / (fabric disc - support disc): 1 for a cloth that stays flat, 0\n"
      "for one that hangs straight down. Nodes: the folds, peaks of the shadow's outline around\n"
      "the axis (smoothed over 5 degrees) that rise 3 % of the fabric radius above the troughs\n"
      "beside them. The axis passes through the cloth's centre at frame 0.\n\n"
      "Example:\n  drape run scenes/cusick_drape.json && drape measure cusick out/cusick_drape");
  return [args] { return measure(*args); };
}

}  // namespace drape::app
