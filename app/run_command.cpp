// drape run and drape validate: load a scene, build the model, simulate, report.
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <set>

#include "commands.h"
#include "drape/core/penetration.h"
#include "drape/core/run.h"
#include "drape/render/renderer.h"

namespace drape::app {
namespace {

std::atomic<bool> interrupted{false};
extern "C" void on_interrupt(int) { interrupted.store(true); }

std::string format_duration(double seconds) {
  char text[32];
  if (seconds < 60) std::snprintf(text, sizeof text, "%.0fs", seconds);
  else if (seconds < 3600) std::snprintf(text, sizeof text, "%dm%02ds", int(seconds) / 60, int(seconds) % 60);
  else std::snprintf(text, sizeof text, "%dh%02dm", int(seconds) / 3600, int(seconds) / 60 % 60);
  return text;
}

// A progress bar on a terminal, one line per frame otherwise, nothing with --quiet.
class Progress {
 public:
  Progress(int frames, bool quiet) : frames_(frames), quiet_(quiet), terminal_(isatty(STDERR_FILENO)) {}
  void frame(const FrameStats& s) {
    warn(s);
    if (quiet_ || s.frame == 0) return;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double left = elapsed / s.frame * (frames_ - s.frame);
    if (terminal_) {
      constexpr int WIDTH = 30;
      const int filled = WIDTH * s.frame / frames_;
      std::fprintf(stderr, "\r[%s%s] frame %d/%d  %s left  ", std::string(filled, '#').c_str(),
                   std::string(WIDTH - filled, '.').c_str(), s.frame, frames_, format_duration(left).c_str());
      if (s.frame == frames_) std::fprintf(stderr, "\n");
    } else {
      std::fprintf(stderr, "frame %d/%d  t=%.3fs  %.0f ms  kinetic %.4g J  %s left\n", s.frame, frames_, s.sim_time,
                   s.wall_ms, s.kinetic_energy, format_duration(left).c_str());
    }
  }
  void end_line() {
    if (terminal_ && !quiet_) std::fprintf(stderr, "\n");
  }
  // After the run: how many frames passed a limit (each said when it first happened).
  void summary() const {
    if (warned_frames_ > 0)
      std::fprintf(stderr, "drape run: warning: %d frame(s) passed a limit (column warnings of stats.csv; docs/scenes.md, \"limits\")\n",
                   warned_frames_);
  }

