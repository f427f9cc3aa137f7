// drape render, and drape run --render: PNG frames and an MP4 of a run's saved meshes.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <limits>
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
  // Ctrl-C finishes the frame in hand and stops: no partial image, an earlier video kept. Caught
  // from the start, so that one during the run folder's reading or OpenGL's start stops cleanly too.
  std::signal(SIGINT, on_render_interrupt);
  std::signal(SIGTERM, on_render_interrupt);
  std::optional<RunFolder> run = open_run_folder(folder, "render");
  if (!run) return EXIT_BAD_INPUT;
  const Model& model = run->model;
  render::RenderSettings settings;
  try {
    settings = render::parse_render_settings(model.scene);
  } catch (const render::RenderError& e) {
    std::cerr << "drape render: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  if (options.width > 0) settings.width = options.width, settings.height = options.height;
  if (options.style) settings.look.style = *options.style;
  if (options.wireframe) settings.look.wireframe = true;
  // The frames asked for, among those the run wrote.
  std::vector<std::pair<int, fs::path>> frames;
  const int first = options.still ? *options.still : options.first_frame, last = options.still ? *options.still : options.last_frame;
  for (const auto& frame : run->frames)
    if (frame.first >= first && frame.first <= last) frames.push_back(frame);
  // A range that names a last frame the run does not have would be cut short in silence.
  const bool past_the_end = !options.still && options.last_frame != std::numeric_limits<int>::max() &&
                            options.last_frame > run->frames.back().first;
  if (frames.empty() || past_the_end) {
    std::cerr << "drape render: " << folder.string() << " has no frame "
              << (options.still || past_the_end ? std::to_string(last) : "from " + std::to_string(first) + " to " + std::to_string(last))
              << "; its frames run from " << run->frames.front().first << " to " << run->frames.back().first << "\n";
    return EXIT_BAD_INPUT;
  }
  const fs::path images = folder / "render";
  std::error_code error;
  if (options.still_output.empty()) fs::create_directories(images, error);
  if (options.still_output.empty() && (error || !fs::is_directory(images))) {
    std::cerr << "drape render: " << images.string() << ": cannot create the folder" << (error ? ": " + error.message() : "") << "\n";
    return EXIT_BAD_INPUT;
  }
  render::Camera camera = settings.camera ? *settings.camera : render::frame_scene(model, Scalar(settings.width) / settings.height);
  if (options.camera_position) camera.position = *options.camera_position;
  if (options.camera_target) camera.target = *options.camera_target;
  if (options.camera_up) camera.up = *options.camera_up;
  if (options.fov) camera.fov_degrees = *options.fov;
  // Each flag that makes the camera impossible named (a scene's camera is checked when parsed).
  const auto camera_flags = [&](bool position_target, bool up) {
    std::string flags;
    const auto add = [&](bool given, const char* flag) {
      if (given) flags += std::string(flags.empty() ? " (" : ", ") + flag;
    };
    if (position_target) add(bool(options.camera_position), "--camera-position"), add(bool(options.camera_target), "--camera-target");
    if (up) add(bool(options.camera_up), "--camera-up");
    return flags.empty() ? flags : flags + ")";
  };
  if (!((camera.target - camera.position).norm() > 0)) {
    std::cerr << "drape render: the camera's position and target must differ" << camera_flags(true, false) << "\n";
    return EXIT_BAD_INPUT;
  }
  if (!(camera.up.cross(camera.target - camera.position).norm() > 0)) {
    std::cerr << "drape render: the camera's up must not be zero or along its view from position to target"
              << camera_flags(true, true) << "\n";
    return EXIT_BAD_INPUT;
  }
  const double fps = settings.fps > 0 ? settings.fps : 1.0 / model.scene.frame_time;
  const TriangleMesh topology = model.cloth_mesh(model.initial_positions);
  try {
    auto renderer = render::make_renderer(settings.width, settings.height, settings.samples);
    std::unique_ptr<render::VideoWriter> video;
    const fs::path video_path = folder / "video.mp4";
    if (options.video && !options.still) {
      if (render::VideoWriter::ffmpeg_available())
        video = std::make_unique<render::VideoWriter>(video_path, settings.width, settings.height, fps);
      else
        std::cerr << "drape render: warning: the ffmpeg program is not on the PATH: PNG frames only, no video\n";
    }
    const auto begin = std::chrono::steady_clock::now();
    const bool terminal = isatty(STDERR_FILENO);
    std::size_t done = 0;
    for (const auto& [frame, path] : frames) {
      if (render_interrupted.load()) {
        video.reset();  // removes the unfinished video
        std::cerr << (terminal ? "\n" : "") << "drape render: interrupted after " << done
                  << " frames; the PNG frames written are whole, an earlier video.mp4 is kept\n";
        return EXIT_RUN_STOPPED;
      }
      const std::vector<Vec3> x = load_frame_positions(path, topology);
      const render::Image image = renderer->render(model, x, frame * model.scene.frame_time, camera, settings.look);
      char name[32];
      std::snprintf(name, sizeof name, "frame_%05d.png", frame);
      const fs::path png = options.still && !options.still_output.empty() ? options.still_output : images / name;
      render::write_png(png, image);
      if (options.still) {
        if (!options.quiet) std::cerr << "drape render: frame " << frame << ": " << png.string() << "\n";
        return EXIT_OK;
      }
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

namespace {

// "X,Y,Z" as three finite numbers.
std::optional<Vec3> parse_vec3(const std::string& text) {
  Vec3 v;
  std::size_t at = 0;
  for (int k = 0; k < 3; ++k) {
    const std::size_t end = k < 2 ? text.find(',', at) : text.size();
    if (end == std::string::npos) return std::nullopt;
    const std::string part = text.substr(at, end - at);
    char* stop = nullptr;
    v[k] = std::strtod(part.c_str(), &stop);
    if (part.empty() || *stop != '\0' || !std::isfinite(v[k])) return std::nullopt;
    at = end + 1;
  }
  return v;
}

// "FIRST:LAST", "FIRST:", ":LAST" or "N" (that frame alone).
bool parse_frame_range(const std::string& text, RenderOptions& options) {
  const std::regex form(R"((\d{0,9})(:?)(\d{0,9}))");
  std::smatch m;
  if (!std::regex_match(text, m, form) || (m[1].length() == 0 && m[3].length() == 0)) return false;
  if (m[2].length() == 0) {
    if (m[3].length() > 0) return false;
    options.first_frame = options.last_frame = std::stoi(m[1]);
    return true;
  }
  if (m[1].length() > 0) options.first_frame = std::stoi(m[1]);
  if (m[3].length() > 0) options.last_frame = std::stoi(m[3]);
  return options.first_frame <= options.last_frame;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto folder = std::make_shared<std::string>();
  auto options = std::make_shared<RenderOptions>();
  struct Text {
    std::string resolution, frames, position, target, up, style;
  };
  auto text = std::make_shared<Text>();
  auto still = std::make_shared<int>(-1);
  auto fov = std::make_shared<double>(0);
  auto output = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("render", "Render a finished run again from its saved meshes, without simulating.");
  cmd->footer(
      "Writes FOLDER/render/frame_NNNNN.png and FOLDER/video.mp4 (H.264, yuv420p; needs the\n"
      "ffmpeg program, else PNGs only); the video holds the frames rendered. Camera, resolution,\n"
      "frame rate, supersampling, style and cloth colours come from the scene's render section\n"
      "(docs/scenes.md); the options below override them for this render. Without a camera the\n"
      "view frames the cloth and obstacles automatically.\n\n"
      "Each cloth's front (the side its triangle normals point to) and back have their own\n"
      "colours: cloth 0 red with a yellow back, cloth 1 blue with a pale blue back, then green,\n"
      "purple, orange and teal, each with a pale back, unless the scene gives its own.\n\n"
      "Examples:\n"
      "  drape render out/drape_sphere --resolution 640x360\n"
      "  drape render out/drape_sphere --still 90 -o sphere.png --camera-position 0,-3,2 --fov 35\n"
      "  drape render out/tablecloth --frames 30:60 --wireframe");
  cmd->add_option("folder", *folder, "A run's output folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--resolution", text->resolution, "WIDTHxHEIGHT, overriding the scene's");
  cmd->add_option("--frames", text->frames, "FIRST:LAST, FIRST: or :LAST (inclusive): only these frames");
  cmd->add_option("--still", *still, "Render frame N alone as a PNG, without a video")->check(CLI::NonNegativeNumber);
  cmd->add_option("-o,--output", *output, "With --still: the PNG's path (default FOLDER/render/frame_NNNNN.png)");
  cmd->add_option("--camera-position", text->position, "X,Y,Z in metres: where the camera is");
  cmd->add_option("--camera-target", text->target, "X,Y,Z in metres: the point it looks at");
  cmd->add_option("--camera-up", text->up, "X,Y,Z: the direction up in the picture (default the scene's, or against gravity)");
  cmd->add_option("--fov", *fov, "Vertical field of view in degrees, from 1 to 170")->check(CLI::Range(1.0, 170.0));
  cmd->add_option("--style", text->style, "shaded (shadows, a grid on the ground; the default) or simple (no shadows, cheaper)");
  cmd->add_flag("--wireframe", options->wireframe, "Draw the cloth's triangle edges over it");
  cmd->add_flag("--no-video", [options](std::int64_t) { options->video = false; }, "PNG frames only");
  cmd->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
  return [folder, options, text, still, fov, output] {
    const auto bad = [](const std::string& what) {
      std::cerr << "drape render: " << what << "\n";
      return EXIT_BAD_INPUT;
    };
    if (!text->resolution.empty() && !parse_resolution(text->resolution, *options))
      return bad("--resolution: expected WIDTHxHEIGHT from 16x16 to 8192x8192, found '" + text->resolution + "'");
    if (!text->frames.empty() && !parse_frame_range(text->frames, *options))
      return bad("--frames: expected FIRST:LAST, FIRST: or :LAST with FIRST <= LAST, found '" + text->frames + "'");
    if (*still >= 0) options->still = *still;
    if (!output->empty() && !options->still) return bad("--output: only with --still (a whole render goes to FOLDER/render/)");
    if (options->still && !text->frames.empty()) return bad("--still and --frames: give one of them");
    options->still_output = *output;
    for (const auto& [name, value, target] : {std::tuple{"--camera-position", &text->position, &options->camera_position},
                                              {"--camera-target", &text->target, &options->camera_target},
                                              {"--camera-up", &text->up, &options->camera_up}})
      if (!value->empty() && !(*target = parse_vec3(*value)))
        return bad(std::string(name) + ": expected X,Y,Z (three numbers, no spaces), found '" + *value + "'");
    if (*fov > 0) options->fov = *fov;
    if (!text->style.empty()) {
      if (text->style != "shaded" && text->style != "simple")
        return bad("--style: expected shaded or simple, found '" + text->style + "'");
      options->style = text->style == "simple" ? render::Look::Style::Simple : render::Look::Style::Shaded;
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
