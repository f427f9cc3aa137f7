#include "drape/core/run.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <regex>
#include <vector>

#include "drape/ccd/input_file.h"
#include "drape/core/mesh_io.h"
#include "drape/core/output_file.h"
#include "drape/core/obstacle.h"
#include "drape/core/penetration.h"
#include "drape/core/stats_columns.h"

namespace drape {

namespace {

// A cell's text: an integer, a number to the last bit, a time in ms to the microsecond, or an
// optional value (empty when absent).
std::string integer(long long v) { return std::to_string(v); }
std::string exact(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}
std::string milliseconds(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", v);
  return text;
}

constexpr ColumnTolerance TIMING{0, 0, true};
constexpr ColumnTolerance EXACT{0, 0};
constexpr ColumnTolerance COUNT{2, 0.05};  // counts of work that rounding can tip: iterations, contacts

}  // namespace

const std::vector<StatsColumn>& stats_columns() {
  using S = const FrameStats&;
  static const std::vector<StatsColumn> columns = {
      {"frame", [](S s) { return integer(s.frame); }, EXACT},
      {"sim_time", [](S s) { return exact(s.sim_time); }, {1e-12, 1e-12}},
      {"wall_ms", [](S s) { return milliseconds(s.wall_ms); }, TIMING},
      {"solve_ms", [](S s) { return milliseconds(s.solve_ms); }, TIMING},
      {"solver_iterations", [](S s) { return integer(s.solver_iterations); }, COUNT},
      {"kinetic_energy", [](S s) { return exact(s.kinetic_energy); }},
      {"potential_energy", [](S s) { return exact(s.potential_energy); }},
      {"max_stretch", [](S s) { return exact(s.max_stretch); }},
      {"min_distance_obstacle", [](S s) { return s.min_distance_obstacle ? exact(*s.min_distance_obstacle) : std::string(); },
       {1e-7, 1e-6}},
      {"obstacle_contacts", [](S s) { return integer(s.obstacle_contacts); }, COUNT},
      {"solver_warnings", [](S s) { return integer(s.solver_warnings); }, EXACT},
      {"bvh_pairs", [](S s) { return integer(s.collisions.bvh_pairs); }},
      {"culled_triangles", [](S s) { return integer(s.collisions.culled_triangles); }},
      {"vf_tests", [](S s) { return integer(s.collisions.vf_tests); }},
      {"ee_tests", [](S s) { return integer(s.collisions.ee_tests); }},
      {"culled", [](S s) { return integer((long long)s.collisions.tests.culled); }},
      {"separated", [](S s) { return integer((long long)s.collisions.tests.separated); }},
      {"root_solves", [](S s) { return integer((long long)s.collisions.tests.root_solves); }},
      {"ccd_hits", [](S s) { return integer(s.collisions.ccd_hits); }},
      {"impulse_iterations", [](S s) { return integer(s.collisions.impulse_iterations); }},
      {"impact_zones", [](S s) { return integer(s.collisions.impact_zones); }},
      {"proximity_impulses", [](S s) { return integer(s.collisions.proximity_impulses); }},
      {"held_self_contacts", [](S s) { return integer(s.collisions.held_self_contacts); }},
      {"rest_clamped_pairs", [](S s) { return integer(s.collisions.rest_clamped_pairs); }},
      {"fail_safes", [](S s) { return integer(s.collisions.fail_safes); }, EXACT},
      {"ccd_ms", [](S s) { return milliseconds(s.collisions.ccd_ms); }, TIMING},
      {"broad_ms", [](S s) { return milliseconds(s.collisions.broad_ms); }, TIMING},
      {"narrow_ms", [](S s) { return milliseconds(s.collisions.narrow_ms); }, TIMING},
      {"response_ms", [](S s) { return milliseconds(s.collisions.response_ms); }, TIMING},
      {"penetrations", [](S s) { return s.penetrations ? integer(*s.penetrations) : std::string(); }, EXACT},
      {"external_work", [](S s) { return exact(s.external_work); }},
      {"energy_excess", [](S s) { return exact(s.energy_excess); }},
      {"step_halvings", [](S s) { return integer(s.step_halvings); }},
      {"strain_limited", [](S s) { return integer(s.strain_limited); }, COUNT},
      {"strain_ms", [](S s) { return milliseconds(s.strain_ms); }, TIMING},
      {"warnings", [](S s) { return integer(s.warnings); }},
  };
  return columns;
}

namespace {

// One cell a column, comma-separated.
template <typename Cell>
std::string csv_line(Cell cell) {
  std::string line;
  for (const StatsColumn& c : stats_columns()) {
    if (&c != &stats_columns().front()) line += ',';
    line += cell(c);
  }
  return line;
}

}  // namespace

std::string stats_header() { return csv_line([](const StatsColumn& c) { return std::string(c.name); }); }

std::string stats_row(const FrameStats& s) { return csv_line([&](const StatsColumn& c) { return c.value(s); }); }

std::filesystem::path mesh_path(const std::filesystem::path& out, int frame, const std::string& format) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%05d", frame);
  return out / (name + mesh_extension(format));
}

