#include "drape/sweep/sweep.h"

#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "drape/core/fingerprint.h"
#include "drape/core/integrator.h"
#include "drape/core/output_file.h"
#include "drape/core/penetration.h"

namespace drape {

std::string SweepSetting::label() const {
  std::ostringstream out;
  out << "steps=" << frame_steps << " solver=";
  if (solver.kind == SolverKind::Cholmod) out << "cholmod:release_solves=" << solver.release_solves;
  else if (solver.kind == SolverKind::Projective)
    out << "projective:iterations=" << solver.iterations << ":history=" << solver.history
        << ":tolerance=" << solver.tolerance << ":chebyshev=" << solver.chebyshev;
  else out << "cg:" << solver.tolerance;
  out << " ccd=" << ccd::method_name(method) << " thickness=" << thickness << " impulses=" << max_impulse_iterations
      << " zones=" << max_zone_iterations << " self_in_solve=" << (self_in_solve ? "on" : "off");
  return out.str();
}

SweepSetting setting_of(const Scene& scene) {
  return {scene.frame_steps, scene.solver, scene.collisions.method, scene.collisions.thickness,
          scene.collisions.max_impulse_iterations, scene.collisions.max_zone_iterations, scene.collisions.self_in_solve};
}

std::vector<SweepSetting> SweepGrid::settings() const {
  std::vector<SweepSetting> out;
  for (int steps : frame_steps)
    for (const SolverSpec& solver : solvers)
      for (ccd::Method method : methods)
        for (Scalar t : thickness)
          for (int impulses : max_impulse_iterations)
            for (int zones : max_zone_iterations)
              for (bool held : self_in_solve) out.push_back({steps, solver, method, t, impulses, zones, held});
  return out;
}

namespace {

// The number that is the whole of text, or nothing.
std::optional<double> whole_number(const std::string& text) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != text.size()) return std::nullopt;
  return value;
}

}  // namespace

SolverSpec parse_solver_setting(const std::string& text, const SolverSpec& scene_default) {
  SolverSpec spec = scene_default;
  if (text == "cholmod" || text.rfind("cholmod:", 0) == 0) {
    spec.kind = SolverKind::Cholmod;
    if (text != "cholmod") {
      const std::string prefix = "cholmod:release_solves=";
      const auto value = text.rfind(prefix, 0) == 0 ? whole_number(text.substr(prefix.size())) : std::nullopt;
      if (!value || !(*value >= 0 && *value <= MAX_RELEASE_SOLVES && *value == std::floor(*value)))
        throw std::invalid_argument("'" + text + "': expected cholmod or cholmod:release_solves=N with N from 0 to " +
                                    std::to_string(MAX_RELEASE_SOLVES));
      spec.release_solves = int(*value);
    }
    return spec;
  }
  // A setting of another type than the scene's starts from that type's defaults.
  if (text == "cg" || text.rfind("cg:", 0) == 0) {
    if (spec.kind != SolverKind::ConjugateGradient) spec.tolerance = default_tolerance(SolverKind::ConjugateGradient);
    spec.kind = SolverKind::ConjugateGradient;
    if (text != "cg") {
      const auto tolerance = whole_number(text.substr(3));
      if (!tolerance || !(*tolerance >= 1e-16 && *tolerance <= 1))
        throw std::invalid_argument("'" + text + "': expected cg:TOLERANCE with a tolerance from 1e-16 to 1");
      spec.tolerance = *tolerance;
    }
    return spec;
  }
  if (text == "projective" || text.rfind("projective:", 0) == 0) {
    if (spec.kind != SolverKind::Projective) spec.tolerance = default_tolerance(SolverKind::Projective);
    spec.kind = SolverKind::Projective;
    const std::string expected =
        "': expected projective or projective:NAME=VALUE[:NAME=VALUE...] with iterations from 1 to " +
        std::to_string(MAX_PROJECTIVE_ITERATIONS) + ", history from 0 to " + std::to_string(MAX_PROJECTIVE_HISTORY) +
        ", tolerance from 0 to 1 and chebyshev from 0 to 0.9999 (for example projective:iterations=20:history=5)";
    std::stringstream fields(text.substr(std::string("projective").size()));
    std::string field;
    std::getline(fields, field, ':');  // empty: before the first colon
    const auto whole = [](double v, double low, double high) { return v >= low && v <= high && v == std::floor(v); };
    while (std::getline(fields, field, ':')) {
      const std::size_t equals = field.find('=');
      const std::string name = field.substr(0, equals);
      const auto value = equals == std::string::npos ? std::nullopt : whole_number(field.substr(equals + 1));
      if (!value) throw std::invalid_argument("'" + text + expected);
      if (name == "iterations" && whole(*value, 1, MAX_PROJECTIVE_ITERATIONS)) spec.iterations = int(*value);
      else if (name == "history" && whole(*value, 0, MAX_PROJECTIVE_HISTORY)) spec.history = int(*value);
      else if (name == "tolerance" && *value >= 0 && *value <= 1) spec.tolerance = *value;
      else if (name == "chebyshev" && *value >= 0 && *value <= MAX_CHEBYSHEV_RHO) spec.chebyshev = *value;
      else throw std::invalid_argument("'" + text + expected);
    }
    if (text.back() == ':') throw std::invalid_argument("'" + text + expected);
    return spec;
  }
  throw std::invalid_argument("'" + text + "': expected cholmod, cholmod:release_solves=N, cg, cg:TOLERANCE, projective or projective:NAME=VALUE[:NAME=VALUE...] (iterations, history, tolerance, chebyshev)");
}