 private:
  // A limit passed: said on the terminal the first time for each kind, even with --quiet (a
  // warning is not progress), counted always.
  void warn(const FrameStats& s) {
    if (s.warnings > 0) ++warned_frames_;
    for (const std::string& message : s.messages) {
      const std::string kind = message.substr(0, message.find(' '));
      if (!said_.insert(kind).second) continue;
      if (terminal_ && !quiet_) std::fprintf(stderr, "\n");
      std::fprintf(stderr, "drape run: warning: frame %d: %s (said once; later frames are counted)\n", s.frame, message.c_str());
    }
  }
  int warned_frames_ = 0;
  std::set<std::string> said_;
  int frames_;
  bool quiet_, terminal_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

struct RunArguments {
  std::string scene;
  int frames = 0;
  std::string out;
  bool quiet = false;
  int threads = 1;
  bool check = false;
  std::string method;
  bool render = false;
  bool overwrite = false;
  std::string resolution;
};

// The cloth's elastic elements as the summaries print them: its springs, and its membrane
// triangles and bending stencils where it has them (a mesh cloth with "membrane": "triangles"
// holds its fabric by triangles, not springs).
std::string elements(const Model& model) {
  std::string text = std::to_string(model.springs.size()) + " springs";
  if (!model.membranes.empty()) text += ", " + std::to_string(model.membranes.size()) + " membrane triangles";
  // A grid's bending stencils (a grid, or a mesh on a grid's lattice) or hinges (other meshes).
  if (!model.hinges.empty()) {
    const auto lattice = std::count_if(model.cloths.begin(), model.cloths.end(), [](const ClothRange& c) { return c.lattice_bending; });
    text += ", " + std::to_string(model.hinges.size()) +
            (lattice == 0 ? " bending hinges" : lattice == long(model.cloths.size()) ? " bending stencils (a grid's)"
                                                                                     : " bending stencils and hinges");
  }
  return text;
}

// Loads and builds; prints the error and returns nullopt on bad input.
std::optional<Model> load_model(const std::string& path, const char* command, const std::string& method = "") {
  try {
    Scene scene = load_scene(path);
    if (!method.empty()) scene.collisions.method = *ccd::parse_method(method);
    Model model = build_model(scene);
    if (const std::string note = thickness_note(model); !note.empty())
      std::cerr << "drape " << command << ": " << path << ": warning: " << note << "\n";
    const StartCheck start = check_start(model);
    if (!start.error.empty()) throw SceneError(start.error);
    if (!start.warning.empty()) std::cerr << "drape " << command << ": " << path << ": warning: " << start.warning << "\n";
    return model;
  } catch (const SceneError& e) {
    std::cerr << "drape " << command << ": " << e.what() << "\n";
  }
  return std::nullopt;
}

int run(const RunArguments& args) {
  std::optional<Model> model = load_model(args.scene, "run", args.method);
  if (!model) return EXIT_BAD_INPUT;
  const Scene& scene = model->scene;
  // The scene's render section may ask for frames even without --render; it is checked now,
  // before simulating, so a bad render section costs no run.
  bool wants_render = false;
  try {
    wants_render = render::parse_render_settings(scene).enabled;
  } catch (const render::RenderError& e) {
    std::cerr << "drape run: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  // So is the --resolution flag.
  RenderOptions render_options;
  render_options.quiet = args.quiet;
  if (!args.resolution.empty() && !parse_resolution(args.resolution, render_options)) {
    std::cerr << "drape run: --resolution: expected WIDTHxHEIGHT from 16x16 to 8192x8192, found '" << args.resolution << "'\n";
    return EXIT_BAD_INPUT;
  }
  if (!args.resolution.empty() && !args.render && !wants_render) {
    std::cerr << "drape run: --resolution sets the rendered frames' size; expected --render beside it (or the scene's "
                 "render.enabled)\n";
    return EXIT_BAD_INPUT;
  }
  RunSettings settings;
  settings.out = args.out.empty() ? scene.output.folder : std::filesystem::path(args.out);
  settings.frames = args.frames > 0 ? args.frames : scene.frames;
  settings.write_meshes = scene.output.meshes;
  settings.threads = args.threads;
  settings.check_penetrations = args.check;
  settings.overwrite = args.overwrite;
  if (!args.quiet)
    std::cerr << "drape run: " << args.scene << ": " << model->vertex_count() << " vertices, " << elements(*model)
              << ", " << settings.frames << " frames of " << scene.frame_steps << " steps; output in "
              << settings.out.string() << "/\n";

  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  Progress progress(settings.frames, args.quiet);
  RunOutcome outcome;
  try {
    outcome = run_simulation(*model, settings, interrupted, [&](const FrameStats& s) { progress.frame(s); });
  } catch (const std::exception& e) {
    progress.end_line();
    std::cerr << "drape run: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  if (outcome.end != RunEnd::Completed) {
    progress.end_line();
    progress.summary();
    if (args.render || wants_render) std::cerr << "drape run: not rendering a run that stopped; 'drape render' can\n";
    std::cerr << "drape run: stopped: " << outcome.message << " (in " << settings.out.string() << "/)\n";
    return EXIT_RUN_STOPPED;
  }
  progress.summary();
  if (!args.quiet)
    std::cerr << "drape run: done: " << outcome.frames_done << " frames; meshes and stats.csv in " << settings.out.string()
              << "/\n";
  if (args.render || wants_render) return render_run(settings.out, render_options);
  return EXIT_OK;
}

}  // namespace

Command add_run_command(CLI::App& app) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* cmd = app.add_subcommand("run", "Simulate a scene: write each frame's cloth mesh and a row of stats.csv.");
  cmd->footer(
      "Output (in the scene's output folder, out/<scene name> by default, or --out):\n"
      "  frame_00000.obj ...  the cloth at each frame (frame 0 is the initial state)\n"
      "  stats.csv            one row per frame: timings, solver iterations, energies, stretch,\n"
      "                       distance to the obstacles\n"
      "  scene.json, meshes/  a copy of the scene and of its meshes: the folder is complete by itself\n"
      "  render/*.png, video.mp4  with --render (or the scene's render.enabled)\n"
      "A run that has to stop (solver failure, NaN, the cloth leaving the scene bounds, a full\n"
      "disk, Ctrl-C) says which frame and why, exits with status 3 and keeps every frame written\n"
      "so far. A folder holding an earlier run is refused (status 2) unless --overwrite.\n\n"
      "Examples:\n"
      "  drape run scenes/drape_sphere.json\n"
      "  drape run scenes/flag.json --frames 10 --out /tmp/flag --quiet");
  cmd->add_option("scene", args->scene, "Scene file (JSON; see docs/scenes.md)")->required()->check(EXISTING_FILE);
  cmd->add_option("--frames", args->frames, "Frames to simulate (default: the scene's)")->check(CLI::Range(1, 10000000));
  cmd->add_option("--out", args->out, "Output folder (default: the scene's output.folder)")
      ->check(CLI::Validator([](std::string& path) { return path.empty() ? std::string("expected a folder's path, not an empty string") : std::string(); },
                             "PATH"));
  cmd->add_flag("-q,--quiet", args->quiet, "Print nothing but errors");
  cmd->add_option("-j,--threads", args->threads, "Threads for the collision narrow phase and the projective solver (results do not depend on it)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_option("--ccd", args->method, "CCD method, overriding the scene's collisions.method")
      ->check(CLI::IsMember({"cubic", "dnf", "vincent", "conservative"}));
  cmd->add_flag("--render", args->render, "Then render PNG frames and an MP4 video (see 'drape render --help')");
  cmd->add_option("--resolution", args->resolution, "With --render: WIDTHxHEIGHT, overriding the scene's");
  cmd->add_flag("--overwrite", args->overwrite,
                "Replace an earlier run in the output folder (its frames, stats.csv, scene copy, renders); without it\n"
                "a run into a folder holding another one refuses");
  cmd->add_flag("--check", args->check, "Run the independent penetration check on every frame (column penetrations)");
  return [args] { return run(*args); };
}

Command add_validate_command(CLI::App& app) {
  auto scene = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("validate", "Check a scene file (and its meshes) without running it.");
  cmd->footer("Exit status 0 when the scene is valid, 2 with a message naming the file and JSON path otherwise.");
  cmd->add_option("scene", *scene, "Scene file")->required()->check(EXISTING_FILE);
  return [scene] {
    const std::optional<Model> model = load_model(*scene, "validate");
    if (!model) return EXIT_BAD_INPUT;
    // The render section too, with the parser drape run uses.
    try {
      render::parse_render_settings(model->scene);
    } catch (const render::RenderError& e) {
      std::cerr << "drape validate: " << e.what() << "\n";
      return EXIT_BAD_INPUT;
    }
    std::cout << *scene << ": valid: " << model->cloths.size() << " cloth(s), " << model->vertex_count() << " vertices, "
              << model->triangles.size() << " triangles, " << elements(*model) << ", " << model->pins.size()
              << " pinned vertices, " << model->obstacles.size() << " obstacle(s); " << model->scene.frames
              << " frames of " << model->scene.frame_steps << " steps\n";
    return EXIT_OK;
  };
}

}  // namespace drape::app
