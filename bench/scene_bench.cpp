// scene_bench: runs a scene once and, at every measured frame, times each CCD method on the
// identical candidate sets of that frame's last step, side by side, with the filter's cull
// rates and the agreement of the methods' hits.
//
//   scene_bench SCENE [--frames N] [--every K] [--passes P] [--threads T]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>

#include "drape/ccd/evaluation.h"
#include "drape/core/integrator.h"
#include "drape/core/penetration.h"

using namespace drape;

namespace {

struct Captured {
  long triangle_pairs = 0;
  std::vector<Vec3> start, end;
  std::vector<ccd::VertexFacePair> vertex_face;
  std::vector<ccd::EdgeEdgePair> edge_edge;
};

struct MethodRun {
  double ms = 0;
  ccd::BatchCounters counters;
  std::vector<bool> hits;
};

MethodRun time_method(const Captured& c, ccd::Method method, int passes) {
  const ccd::BatchInput input{c.start, c.end, c.vertex_face, c.edge_edge};
  ccd::Options options;
  options.method = method;
  MethodRun run;
  std::vector<double> ms;
  for (int p = 0; p < passes; ++p) {
    const auto begin = std::chrono::steady_clock::now();
    const ccd::BatchOutput out = ccd::run_batch(input, options, 1);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
    if (p == 0) {
      run.counters = out.counters;
      for (const auto& r : out.vertex_face) run.hits.push_back(r.hit);
      for (const auto& r : out.edge_edge) run.hits.push_back(r.hit);
    }
  }
  run.ms = ccd::median(ms);
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Runs a scene and times every CCD method on the identical candidate sets of its frames."};
  std::string scene_path;
  int frames = 0, every = 1, passes = 5, threads = 1;
  bool check = false;
  app.add_option("scene", scene_path, "Scene file")->required()->check(CLI::ExistingFile);
  app.add_option("--frames", frames, "Frames to run (default: the scene's)");
  app.add_option("--every", every, "Measure every K-th frame")->capture_default_str();
  app.add_option("--passes", passes, "Timed passes per method (median)")->capture_default_str();
  app.add_option("--threads", threads, "Threads of the simulation's own narrow phase")->capture_default_str();
  app.add_flag("--check", check, "Run the independent penetration check on every frame");
  CLI11_PARSE(app, argc, argv);

  Model model;
  try {
    model = build_model(load_scene(scene_path));
  } catch (const SceneError& e) {
    std::fprintf(stderr, "scene_bench: %s\n", e.what());
    return 2;
  }
  if (frames <= 0) frames = model.scene.frames;
  State state = initial_state(model);
  Integrator integrator(model, make_linear_solver(model.scene.solver), threads);
  if (!integrator.collisions()) {
    std::fprintf(stderr, "scene_bench: %s has no collision pipeline (no self-collision, no mesh obstacle)\n", scene_path.c_str());
    return 2;
  }
  Captured captured;
  integrator.collisions()->set_observer([&](const ccd::BatchInput& in, long triangle_pairs) {
    captured.triangle_pairs = triangle_pairs;
    captured.start.assign(in.start.begin(), in.start.end());
    captured.end.assign(in.end.begin(), in.end.end());
    captured.vertex_face.assign(in.vertex_face.begin(), in.vertex_face.end());
    captured.edge_edge.assign(in.edge_edge.begin(), in.edge_edge.end());
  });

  std::printf("scene_bench %s: %zu vertices, %d frames of %d steps; narrow phase timed on one thread, median of %d\n",
              scene_path.c_str(), model.vertex_count(), frames, model.scene.frame_steps, passes);
  std::printf("%5s %8s %9s %9s %7s %7s %9s %9s %9s %9s %8s %8s %6s %6s %9s %5s\n", "frame", "pairs", "vf_tests", "ee_tests",
              "dnf%", "vin%", "cubic_ms", "dnf_ms", "vin_ms", "cons_ms", "vin/cub", "vin/dnf", "hits", "diff", "step_ms", "pen");
  double total[4] = {0, 0, 0, 0};
  long disagreements = 0, penetrations = 0, tests = 0, culled_vincent = 0;
  for (int frame = 1; frame <= frames; ++frame) {
    double step_ms = 0;
    for (int step = 0; step < model.scene.frame_steps; ++step) {
      const auto begin = std::chrono::steady_clock::now();
      const StepReport r = integrator.step(state);
      step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
      if (!r.ok) {
        std::printf("stopped at frame %d: %s\n", frame, r.failure.c_str());
        return 3;
      }
    }
    int found = 0;
    if (check) penetrations += found = int(find_penetrations(model, state.positions, state.time).size());
    if (frame % every != 0) continue;
    MethodRun runs[4];
    const ccd::Method methods[4] = {ccd::Method::Cubic, ccd::Method::Dnf, ccd::Method::Vincent, ccd::Method::Conservative};
    for (int m = 0; m < 4; ++m) runs[m] = time_method(captured, methods[m], passes), total[m] += runs[m].ms;
    long diff = 0, hits = 0;
    for (std::size_t i = 0; i < runs[2].hits.size(); ++i) {
      hits += runs[2].hits[i];
      diff += runs[0].hits[i] != runs[2].hits[i] || runs[1].hits[i] != runs[2].hits[i];
    }
    disagreements += diff;
    const double n = double(captured.vertex_face.size() + captured.edge_edge.size());
    tests += long(n);
    culled_vincent += long(runs[2].counters.culled);
    std::printf("%5d %8zu %9zu %9zu %6.2f%% %6.2f%% %9.2f %9.2f %9.2f %9.2f %7.1fx %7.2fx %6ld %6ld %9.1f %5s\n", frame,
                size_t(captured.triangle_pairs), captured.vertex_face.size(), captured.edge_edge.size(),
                n ? 100.0 * runs[1].counters.culled / n : 0.0, n ? 100.0 * runs[2].counters.culled / n : 0.0, runs[0].ms,
                runs[1].ms, runs[2].ms, runs[3].ms, runs[0].ms / runs[2].ms, runs[1].ms / runs[2].ms, hits, diff, step_ms,
                check ? std::to_string(found).c_str() : "-");
  }
  std::printf("\ntotal narrow phase: cubic %.1f ms, dnf %.1f ms, vincent %.1f ms, conservative %.1f ms\n", total[0], total[1],
              total[2], total[3]);
  std::printf("vincent is %.2fx faster than cubic and %.2fx than dnf; conservative costs %.2fx vincent\n", total[0] / total[2],
              total[1] / total[2], total[3] / total[2]);
  std::printf("vincent culled %.2f%% of %ld tests; %ld tests where cubic or dnf disagree with vincent%s\n",
              tests ? 100.0 * culled_vincent / tests : 0.0, tests, disagreements,
              check ? (", " + std::to_string(penetrations) + " penetrations over the run").c_str() : "");
  return 0;
}
