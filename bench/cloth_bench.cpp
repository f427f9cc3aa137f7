// cloth_bench: milliseconds per implicit step and peak memory for large grids, CHOLMOD beside
// the conjugate gradient, in one run. Each configuration runs in a child process so that its
// peak resident memory is its own.
//
//   cloth_bench [--steps N] [--sizes 100,200]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>

#include "drape/core/linear_solver.h"
#include "drape/ccd_eval/evaluation.h"
#include "child_process.h"
#include "drape/core/integrator.h"

using namespace drape;

namespace {

struct Measurement {
  double ms_per_step = 0;   // median over the timed steps
  double solve_ms = 0;      // median linear-solve share
  double iterations = 0;    // mean solver iterations per step
  long peak_kib = 0;        // peak resident memory of the child
  bool ok = false;
};

std::string scene_json(int cells, const char* solver) {
  char text[512];
  // cg's tolerance and iteration cap (cholmod has neither: the scene refuses them).
  const char* cg = std::string(solver) == "cg" ? R"(, "tolerance": 1e-6, "max_iterations": 5000)" : "";
  std::snprintf(text, sizeof text,
                R"({"frame_time": 0.0333333333333, "frame_steps": 10,
                    "cloths": [{"grid": {"size": [2, 2], "resolution": [%d, %d]}}],
                    "handles": [{"corners": ["top-left", "top-right"]}],
                    "solver": {"type": "%s"%s}})",
                cells, cells, solver, cg);
  return text;
}

// In the child: build, one untimed step (CHOLMOD's symbolic analysis), then timed steps.
Measurement measure_here(int cells, const char* solver, int steps) {
  const Model model = build_model(parse_scene(scene_json(cells, solver), "bench.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  integrator.step(state);
  std::vector<double> total, solve;
  double iterations = 0;
  Measurement m;
  for (int i = 0; i < steps; ++i) {
    const auto begin = std::chrono::steady_clock::now();
    const StepReport r = integrator.step(state);
    total.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
    solve.push_back(r.solve_ms);
    iterations += r.solver_iterations;
    if (!r.ok) return m;
  }
  m.ms_per_step = ccd::median(total);
  m.solve_ms = ccd::median(solve);
  m.iterations = iterations / steps;
  m.ok = true;
  return m;
}

Measurement measure(int cells, const char* solver, int steps) {
  Measurement m;
  const bench::ChildRun child = bench::run_in_child([&] { return measure_here(cells, solver, steps); }, m);
  if (!child.returned) m.ok = false;
  m.peak_kib = child.peak_kib;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  drape::keep_freed_memory();  // as the drape program does
  CLI::App app{"Milliseconds per implicit cloth step and peak memory: CHOLMOD beside CG on large grids."};
  int steps = 5;
  std::vector<int> sizes{100, 200};
  app.add_option("--steps", steps, "Timed steps per configuration (median reported)")->capture_default_str();
  app.add_option("--sizes", sizes, "Grid cells per side (100 -> 10,201 vertices, 200 -> 40,401)")->delimiter(',');
  CLI11_PARSE(app, argc, argv);

  std::printf("cloth_bench: a 2 m cloth pinned at two corners, h = 1/300 s, %d timed steps, medians; one thread.\n\n", steps);
  std::printf("%9s %-8s %12s %10s %12s %12s\n", "vertices", "solver", "ms/step", "solve ms", "iterations", "peak MiB");
  for (int cells : sizes) {
    Measurement results[2];
    const char* solvers[2] = {"cholmod", "cg"};
    for (int s = 0; s < 2; ++s) {
      results[s] = measure(cells, solvers[s], steps);
      const Measurement& m = results[s];
      if (!m.ok) {
        std::printf("%9d %-8s failed\n", (cells + 1) * (cells + 1), solvers[s]);
        continue;
      }
      std::printf("%9d %-8s %12.1f %10.1f %12.0f %12.1f\n", (cells + 1) * (cells + 1), solvers[s], m.ms_per_step,
                  m.solve_ms, m.iterations, m.peak_kib / 1024.0);
    }
    if (results[0].ok && results[1].ok)
      std::printf("%9s cg/cholmod: %.2fx the time, %.2fx the memory\n", "", results[1].ms_per_step / results[0].ms_per_step,
                  double(results[1].peak_kib) / results[0].peak_kib);
  }
  return 0;
}
