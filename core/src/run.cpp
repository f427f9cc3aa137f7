#include "drape/core/run.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "drape/core/mesh_io.h"
#include "drape/core/obstacle.h"
#include "drape/core/penetration.h"

namespace drape {

std::string stats_header() {
  return "frame,sim_time,wall_ms,solve_ms,solver_iterations,kinetic_energy,potential_energy,max_stretch,"
         "min_distance_obstacle,obstacle_contacts,solver_warnings,bvh_pairs,vf_tests,ee_tests,culled,separated,root_solves,"
         "ccd_hits,impulse_iterations,impact_zones,proximity_impulses,rest_clamped_pairs,fail_safes,ccd_ms,response_ms,penetrations";
}

std::string stats_row(const FrameStats& s) {
  char buffer[1024];
  char distance[32] = "";
  if (s.min_distance_obstacle) std::snprintf(distance, sizeof distance, "%.17g", *s.min_distance_obstacle);
  char penetrations[16] = "";
  if (s.penetrations) std::snprintf(penetrations, sizeof penetrations, "%d", *s.penetrations);
  const CollisionCounters& c = s.collisions;
  std::snprintf(buffer, sizeof buffer,
                "%d,%.17g,%.3f,%.3f,%ld,%.17g,%.17g,%.17g,%s,%d,%d,%ld,%ld,%ld,%llu,%llu,%llu,%ld,%ld,%ld,%ld,%ld,%ld,%.3f,%.3f,%s",
                s.frame, s.sim_time, s.wall_ms, s.solve_ms, s.solver_iterations, s.kinetic_energy, s.potential_energy,
                s.max_stretch, distance, s.obstacle_contacts, s.solver_warnings, c.bvh_pairs, c.vf_tests, c.ee_tests,
                static_cast<unsigned long long>(c.tests.culled), static_cast<unsigned long long>(c.tests.separated),
                static_cast<unsigned long long>(c.tests.root_solves),
                c.ccd_hits, c.impulse_iterations, c.impact_zones, c.proximity_impulses, c.rest_clamped_pairs, c.fail_safes, c.ccd_ms,
                c.response_ms, penetrations);
  return buffer;
}

std::filesystem::path mesh_path(const std::filesystem::path& out, int frame, const std::string& format) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%05d", frame);
  return out / (name + mesh_extension(format));
}

namespace {

// stats.csv, one whole row per write, flushed at once: a reader or a crash never sees half a row.
class StatsFile {
 public:
  explicit StatsFile(const std::filesystem::path& path) : file_(std::fopen(path.c_str(), "w")) {
    if (!file_) throw std::runtime_error(path.string() + ": cannot write the statistics file");
    write(stats_header());
  }
  ~StatsFile() { std::fclose(file_); }
  void write(const std::string& row) {
    const std::string line = row + "\n";
    std::fwrite(line.data(), 1, line.size(), file_);
    std::fflush(file_);
  }

 private:
  std::FILE* file_;
};

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

}  // namespace

RunOutcome run_simulation(const Model& model, const RunSettings& settings, const std::atomic<bool>& interrupt,
                          const std::function<void(const FrameStats&)>& on_frame) {
  std::error_code error;
  std::filesystem::create_directories(settings.out, error);
  if (error || !std::filesystem::is_directory(settings.out))
    throw std::runtime_error(settings.out.string() + ": cannot create the output folder" +
                             (error ? ": " + error.message() : ""));
  // A copy of the scene beside its results.
  if (!model.scene.file.empty() && std::filesystem::is_regular_file(model.scene.file)) {
    std::filesystem::copy_file(model.scene.file, settings.out / "scene.json",
                               std::filesystem::copy_options::overwrite_existing, error);
    if (error) throw std::runtime_error((settings.out / "scene.json").string() + ": cannot copy the scene: " + error.message());
    // Where the scene came from: its mesh paths are relative to that folder.
    std::ofstream(settings.out / "scene_path.txt") << std::filesystem::absolute(model.scene.file).string() << "\n";
  }
  StatsFile stats(stats_path(settings.out));
  const std::string& format = model.scene.output.mesh_format;
  const auto write_frame = [&](const State& state, FrameStats row) {
    if (settings.check_penetrations) row.penetrations = int(find_penetrations(model, state.positions, state.time).size());
    if (settings.write_meshes) save_mesh(mesh_path(settings.out, row.frame, format), model.cloth_mesh(state.positions), format);
    stats.write(stats_row(row));
    if (on_frame) on_frame(row);
  };

  State state = initial_state(model);
  Integrator integrator(model, make_linear_solver(model.scene.solver), settings.threads);
  write_frame(state, measure(model, state, 0));

  RunOutcome outcome;
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
    write_frame(state, row);
    outcome.frames_done = frame;
  }
  return outcome;
}

}  // namespace drape