namespace {

FrameStats measure(const Model& model, const State& state, int frame) {
  FrameStats s;
  s.frame = frame;
  s.sim_time = state.time;
  s.kinetic_energy = kinetic_energy(model, state);
  s.potential_energy = potential_energy(model, state);
  s.max_stretch = max_stretch(model, state);
  for (const Obstacle& o : model.obstacles) {
    const Scalar d = distance_to_obstacle(o, state.time, state.positions);
    s.min_distance_obstacle = s.min_distance_obstacle ? std::min(*s.min_distance_obstacle, d) : d;
  }
  return s;
}


// What drape writes into a run folder, and nothing else: files by name, and the folders
// meshes/ and render/ only when every entry in them is one drape writes there.
bool matches(const std::filesystem::path& path, const std::regex& pattern) {
  return std::regex_match(path.filename().string(), pattern);
}

bool folder_of_only(const std::filesystem::path& folder, const std::regex& pattern) {
  std::error_code error;
  for (std::filesystem::directory_iterator it(folder, error), end; !error && it != end; it.increment(error))
    if (!matches(it->path(), pattern)) return false;
  return !error;
}

bool is_run_file(const std::filesystem::directory_entry& entry) {
  static const std::regex file(R"((frame_\d+\.[A-Za-z0-9]+|stats\.csv|scene\.json|scene_path\.txt|video\.mp4)(\.partial)?)");
  static const std::regex mesh_copy(R"((cloth|obstacle)_\d+(\.[A-Za-z0-9]+)?(\.partial)?)");
  static const std::regex image(R"(frame_\d+\.png(\.partial)?)");
  std::error_code error;
  if (!entry.is_directory(error)) return matches(entry.path(), file);
  const std::string name = entry.path().filename().string();
  if (name == "meshes") return folder_of_only(entry.path(), mesh_copy);
  if (name == "render") return folder_of_only(entry.path(), image);
  return false;
}

void prepare_run_folder(const std::filesystem::path& out, bool overwrite) {
  std::error_code error;
  std::filesystem::create_directories(out, error);
  if (error || !std::filesystem::is_directory(out))
    throw RunSetupError(out.string() + ": cannot create the output folder" + (error ? ": " + error.message() : ""));
  std::vector<std::filesystem::path> old;
  try {
    for (const auto& entry : std::filesystem::directory_iterator(out))
      if (is_run_file(entry)) old.push_back(entry.path());
  } catch (const std::filesystem::filesystem_error& e) {
    throw RunSetupError(out.string() + ": cannot list the output folder: " + e.code().message());
  }
  if (old.empty()) return;
  if (!overwrite)
    throw RunSetupError(out.string() + ": the folder holds another run (" + old.front().filename().string() +
                        (old.size() > 1 ? " and " + std::to_string(old.size() - 1) + " more" : "") +
                        "); give --overwrite to replace it, or another --out");
  for (const auto& path : old) {
    std::filesystem::remove_all(path, error);
    if (error) throw RunSetupError(path.string() + ": cannot remove the earlier run's file: " + error.message());
  }
}

}  // namespace

void remove_run_folder(const std::filesystem::path& out) {
  try {
    for (const auto& entry : std::filesystem::directory_iterator(out))
      if (!is_run_file(entry))
        throw RunSetupError(out.string() + ": holds " + entry.path().filename().string() +
                            ", which drape did not write; move it, or give the run another folder");
  } catch (const std::filesystem::filesystem_error& e) {
    throw RunSetupError(out.string() + ": cannot list the folder: " + e.code().message());
  }
  std::error_code error;
  std::filesystem::remove_all(out, error);
  if (error) throw RunSetupError(out.string() + ": cannot remove the earlier run: " + error.message());
}

