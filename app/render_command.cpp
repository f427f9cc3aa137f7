// drape render, and drape run --render: PNG frames and an MP4 of a run's saved meshes.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <regex>

#include "commands.h"
#include "drape/core/mesh_io.h"
#include "drape/core/run.h"
#include "drape/render/renderer.h"
#include "run_folder.h"

namespace drape::app {

namespace fs = std::filesystem;

std::atomic<bool> render_interrupted{false};
extern "C" void on_render_interrupt(int) { render_interrupted.store(true); }

int render_run(const fs::path& folder, const RenderOptions& options) {
  std::optional<RunFolder> run = open_run_folder(folder, "render");
  if (!run) return EXIT_BAD_INPUT;
  const Model& model = run->model;
  const auto& frames = run->frames;
  render::RenderSettings settings;
  try {
    settings = render::parse_render_settings(model.scene);
  } catch (const render::RenderError& e) {
    std::cerr << "drape render: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  if (options.width > 0) settings.width = options.width, settings.height = options.height;
  const fs::path images = folder / "render";
  std::error_code error;
  fs::create_directories(images, error);
  if (error || !fs::is_directory(images)) {
    std::cerr << "drape render: " << images.string() << ": cannot create the folder" << (error ? ": " + error.message() : "") << "\n";
    return EXIT_BAD_INPUT;
  }
  const render::Camera camera =
      settings.camera ? *settings.camera : render::frame_scene(model, Scalar(settings.width) / settings.height);
  const double fps = settings.fps > 0 ? settings.fps : 1.0 / model.scene.frame_time;
  const TriangleMesh topology = model.cloth_mesh(model.initial_positions);
  try {
    auto renderer = render::make_renderer(settings.width, settings.height, settings.samples);
    std::unique_ptr<render::VideoWriter> video;
    const fs::path video_path = folder / "video.mp4";
    if (options.video) {
      if (render::VideoWriter::ffmpeg_available())
        video = std::make_unique<render::VideoWriter>(video_path, settings.width, settings.height, fps);
      else
        std::cerr << "drape render: warning: the ffmpeg program is not on the PATH: PNG frames only, no video\n";
    }
    const auto begin = std::chrono::steady_clock::now();
    const bool terminal = isatty(STDERR_FILENO);
    std::size_t done = 0;
    // Ctrl-C finishes the frame in hand and stops: no partial image, an earlier video kept.
    std::signal(SIGINT, on_render_interrupt);
    std::signal(SIGTERM, on_render_interrupt);
    for (const auto& [frame, path] : frames) {
      if (render_interrupted.load()) {
        video.reset();  // removes the unfinished video
        std::cerr << (terminal ? "\n" : "") << "drape render: interrupted after " << done
                  << " frames; the PNG frames written are whole, an earlier video.mp4 is kept\n";
        return EXIT_RUN_STOPPED;
      }
      const std::vector<Vec3> x = load_frame_positions(path, topology);
      const render::Image image = renderer->render(model, x, frame * model.scene.frame_time, camera);
      char name[32];
      std::snprintf(name, sizeof name, "frame_%05d.png", frame);
      render::write_png(images / name, image);
      if (video) video->add(image);
      // On a terminal one line rewritten; in a log a line every tenth of the frames.
      ++done;
      if (!options.quiet && terminal)
        std::cerr << "\rdrape render: frame " << frame << "/" << frames.back().first << std::flush;
      else if (!options.quiet && (done % std::max<std::size_t>(1, frames.size() / 10) == 0))
        std::cerr << "drape render: frame " << frame << "/" << frames.back().first << "\n";
    }
    if (video) video->close();
    if (!options.quiet) {
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
      std::cerr << (terminal ? "\r" : "") << "drape render: " << frames.size() << " frames (" << settings.width << "x" << settings.height << ", "
                << seconds * 1e3 / frames.size() << " ms a frame) in " << images.string() << "/";
      if (video) std::cerr << "; video: " << video_path.string();
      std::cerr << "\n";
    }
  } catch (const std::exception& e) {
    // Ctrl-C reaches ffmpeg too (one process group): its broken pipe is the interruption.
    if (render_interrupted.load()) {
      std::cerr << "\ndrape render: interrupted; the PNG frames written are whole, an earlier video.mp4 is kept\n";
      return EXIT_RUN_STOPPED;
    }
    std::cerr << "\ndrape render: " << e.what() << " (the simulation output is untouched)\n";
    return EXIT_BAD_INPUT;
  }
  return EXIT_OK;
}

Command add_render_command(CLI::App& app) {
  auto folder = std::make_shared<std::string>();
  auto options = std::make_shared<RenderOptions>();
  auto resolution = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("render", "Render a finished run again from its saved meshes, without simulating.");
  cmd->footer(
      "Writes FOLDER/render/frame_NNNNN.png and FOLDER/video.mp4 (H.264, yuv420p; needs the\n"
      "ffmpeg program, else PNGs only). Camera, resolution, frame rate and supersampling come\n"
      "from the scene's render section (docs/scenes.md); without a camera the view frames the\n"
      "cloth and obstacles automatically.\n\n"
      "Example:\n  drape render out/drape_sphere --resolution 640x360");
  cmd->add_option("folder", *folder, "A run's output folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--resolution", *resolution, "WIDTHxHEIGHT, overriding the scene's");
  cmd->add_flag("--no-video", [options](std::int64_t) { options->video = false; }, "PNG frames only");
  cmd->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
  return [folder, options, resolution] {
    if (!resolution->empty() && !parse_resolution(*resolution, *options)) {
      std::cerr << "drape render: --resolution: expected WIDTHxHEIGHT from 16x16 to 8192x8192, found '" << *resolution << "'\n";
      return EXIT_BAD_INPUT;
    }
    return render_run(*folder, *options);
  };
}

bool parse_resolution(const std::string& text, RenderOptions& options) {
  const std::regex form(R"((\d{1,5})x(\d{1,5}))");
  std::smatch m;
  if (!std::regex_match(text, m, form)) return false;
  options.width = std::stoi(m[1]);
  options.height = std::stoi(m[2]);
  return options.width >= 16 && options.height >= 16 && options.width <= 8192 && options.height <= 8192;
}

}  // namespace drape::app
