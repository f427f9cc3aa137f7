// drape measure: the textile laboratory's measurements on a run's saved frames, the Cusick
// drape test and the cantilever bending test (core/textile.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

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

// The Cusick test on one frame: prints its drape coefficient and nodes.
int measure_cusick_test(const MeasureArguments& args, const Model& model, int frame, const std::vector<Vec3>& positions,
                        const Vec3& down) {
  // The axis through the cloth's centre at the start, along gravity; the fabric's radius, its
  // largest distance from the axis at the start (a flat disc's).
  CusickSetup setup;
  setup.down = down;
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
  const Scalar threshold = NODE_PROMINENCE * setup.fabric_radius;
  if (args.json) {
    std::string depths;
    for (const Scalar d : r.node_depths) {
      char number[32];
      std::snprintf(number, sizeof number, "%.5f", double(d));
      depths += (depths.empty() ? "" : ", ") + std::string(number);
    }
    std::printf("{\"frame\": %d, \"fabric_radius_m\": %.6g, \"support_radius_m\": %.6g, \"shadow_area_m2\": %.6g, "
                "\"drape_coefficient\": %.4f, \"nodes\": %d, \"node_depths_m\": [%s], \"node_threshold_m\": %.5f}\n",
                frame, double(setup.fabric_radius), double(setup.support_radius), double(r.shadow_area),
                double(r.drape_coefficient), r.nodes, depths.c_str(), double(threshold));
  } else {
    std::printf("%s, frame %d: Cusick drape coefficient %.4f, %d nodes (shadow %.2f cm^2; fabric disc radius %.2f cm%s, "
                "support %.2f cm)\n",
                args.folder.c_str(), frame, double(r.drape_coefficient), r.nodes, double(r.shadow_area) * 1e4,
                double(setup.fabric_radius) * 100, args.fabric_radius > 0 ? "" : " from frame 0", double(setup.support_radius) * 100);
    if (!r.node_depths.empty()) {
      std::printf("  node depths, cm, around the axis:");
      for (const Scalar d : r.node_depths) std::printf(" %.2f", double(d) * 100);
      std::printf(" (a node from %.2f cm; the shallowest %.2f cm)\n", double(threshold) * 100,
                  double(*std::min_element(r.node_depths.begin(), r.node_depths.end())) * 100);
    }
  }
  return EXIT_OK;
}

// The cantilever test on one frame: the strip's overhang and tip drop, the bending length the
// heavy elastica gives for that drop, and, for a material with a bending rigidity, the drop
// the elastica predicts from it.
int measure_cantilever_test(const MeasureArguments& args, const Model& model, int frame, const std::vector<Vec3>& positions,
                            const Vec3& down) {
  if (model.cloths.size() != 1) {
    std::cerr << "drape measure: " << args.folder << ": expected one cloth (the strip), found " << model.cloths.size() << "\n";
    return EXIT_BAD_INPUT;
  }
  const Material& material = model.scene.cloths.front().material;
  const Scalar weight = material.density * model.scene.gravity.norm();  // N/m^2
  if (!(weight > 0)) {
    std::cerr << "drape measure: " << args.folder << ": expected gravity (the strip bends under its own weight)\n";
    return EXIT_BAD_INPUT;
  }
  std::vector<bool> held(model.vertex_count());
  for (std::size_t v = 0; v < held.size(); ++v) held[v] = model.pin_of_vertex[v] >= 0;
  CantileverResult r;
  Scalar measured = 0;
  try {
    r = measure_cantilever(model.initial_positions, positions, held, down);
    measured = elastica_bending_length(r.clamped_length(), r.drop);
  } catch (const std::invalid_argument& e) {
    std::cerr << "drape measure: " << args.folder << ", frame " << frame << ": " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  const Scalar rigidity = material.bending_rigidity;                      // N m, 0 for bending springs
  const Scalar expected_length = rigidity > 0 ? std::cbrt(rigidity / weight) : 0;
  const Scalar expected_drop = rigidity > 0 ? heavy_elastica_drop(r.clamped_length(), weight / rigidity) : 0;
  if (args.json) {
    std::printf("{\"frame\": %d, \"overhang_m\": %.6g, \"clamped_length_m\": %.6g, \"tip_drop_m\": %.6g, "
                "\"bending_length_m\": %.6g, \"flexural_rigidity_Nm\": %.6g",
                frame, double(r.overhang), double(r.clamped_length()), double(r.drop), double(measured),
                double(weight * measured * measured * measured));
    if (rigidity > 0)
      std::printf(", \"material_bending_length_m\": %.6g, \"elastica_drop_m\": %.6g, \"drop_over_elastica\": %.4f",
                  double(expected_length), double(expected_drop), double(r.drop / expected_drop));
    std::printf("}\n");
    return EXIT_OK;
  }
  std::printf("%s, frame %d: cantilever overhang %.2f cm (clamped length %.2f cm), tip drop %.2f cm:\n"
              "  bending length %.3f cm, flexural rigidity %.3g N m (mass per area %.4g g/m^2)\n",
              args.folder.c_str(), frame, double(r.overhang) * 100, double(r.clamped_length()) * 100, double(r.drop) * 100,
              double(measured) * 100, double(weight * measured * measured * measured), double(material.density) * 1000);
  if (rigidity > 0)
    std::printf("  the material's bending rigidity %.3g N m: bending length %.3f cm, the heavy elastica's drop %.2f cm; "
                "measured / elastica %.4f\n",
                double(rigidity), double(expected_length) * 100, double(expected_drop) * 100, double(r.drop / expected_drop));
  else
    std::printf("  the material bends by springs ('bend'), which have no bending rigidity to compare with\n");
  return EXIT_OK;
}

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
  const Vec3 down = model.scene.gravity.norm() > 0 ? Vec3(model.scene.gravity.normalized()) : Vec3(-Vec3::UnitZ());
  return args.test == "cusick" ? measure_cusick_test(args, model, chosen->first, positions, down)
                               : measure_cantilever_test(args, model, chosen->first, positions, down);
}

}  // namespace