namespace {

// The scene copy and its meshes, read before anything in the folder is removed (the scene may
// be the copy of the run it replaces).
struct RunInputs {
  std::string scene;  // the copy's text, mesh paths pointing into meshes/
  std::vector<std::pair<std::string, std::string>> meshes;  // relative path, bytes
};

std::optional<RunInputs> read_run_inputs(const Scene& scene) {
  // A scene parsed from text without a file (a test, an API user) has no copy.
  if (scene.file.empty() || scene.text.empty()) return std::nullopt;
  // The scene as it ran, with each mesh path pointing at a copy in meshes/: the folder alone
  // is enough to check and render the run, whatever happens to the original files later.
  nlohmann::ordered_json root;
  try {
    root = nlohmann::ordered_json::parse(scene.text);
  } catch (const nlohmann::json::exception& e) {
    throw RunSetupError(scene.file.string() + ": cannot copy the scene: " + e.what());
  }
  RunInputs inputs;
  const auto copy_mesh = [&](nlohmann::ordered_json& entry, const std::filesystem::path& source, const std::string& name) {
    const std::string relative = "meshes/" + name + source.extension().string();
    try {
      inputs.meshes.emplace_back(relative, ccd::read_input_file(source, ccd::MAX_MESH_BYTES, "mesh file"));
    } catch (const ccd::InputFileError& e) {
      throw RunSetupError(e.what());
    }
    entry["mesh"] = relative;
  };
  for (std::size_t c = 0; c < scene.cloths.size(); ++c)
    if (!scene.cloths[c].grid) copy_mesh(root["cloths"][c], scene.cloths[c].mesh_file, "cloth_" + std::to_string(c));
  for (std::size_t o = 0; o < scene.obstacles.size(); ++o)
    if (scene.obstacles[o].kind == ObstacleSpec::Kind::Mesh)
      copy_mesh(root["obstacles"][o], scene.obstacles[o].mesh_file, "obstacle_" + std::to_string(o));
  inputs.scene = root.dump(2) + "\n";
  return inputs;
}

void write_run_inputs(const RunInputs& inputs, const std::filesystem::path& out) {
  if (!inputs.meshes.empty()) {
    std::error_code error;
    std::filesystem::create_directories(out / "meshes", error);
    if (error) throw OutputError((out / "meshes").string() + ": cannot create the folder: " + error.message());
  }
  for (const auto& [relative, bytes] : inputs.meshes) write_file_atomically(out / relative, bytes);
  write_file_atomically(out / "scene.json", inputs.scene);
}

}  // namespace