namespace {

Scene with_setting(Scene scene, const SweepSetting& s) {
  scene.frame_steps = s.frame_steps;
  scene.solver = s.solver;
  scene.collisions.method = s.method;
  scene.collisions.thickness = s.thickness;
  scene.collisions.max_impulse_iterations = s.max_impulse_iterations;
  scene.collisions.max_zone_iterations = s.max_zone_iterations;
  scene.collisions.self_in_solve = s.self_in_solve;
  return scene;
}

struct Trajectory {
  std::vector<std::vector<Vec3>> positions;  // frame 0 .. frames_done
  std::vector<Scalar> energy;
};

// A trajectory's file: a line naming the format, the frame and vertex counts, then per frame
// its energy and positions as native doubles (the file is read back on the machine, or the
// cluster, that wrote it).
constexpr const char* TRAJECTORY_MAGIC = "drape trajectory 1\n";

std::string trajectory_bytes(const Trajectory& t) {
  std::string bytes = TRAJECTORY_MAGIC;
  const std::uint64_t frames = t.positions.size(), vertices = frames ? t.positions[0].size() : 0;
  bytes.append(reinterpret_cast<const char*>(&frames), sizeof frames);
  bytes.append(reinterpret_cast<const char*>(&vertices), sizeof vertices);
  for (std::size_t f = 0; f < frames; ++f) {
    const double e = t.energy[f];
    bytes.append(reinterpret_cast<const char*>(&e), sizeof e);
    for (const Vec3& p : t.positions[f]) bytes.append(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
  }
  return bytes;
}

std::optional<Trajectory> read_trajectory(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string magic(std::char_traits<char>::length(TRAJECTORY_MAGIC), '\0');
  std::uint64_t frames = 0, vertices = 0;
  if (!in.read(magic.data(), std::streamsize(magic.size())) || magic != TRAJECTORY_MAGIC ||
      !in.read(reinterpret_cast<char*>(&frames), sizeof frames) || !in.read(reinterpret_cast<char*>(&vertices), sizeof vertices) ||
      frames > (1u << 24) || vertices > (1u << 28))
    return std::nullopt;
  Trajectory t;
  t.positions.assign(frames, std::vector<Vec3>(vertices));
  t.energy.resize(frames);
  for (std::size_t f = 0; f < frames; ++f) {
    double e = 0;
    if (!in.read(reinterpret_cast<char*>(&e), sizeof e)) return std::nullopt;
    t.energy[f] = e;
    for (Vec3& p : t.positions[f])
      if (!in.read(reinterpret_cast<char*>(p.data()), 3 * sizeof(double))) return std::nullopt;
  }
  return t;
}

// Returns nullopt when interrupted.
std::optional<SweepResult> simulate(const Scene& scene, const SweepSetting& setting, int frames, Trajectory& trajectory,
                                    const std::atomic<bool>& interrupt) {
  SweepResult result;
  result.setting = setting;
  const Model model = build_model(with_setting(scene, setting));
  State state = initial_state(model);
  Integrator integrator(model, 1);
  const auto record = [&] {
    trajectory.positions.push_back(state.positions);
    trajectory.energy.push_back(kinetic_energy(model, state) + potential_energy(model, state));
  };
  record();
  double wall_ms = 0;
  for (int frame = 1; frame <= frames && !result.failed; ++frame) {
    const auto begin = std::chrono::steady_clock::now();
    for (int step = 0; step < model.scene.frame_steps; ++step) {
      if (interrupt.load()) return std::nullopt;
      const StepReport r = integrator.step(state);
      if (!r.ok) {
        result.failed = true;
        result.failure = "frame " + std::to_string(frame) + ": " + r.failure;
        break;
      }
    }
    if (result.failed) break;
    wall_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    result.penetrations += long(find_penetrations(model, state.positions, state.time).size());
    record();
    result.frames_done = frame;
  }
  result.wall_ms_per_frame = result.frames_done ? wall_ms / result.frames_done : 0;
  result.energy_drift = trajectory.energy.back() - trajectory.energy.front();
  return result;
}

void compare(SweepResult& r, const Trajectory& run, const Trajectory& reference) {
  double squares = 0;
  std::size_t count = 0;
  for (std::size_t f = 1; f < run.positions.size() && f < reference.positions.size(); ++f) {
    for (std::size_t v = 0; v < run.positions[f].size(); ++v) {
      const double d = (run.positions[f][v] - reference.positions[f][v]).norm();
      squares += d * d;
      r.max_error = std::max(r.max_error, d);
      ++count;
    }
    r.energy_error = std::max(r.energy_error, double(std::abs(run.energy[f] - reference.energy[f])));
  }
  r.rms_error = count ? std::sqrt(squares / double(count)) : 0;
}

std::filesystem::path run_folder(const SweepPlan& plan, std::size_t run) {
  char name[32];
  std::snprintf(name, sizeof name, "run_%03zu", run);
  return plan.out / "runs" / name;
}

// What a kept run must match to count for this plan's run: the setting to the last bit, the
// frames, and the scene's text and meshes.
nlohmann::json identity(const SweepPlan& plan, std::size_t run) {
  const SweepSetting& s = plan.setting(run);
  char exact[256];
  std::snprintf(exact, sizeof exact, "%d %d %.17g %d %d %.17g %d %s %.17g %d %d %d", s.frame_steps, int(s.solver.kind),
                double(s.solver.tolerance), s.solver.iterations, s.solver.history, double(s.solver.chebyshev), s.solver.release_solves,
                std::string(ccd::method_name(s.method)).c_str(), double(s.thickness), s.max_impulse_iterations,
                s.max_zone_iterations, int(s.self_in_solve));
  return {{"setting", s.label()}, {"exact", exact}, {"reference", run == 0}, {"frames", plan.frames},
          {"scene", plan.scene.file.string()}, {"inputs", scene_fingerprint(plan.scene)}};
}

std::optional<SweepResult> read_result(const SweepPlan& plan, std::size_t run) {
  std::ifstream in(run_folder(plan, run) / "result.json");
  if (!in) return std::nullopt;
  try {
    nlohmann::json j;
    in >> j;
    if (j.at("identity") != identity(plan, run)) return std::nullopt;
    SweepResult r;
    r.setting = plan.setting(run);
    r.reference = run == 0;
    r.failed = j.at("failed");
    r.failure = j.at("failure");
    r.frames_done = j.at("frames_done");
    r.wall_ms_per_frame = j.at("wall_ms_per_frame");
    r.energy_drift = j.at("energy_drift");
    r.penetrations = j.at("penetrations");
    return r;
  } catch (const std::exception&) {
    return std::nullopt;  // unreadable or of another version: run again
  }
}

}  // namespace

void check_sweep_plan(const SweepPlan& plan) {
  for (std::size_t run = 0; run < plan.size(); ++run) build_model(with_setting(plan.scene, plan.setting(run)));
}

bool sweep_run_done(const SweepPlan& plan, std::size_t run) {
  return read_result(plan, run) && std::filesystem::exists(run_folder(plan, run) / "trajectory.bin");
}

std::optional<SweepResult> run_sweep_run(const SweepPlan& plan, std::size_t run, const std::atomic<bool>& interrupt) {
  Trajectory trajectory;
  std::optional<SweepResult> result = simulate(plan.scene, plan.setting(run), plan.frames, trajectory, interrupt);
  if (!result) return std::nullopt;
  result->reference = run == 0;
  // Kept in a partial folder renamed into place: a run is in runs/ whole or not at all.
  const std::filesystem::path folder = run_folder(plan, run), partial = folder.string() + ".partial";
  std::error_code error;
  std::filesystem::remove_all(partial, error);
  std::filesystem::create_directories(partial, error);
  if (error) throw std::runtime_error(partial.string() + ": cannot create the run's folder: " + error.message());
  write_file_atomically(partial / "trajectory.bin", trajectory_bytes(trajectory));
  const nlohmann::json j = {{"identity", identity(plan, run)},
                            {"failed", result->failed},
                            {"failure", result->failure},
                            {"frames_done", result->frames_done},
                            {"wall_ms_per_frame", result->wall_ms_per_frame},
                            {"energy_drift", result->energy_drift},
                            {"penetrations", result->penetrations}};
  write_file_atomically(partial / "result.json", j.dump(2) + "\n");
  std::filesystem::remove_all(folder, error);
  std::filesystem::rename(partial, folder, error);
  if (error) throw std::runtime_error(folder.string() + ": cannot move the run into place: " + error.message());
  return result;
}

std::vector<SweepResult> gather_sweep(const SweepPlan& plan) {
  std::vector<SweepResult> results;
  const std::optional<SweepResult> reference = read_result(plan, 0);
  if (!reference) return results;
  results.push_back(*reference);
  if (reference->failed) return results;  // nothing to compare with
  const std::optional<Trajectory> reference_trajectory = read_trajectory(run_folder(plan, 0) / "trajectory.bin");
  if (!reference_trajectory) throw std::runtime_error((run_folder(plan, 0) / "trajectory.bin").string() + ": unreadable");
  for (std::size_t run = 1; run < plan.size(); ++run) {
    std::optional<SweepResult> r = read_result(plan, run);
    if (!r) continue;
    const std::optional<Trajectory> trajectory = read_trajectory(run_folder(plan, run) / "trajectory.bin");
    // Kept with another mesh (fingerprints collide, or the file was replaced): not comparable.
    if (!trajectory || trajectory->positions.empty() ||
        trajectory->positions[0].size() != reference_trajectory->positions[0].size())
      continue;
    compare(*r, *trajectory, *reference_trajectory);
    results.push_back(*r);
  }
  mark_pareto_front(results);
  return results;
}

void mark_pareto_front(std::vector<SweepResult>& results) {
  const auto candidate = [](const SweepResult& r) { return !r.reference && !r.failed && r.penetrations == 0; };
  for (SweepResult& r : results) {
    r.pareto = candidate(r);
    if (!r.pareto) continue;
    for (const SweepResult& other : results) {
      if (&other == &r || !candidate(other)) continue;
      const bool no_worse = other.wall_ms_per_frame <= r.wall_ms_per_frame && other.rms_error <= r.rms_error;
      const bool better = other.wall_ms_per_frame < r.wall_ms_per_frame || other.rms_error < r.rms_error;
      if (no_worse && better) {
        r.pareto = false;
        break;
      }
    }
  }
}

std::string sweep_csv_header() {
  return "reference,frame_steps,solver,tolerance,projective_iterations,projective_history,chebyshev,release_solves,method,thickness,max_impulse_iterations,max_zone_iterations,self_in_solve,frames_done,failed,"
         "wall_ms_per_frame,rms_error_m,max_error_m,energy_error_j,energy_drift_j,penetrations,pareto,failure";
}

std::string sweep_csv_row(const SweepResult& r) {
  const SweepSetting& s = r.setting;
  std::string failure = r.failure;
  std::replace(failure.begin(), failure.end(), '"', '\'');
  char row[512];
  const bool cg = s.solver.kind == SolverKind::ConjugateGradient, projective = s.solver.kind == SolverKind::Projective;
  std::snprintf(row, sizeof row, "%d,%d,%s,%.3g,%d,%d,%.6g,%d,%s,%.6g,%d,%d,%d,%d,%d,%.3f,%.6e,%.6e,%.6e,%.6e,%ld,%d,", int(r.reference),
                s.frame_steps, cg ? "cg" : projective ? "projective" : "cholmod",
                cg || projective ? double(s.solver.tolerance) : 0.0, projective ? s.solver.iterations : 0,
                projective ? s.solver.history : 0, projective && s.solver.history == 0 ? double(s.solver.chebyshev) : 0.0,
                s.solver.kind == SolverKind::Cholmod ? s.solver.release_solves : 0,
                std::string(ccd::method_name(s.method)).c_str(), double(s.thickness), s.max_impulse_iterations,
                s.max_zone_iterations, int(s.self_in_solve), r.frames_done, int(r.failed), r.wall_ms_per_frame, r.rms_error, r.max_error, r.energy_error,
                r.energy_drift, r.penetrations, int(r.pareto));
  return row + (failure.empty() ? std::string() : "\"" + failure + "\"");
}

void write_sweep_csv(const std::filesystem::path& path, const std::vector<SweepResult>& results) {
  std::filesystem::path partial = path;
  partial += ".partial";  // renamed into place: never a half-written table
  {
    std::ofstream out(partial);
    out << sweep_csv_header() << "\n";
    for (const SweepResult& r : results) out << sweep_csv_row(r) << "\n";
    if (!out.flush()) throw std::runtime_error(path.string() + ": cannot write the sweep table");
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error) throw std::runtime_error(path.string() + ": cannot write the sweep table: " + error.message());
}

namespace {

// The setting's label with only the knobs that vary across the results.
std::string varying_label(const SweepSetting& s, const std::vector<SweepResult>& results) {
  std::istringstream parts(s.label());
  std::vector<std::string> mine(std::istream_iterator<std::string>{parts}, {});
  std::vector<bool> varies(mine.size(), false);
  for (const SweepResult& r : results) {
    if (r.reference) continue;
    std::istringstream other_parts(r.setting.label());
    std::vector<std::string> other(std::istream_iterator<std::string>{other_parts}, {});
    for (std::size_t k = 0; k < mine.size() && k < other.size(); ++k) varies[k] = varies[k] || other[k] != mine[k];
  }
  std::string label;
  for (std::size_t k = 0; k < mine.size(); ++k)
    if (varies[k]) label += (label.empty() ? "" : " ") + mine[k];
  return label;
}

}  // namespace

std::string plot_sweep(const std::filesystem::path& png, const std::vector<SweepResult>& results, const std::string& title) {
  // Errors of zero (a run equal to the reference) sit on the axis floor of the log scale.
  constexpr double FLOOR = 1e-12;
  // A missing or dead gnuplot must surface as a failed plot, not kill drape with SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  std::FILE* gnuplot = popen("gnuplot 2>&1", "w");
  if (!gnuplot) return "cannot start gnuplot";
  std::ostringstream script;
  script << "set terminal pngcairo size 1200,800 font ',11'\n";
  std::string quoted = png.string();
  std::replace(quoted.begin(), quoted.end(), '"', '\'');
  script << "set output \"" << quoted << "\"\n";
  script << "set title \"" << title << "\" noenhanced\n";
  script << "set xlabel 'wall time per frame (ms)'\nset ylabel 'RMS vertex error against the reference (m)'\n";
  script << "set logscale xy\nset grid\nset key top right\n";
  const auto block = [&](const std::string& name, const std::function<bool(const SweepResult&)>& keep, bool sorted) {
    std::vector<const SweepResult*> rows;
    for (const SweepResult& r : results)
      if (keep(r)) rows.push_back(&r);
    if (sorted)
      std::sort(rows.begin(), rows.end(), [](auto* a, auto* b) { return a->wall_ms_per_frame < b->wall_ms_per_frame; });
    script << "$" << name << " << EOD\n";
    for (const SweepResult* r : rows) {
      std::string label = varying_label(r->setting, results);
      std::replace(label.begin(), label.end(), '"', '\'');
      script << r->wall_ms_per_frame << " " << std::max(r->rms_error, FLOOR) << " \"" << label << "\"\n";
    }
    if (rows.empty()) script << "NaN NaN \"\"\n";
    script << "EOD\n";
  };
  block("ok", [](const SweepResult& r) { return !r.reference && !r.failed && r.penetrations == 0; }, false);
  block("front", [](const SweepResult& r) { return r.pareto; }, true);
  block("bad", [](const SweepResult& r) { return !r.reference && (r.failed || r.penetrations > 0); }, false);
  script << "plot $ok using 1:2 with points pt 7 ps 1.2 lc rgb '#7f7f7f' title 'runs',"
            " $front using 1:2 with linespoints pt 7 ps 1.6 lw 2 lc rgb '#d62728' title 'Pareto front',"
            " $front using 1:2:3 with labels left offset 1,0.6 font ',9' noenhanced notitle,"
            " $bad using 1:2 with points pt 2 ps 1.6 lc rgb '#1f77b4' title 'failed or penetrating'\n";
  const std::string text = script.str();
  std::fwrite(text.data(), 1, text.size(), gnuplot);
  const int status = pclose(gnuplot);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127) return "gnuplot is not installed (Debian package gnuplot-nox)";
  if (status != 0) return "gnuplot failed (status " + std::to_string(status) + ")";
  if (!std::filesystem::exists(png)) return "gnuplot wrote no " + png.string();
  return "";
}

}  // namespace drape