Command add_measure_command(CLI::App& app) {
  auto args = std::make_shared<MeasureArguments>();
  CLI::App* cmd = app.add_subcommand("measure", "Measure a run as the textile laboratory would (the Cusick drape test, the cantilever test).");
  cmd->add_option("test", args->test, "The test: cusick or cantilever")->required()->check(CLI::IsMember({"cusick", "cantilever"}));
  cmd->add_option("folder", args->folder, "A run's output folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--frame", args->frame, "The frame to measure (default the last)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--support-radius", args->support_radius, "cusick: the support disc's radius, m")
      ->capture_default_str()
      ->check(FINITE_NUMBER)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--fabric-radius", args->fabric_radius, "cusick: the fabric disc's radius, m (default: the cloth's at frame 0)")
      ->check(FINITE_NUMBER)
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", args->json, "One JSON object");
  cmd->footer(
      "cusick (BS 5058, ISO 9073-9): the shadow of the draped cloth cast along gravity, against\n"
      "the fabric disc and the support disc (18 cm across by default). Drape coefficient =\n"
      "(shadow - support disc) / (fabric disc - support disc): 1 for a cloth that stays flat, 0\n"
      "for one that hangs straight down. Nodes: the folds, peaks of the shadow's outline around\n"
      "the axis (smoothed over 5 degrees) that rise 3 % of the fabric radius above the troughs\n"
      "beside them; each node's depth is printed (how far it rises above the higher of the two),\n"
      "so a count that hangs on a node near the threshold shows. The axis passes through the\n"
      "cloth's centre at frame 0.\n\n"
      "cantilever (Peirce; ASTM D1388): one strip, held at one end by a handle (the clamp), its\n"
      "free end overhanging. The tip's drop since frame 0 gives the bending length c, the heavy\n"
      "elastica's for that drop (solved numerically), and the flexural rigidity w g c^3; for a\n"
      "material with a bending_rigidity, also the elastica's drop for it and measured / elastica.\n"
      "The strip bends from half a quad behind its last held vertex (a hinge's dual cell): the\n"
      "clamped length.\n\n"
      "Examples:\n  drape run scenes/cusick_drape.json && drape measure cusick out/cusick_drape\n"
      "  drape run scenes/cantilever.json && drape measure cantilever out/cantilever");
  return [args] { return measure(*args); };
}

}  // namespace drape::app