RunOutcome run_simulation(const Model& model, const RunSettings& settings, const std::atomic<bool>& interrupt,
                          const std::function<void(const FrameStats&)>& on_frame) {
  const std::optional<RunInputs> inputs = read_run_inputs(model.scene);
  // The run writes its scene's copy as the folder's scene.json: a run's own copy may be run
  // again into its folder (its statistics say it is one), a scene of the user's may not be
  // replaced by it.
  if (std::error_code error; !model.scene.file.empty() &&
                             std::filesystem::equivalent(model.scene.file, settings.out / "scene.json", error) &&
                             !std::filesystem::exists(settings.out / "stats.csv", error))
    throw RunSetupError(model.scene.file.string() + ": the scene is the output folder's scene.json, which the run " +
                        "writes (its copy of the scene); give another --out");
  prepare_run_folder(settings.out, settings.overwrite);
  // A failed write from here on (a full disk) stops the run: status 3, as during it.
  std::optional<LineFile> stats;
  try {
    if (inputs) write_run_inputs(*inputs, settings.out);
    stats.emplace(stats_path(settings.out));
    stats->write_line(stats_header());
  } catch (const OutputError& e) {
    RunOutcome outcome;
    outcome.end = RunEnd::Stopped;
    outcome.message = std::string("cannot write the run's inputs: ") + e.what() + "; no frame is written";
    return outcome;
  }
  State state = initial_state(model);
  const std::string& format = model.scene.output.mesh_format;
  // Writes the frame's mesh then its row: a row in stats.csv means its frame is complete.
  const auto write_frame = [&](const State& state, FrameStats row) {
    if (settings.check_penetrations) row.penetrations = int(find_penetrations(model, state.positions, state.time).size());
    if (settings.write_meshes) save_mesh(mesh_path(settings.out, row.frame, format), model.cloth_mesh(state.positions), format);
    stats->write_line(stats_row(row));
    if (on_frame) on_frame(row);
  };
  RunOutcome outcome;
  const RunLimits& limits = model.scene.limits;
  const Scalar scale = energy_scale(model);
  const Scalar energy_start = kinetic_energy(model, state) + potential_energy(model, state);
  Scalar external_work = 0;
  const auto stop_on_write_error = [&](const std::string& what, int frame) {
    outcome.end = RunEnd::Stopped;
    outcome.message = "cannot write frame " + std::to_string(frame) + ": " + what +
                      (frame > 0 ? "; frames 0 to " + std::to_string(frame - 1) + " are written" : "");
    return outcome;
  };

  Integrator integrator(model, settings.threads);
  try {
    write_frame(state, measure(model, state, 0));
  } catch (const std::runtime_error& e) {  // OutputError, MeshFileError
    return stop_on_write_error(e.what(), 0);
  }

  for (int frame = 1; frame <= settings.frames; ++frame) {
    FrameStats totals;
    const auto begin = std::chrono::steady_clock::now();
    for (int step = 0; step < model.scene.frame_steps; ++step) {
      if (interrupt.load()) {
        outcome.end = RunEnd::Interrupted;
        outcome.message = "interrupted during frame " + std::to_string(frame) + "; frames 0 to " +
                          std::to_string(frame - 1) + " are written";
        return outcome;
      }
      const StepReport r = integrator.step(state);
      totals.solve_ms += r.solve_ms;
      totals.solver_iterations += r.solver_iterations;
      totals.obstacle_contacts += r.obstacle_contacts;
      totals.solver_warnings += !r.solver_converged;
      totals.collisions.add(r.collisions);
      totals.step_halvings += r.step_halvings;
      totals.strain_limited += r.strain_limited;
      totals.strain_ms += r.strain_ms;
      external_work += r.external_work;
      if (!r.ok) {
        outcome.end = RunEnd::Stopped;
        outcome.message = "frame " + std::to_string(frame) + " (t = " + std::to_string(state.time) + " s): " +
                          r.failure + "; frames 0 to " + std::to_string(frame - 1) + " are written";
        return outcome;
      }
    }
    FrameStats row = measure(model, state, frame);
    row.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    row.solve_ms = totals.solve_ms;
    row.solver_iterations = totals.solver_iterations;
    row.obstacle_contacts = totals.obstacle_contacts;
    row.solver_warnings = totals.solver_warnings;
    row.collisions = totals.collisions;
    row.step_halvings = totals.step_halvings;
    row.strain_limited = totals.strain_limited;
    row.strain_ms = totals.strain_ms;
    row.external_work = external_work;
    row.energy_excess = row.kinetic_energy + row.potential_energy - (energy_start + external_work);
    // The limits: a warning counted and said, or a stop that keeps this frame.
    char text[512];
    std::string stop;
    if (row.energy_excess > limits.energy_warn * scale) {
      ++row.warnings;
      std::snprintf(text, sizeof text,
                    "energy %.4g J is %.3g J above its start plus the sources' work (%.4g J); the limits are %.3g J to "
                    "warn and %.3g J to stop (limits.energy_warn and energy_stop times the scene's energy scale, %.4g J)",
                    row.kinetic_energy + row.potential_energy, row.energy_excess, energy_start + external_work,
                    limits.energy_warn * scale, limits.energy_stop * scale, scale);
      row.messages.push_back(text);
      if (row.energy_excess > limits.energy_stop * scale) stop = text;
    }
    if (row.max_stretch > limits.stretch_warn) {
      ++row.warnings;
      std::snprintf(text, sizeof text,
                    "a spring is stretched to %.4g times its rest length; the limits are %.4g to warn and %.4g to stop "
                    "(limits.stretch_warn and stretch_stop)",
                    row.max_stretch, limits.stretch_warn, limits.stretch_stop);
      row.messages.push_back(text);
      if (row.max_stretch > limits.stretch_stop && stop.empty()) stop = text;
    }
    // The response's last resort: not a limit of the scene's, but a frame whose cloth it froze
    // in part is not the simulation the user asked for, so it is said and counted too.
    if (row.collisions.fail_safes > 0) {
      ++row.warnings;
      std::snprintf(text, sizeof text,
                    "the collision response's fail-safe held colliding cloth vertices at their start positions in %ld "
                    "step(s) (column fail_safes): its impulse and impact-zone rounds (collisions.max_impulse_iterations "
                    "and max_zone_iterations) left a collision",
                    long(row.collisions.fail_safes));
      row.messages.push_back(text);
    }
    try {
      write_frame(state, row);
    } catch (const std::runtime_error& e) {
      return stop_on_write_error(e.what(), frame);
    }
    outcome.frames_done = frame;
    if (!stop.empty()) {
      outcome.end = RunEnd::Stopped;
      outcome.message = "frame " + std::to_string(frame) + ": " + stop + "; frames 0 to " + std::to_string(frame) +
                        " are written";
      return outcome;
    }
  }
  return outcome;
}

}  // namespace drape
