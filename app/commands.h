#pragma once
/// \file
/// The subcommands of the drape program. Each registers its options on the CLI11 app and
/// returns the function that runs it; the function returns the process exit status.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>

#include "drape/render/renderer.h"

namespace drape::app {

/// Exit statuses shared by all commands.
inline constexpr int EXIT_OK = 0;
inline constexpr int EXIT_CHECK_FAILED = 1;  ///< the command ran and found a problem
inline constexpr int EXIT_BAD_INPUT = 2;     ///< a flag, scene, mesh or query file is malformed
inline constexpr int EXIT_RUN_STOPPED = 3;   ///< a simulation had to stop (or was interrupted)

using Command = std::function<int()>;

// CLI11's ExistingFile, with the reason a path is not a readable file named: no such file, a
// loop of symbolic links ("Too many levels of symbolic links"), a folder.
inline const CLI::Validator EXISTING_FILE(
    [](std::string& input) -> std::string {
      std::error_code error;
      const std::filesystem::file_status status = std::filesystem::status(input, error);
      if (status.type() == std::filesystem::file_type::not_found) return "no such file: " + input;
      if (error) return input + ": " + error.message();
      if (std::filesystem::is_directory(status)) return input + " is a folder; expected a file";
      return {};
    },
    "FILE");

// CLI11's ranges let NaN through (every comparison with it is false), and a tolerance or
// thickness must be a finite number.
inline const CLI::Validator FINITE_NUMBER(
    [](std::string& input) {
      char* end = nullptr;
      const double value = std::strtod(input.c_str(), &end);
      if (input.empty() || *end != '\0' || !std::isfinite(value)) return "expected a finite number, found '" + input + "'";
      return std::string();
    },
    "FINITE");


Command add_ccd_command(CLI::App& app);
Command add_run_command(CLI::App& app);
Command add_validate_command(CLI::App& app);
Command add_check_stats_command(CLI::App& app);
Command add_check_command(CLI::App& app);
Command add_render_command(CLI::App& app);
Command add_sweep_command(CLI::App& app);
Command add_batch_command(CLI::App& app);
Command add_measure_command(CLI::App& app);

/// Options of a render, from drape render or drape run --render.
struct RenderOptions {
  int width = 0, height = 0;  ///< 0: the scene's
  bool video = true;
  bool quiet = false;
  int first_frame = 0, last_frame = std::numeric_limits<int>::max();  ///< the frames to render
  std::optional<int> still;             ///< render this frame alone, no video
  std::filesystem::path still_output;   ///< the still's file; empty: FOLDER/render/frame_NNNNN.png
  std::optional<Vec3> camera_position, camera_target, camera_up;  ///< over the scene's camera
  std::optional<double> fov;
  std::optional<render::Look::Style> style;
  bool wireframe = false;
};
/// Renders a run folder's saved frames; returns the exit status.
int render_run(const std::filesystem::path& folder, const RenderOptions& options);
/// Parses WIDTHxHEIGHT into options; false when malformed or out of range.
bool parse_resolution(const std::string& text, RenderOptions& options);

}  // namespace drape::app
