#include "drape/core/sweep.h"

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

#include "drape/core/integrator.h"
#include "drape/core/penetration.h"

namespace drape {

std::string SweepSetting::label() const {
  std::ostringstream out;
  out << "steps=" << frame_steps << " solver=";
  if (solver.kind == SolverKind::Cholmod) out << "cholmod";
  else if (solver.kind == SolverKind::Projective) out << "projective:" << solver.iterations << ":" << solver.chebyshev;
  else out << "cg:" << solver.tolerance;
  out << " ccd=" << ccd::method_name(method) << " thickness=" << thickness << " impulses=" << max_impulse_iterations
      << " zones=" << max_zone_iterations;
  return out.str();
}

SweepSetting setting_of(const Scene& scene) {
  return {scene.frame_steps, scene.solver, scene.collisions.method, scene.collisions.thickness,
          scene.collisions.max_impulse_iterations, scene.collisions.max_zone_iterations};
}

std::vector<SweepSetting> SweepGrid::settings() const {
  std::vector<SweepSetting> out;
  for (int steps : frame_steps)
    for (const SolverSpec& solver : solvers)
      for (ccd::Method method : methods)
        for (Scalar t : thickness)
          for (int impulses : max_impulse_iterations)
            for (int zones : max_zone_iterations) out.push_back({steps, solver, method, t, impulses, zones});
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
  if (text == "cholmod") {
    spec.kind = SolverKind::Cholmod;
    return spec;
  }
  if (text == "cg" || text.rfind("cg:", 0) == 0) {
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
    spec.kind = SolverKind::Projective;
    const std::string expected = "': expected projective:ITERATIONS or projective:ITERATIONS:CHEBYSHEV with iterations from 1 to " +
                                 std::to_string(MAX_PROJECTIVE_ITERATIONS) + " and a Chebyshev estimate from 0 to 0.9999";
    std::stringstream fields(text.substr(std::string("projective").size()));
    std::string field;
    std::getline(fields, field, ':');  // empty: before the first colon
    int index = 0;
    while (std::getline(fields, field, ':')) {
      const auto value = whole_number(field);
      if (index == 0 && value && *value >= 1 && *value <= MAX_PROJECTIVE_ITERATIONS && *value == std::floor(*value))
        spec.iterations = int(*value);
      else if (index == 1 && value && *value >= 0 && *value <= MAX_CHEBYSHEV_RHO)
        spec.chebyshev = *value;
      else
        throw std::invalid_argument("'" + text + expected);
      ++index;
    }
    if (text.back() == ':') throw std::invalid_argument("'" + text + expected);
    return spec;
  }
  throw std::invalid_argument("'" + text + "': expected cholmod, cg, cg:TOLERANCE, projective or projective:ITERATIONS[:CHEBYSHEV]");
}

namespace {

Scene with_setting(Scene scene, const SweepSetting& s) {
  scene.frame_steps = s.frame_steps;
  scene.solver = s.solver;
  scene.collisions.method = s.method;
  scene.collisions.thickness = s.thickness;
  scene.collisions.max_impulse_iterations = s.max_impulse_iterations;
  scene.collisions.max_zone_iterations = s.max_zone_iterations;
  return scene;
}

struct Trajectory {
  std::vector<std::vector<Vec3>> positions;  // frame 0 .. frames_done
  std::vector<Scalar> energy;
};

SweepResult simulate(const Scene& scene, const SweepSetting& setting, int frames, Trajectory& trajectory) {
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

}  // namespace

std::vector<SweepResult> run_sweep(const Scene& scene, const SweepSetting& reference_setting,
                                   const std::vector<SweepSetting>& settings, int frames,
                                   const std::function<void(const SweepResult&, std::size_t, std::size_t)>& on_result) {
  std::vector<SweepResult> results;
  const std::size_t total = settings.size() + 1;
  Trajectory reference;
  SweepResult ref = simulate(scene, reference_setting, frames, reference);
  ref.reference = true;
  results.push_back(ref);
  if (on_result) on_result(results.back(), 1, total);
  if (ref.failed) return results;
  for (const SweepSetting& setting : settings) {
    Trajectory trajectory;
    SweepResult r = simulate(scene, setting, frames, trajectory);
    compare(r, trajectory, reference);
    results.push_back(r);
    if (on_result) on_result(results.back(), results.size(), total);
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
  return "reference,frame_steps,solver,cg_tolerance,projective_iterations,chebyshev,method,thickness,max_impulse_iterations,max_zone_iterations,frames_done,failed,"
         "wall_ms_per_frame,rms_error_m,max_error_m,energy_error_j,energy_drift_j,penetrations,pareto,failure";
}

std::string sweep_csv_row(const SweepResult& r) {
  const SweepSetting& s = r.setting;
  std::string failure = r.failure;
  std::replace(failure.begin(), failure.end(), '"', '\'');
  char row[512];
  const bool cg = s.solver.kind == SolverKind::ConjugateGradient, projective = s.solver.kind == SolverKind::Projective;
  std::snprintf(row, sizeof row, "%d,%d,%s,%.3g,%d,%.6g,%s,%.6g,%d,%d,%d,%d,%.3f,%.6e,%.6e,%.6e,%.6e,%ld,%d,", int(r.reference),
                s.frame_steps, cg ? "cg" : projective ? "projective" : "cholmod", cg ? double(s.solver.tolerance) : 0.0,
                projective ? s.solver.iterations : 0, projective ? double(s.solver.chebyshev) : 0.0,
                std::string(ccd::method_name(s.method)).c_str(), double(s.thickness), s.max_impulse_iterations,
                s.max_zone_iterations, r.frames_done, int(r.failed), r.wall_ms_per_frame, r.rms_error, r.max_error, r.energy_error,
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
