// scene_bench: the paper's cloth benchmark on any scene. Runs the scene once; at every
// measured frame it times each CCD method on the identical elementary tests of that frame (every
// detection round of every step of the frame, as the simulation made them), side by
// side: candidate pairs, tests, cull rates of dnf and vincent, narrow-phase milliseconds per
// method, speed-ups, and the agreement of the methods' hits (every difference printed).
//
//   scene_bench SCENE [--frames N] [--every K] [--passes P] [--check] [--no-feature-boxes]
//                     [--dump-ccd DIR [--dump-frame F] [--dump-limit Q]]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <tuple>

#include "drape/core/linear_solver.h"
#include "drape/ccd/broad_phase.h"
#include "drape/ccd_eval/evaluation.h"
#include "drape/ccd/patch_tree.h"
#include "drape/ccd_eval/query_file.h"
#include "drape/core/integrator.h"
#include "drape/core/penetration.h"

using namespace drape;
namespace fs = std::filesystem;

namespace {

// One detection round's tests, with the positions they index.
struct Batch {
  std::vector<Vec3> start, end;
  std::vector<ccd::VertexFacePair> vertex_face;
  std::vector<ccd::EdgeEdgePair> edge_edge;
  std::size_t tests() const { return vertex_face.size() + edge_edge.size(); }
};

struct Frame {
  int number = 0;
  long triangle_pairs = 0;
  std::vector<Batch> batches;
  std::vector<std::size_t> differing;  // tests (frame order) where the methods' hits differ
  std::size_t vertex_face() const {
    std::size_t n = 0;
    for (const Batch& b : batches) n += b.vertex_face.size();
    return n;
  }
  std::size_t tests() const {
    std::size_t n = 0;
    for (const Batch& b : batches) n += b.tests();
    return n;
  }
};

// Indices into ccd::ALL_METHODS (cubic, dnf, vincent, conservative).
enum { CUBIC, DNF, VINCENT, CONSERVATIVE, PAPER };
static_assert(ccd::ALL_METHODS[CUBIC] == ccd::Method::Cubic && ccd::ALL_METHODS[DNF] == ccd::Method::Dnf &&
              ccd::ALL_METHODS[VINCENT] == ccd::Method::Vincent && ccd::ALL_METHODS[CONSERVATIVE] == ccd::Method::Conservative);

struct MethodRun {
  double ms = 0;  // median over the passes of the whole frame's narrow phase
  ccd::BatchCounters counters;
  std::vector<bool> hits;  // every test of the frame, batch after batch, vertex-face first
};

// One timed configuration: a method and its separation depth.
struct Timed {
  ccd::Method method;
  int separation_depth;
};

// The frame's whole narrow phase for each configuration, the passes interleaved across them
// (pass p of every configuration before pass p + 1 of any): a burst of load from another job
// on a shared machine then falls on one pass of several configurations, which the median drops,
// rather than on every pass of one.
template <std::size_t N>
std::array<MethodRun, N> time_methods(const Frame& frame, const std::array<Timed, N>& timed, int passes) {
  std::array<MethodRun, N> runs;
  std::array<std::vector<double>, N> ms;
  for (int p = 0; p < passes; ++p) {
    for (std::size_t m = 0; m < N; ++m) {
      ccd::Options options;
      options.method = timed[m].method;
      options.separation_depth = timed[m].separation_depth;  // thickness 0: exact contact, as the simulation's pipeline asks
      MethodRun& run = runs[m];
      double total = 0;
      for (const Batch& b : frame.batches) {
        const ccd::BatchInput input{b.start, b.end, b.vertex_face, b.edge_edge};
        const auto begin = std::chrono::steady_clock::now();
        const ccd::BatchOutput out = ccd::run_batch(input, options, 1);
        total += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
        if (p == 0) {
          run.counters += out.counters;
          const std::size_t base = run.hits.size();
          run.hits.resize(base + b.vertex_face.size() + b.edge_edge.size(), false);
          for (const auto& hit : out.vertex_face) run.hits[base + hit.index] = true;
          for (const auto& hit : out.edge_edge) run.hits[base + b.vertex_face.size() + hit.index] = true;
        }
      }
      ms[m].push_back(total);
    }
  }
  for (std::size_t m = 0; m < N; ++m) runs[m].ms = ccd::median(ms[m]);
  return runs;
}

// The self-collision broad phase of the frame's rounds, both ways, on the identical motions:
// the btDbvt over every triangle against itself (what every round did before the patch tree)
// and the patch tree with its culling, each through feature_pairs to the elementary tests (the
// btDbvt's sorted and made unique, the patch tree's made once by their owners). Every round
// whole: a run's later rounds test only what moved since the round before.
struct SelfBroadPhase {
  double dbvt_ms = 0, patch_ms = 0;  // medians over the passes of the frame's rounds
  std::size_t dbvt_tests = 0, patch_tests = 0;
  long dbvt_pairs = 0, patch_pairs = 0;
  long dbvt_hits = 0, lost_hits = 0;  // vincent's hits among the btDbvt's tests; of those, not among the patch tree's
};

SelfBroadPhase time_self_broad_phase(const Frame& frame, const Model& model, int passes) {
  SelfBroadPhase out;
  std::vector<ccd::TriangleIndices> triangles;
  for (const Triangle& t : model.triangles) triangles.push_back({t[0], t[1], t[2]});
  const Scalar margin = model.scene.collisions.thickness;
  ccd::PatchTree patches(triangles, model.initial_positions);
  const ccd::FeatureOwners owners = ccd::feature_owners(triangles);
  ccd::BoxTree tree;  // built untimed on the first round; each timed round updates it in place, as a run does
  if (!frame.batches.empty()) {
    std::vector<ccd::Aabb> boxes(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
      boxes[i] = ccd::swept_box(triangles[i], frame.batches[0].start, frame.batches[0].end, margin);
    tree.update(boxes);
  }
  std::vector<double> dbvt_ms, patch_ms;
  const auto since = [](auto begin) { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count(); };
  // feature_pairs sorts its tests by these keys.
  const auto vf_less = [](const ccd::VertexFacePair& a, const ccd::VertexFacePair& b) {
    return std::tie(a.vertex, a.face) < std::tie(b.vertex, b.face);
  };
  const auto ee_less = [](const ccd::EdgeEdgePair& a, const ccd::EdgeEdgePair& b) {
    return std::tie(a.edge_a, a.edge_b) < std::tie(b.edge_a, b.edge_b);
  };
  for (int p = 0; p < passes; ++p) {
    double dbvt = 0, patch = 0;
    for (const Batch& b : frame.batches) {
      auto begin = std::chrono::steady_clock::now();
      std::vector<ccd::Aabb> boxes(triangles.size());
      for (std::size_t i = 0; i < triangles.size(); ++i) boxes[i] = ccd::swept_box(triangles[i], b.start, b.end, margin);
      tree.update(boxes);
      const auto dbvt_pairs = tree.self_pairs();
      const auto volumes = ccd::vertex_volumes(b.start, b.end, margin);
      const ccd::Candidates all = ccd::feature_pairs(triangles, triangles, dbvt_pairs, volumes);
      dbvt += since(begin);
      begin = std::chrono::steady_clock::now();
      const auto patch_pairs = patches.self_pairs(b.start, b.end, margin);
      ccd::Candidates kept = patch_pairs.empty() ? ccd::Candidates{}
                                                 : ccd::feature_pairs(triangles, triangles, patch_pairs, owners, owners,
                                                                      ccd::vertex_volumes(b.start, b.end, margin));
      patch += since(begin);
      if (p > 0) continue;
      out.dbvt_pairs += long(dbvt_pairs.size()), out.patch_pairs += long(patch_pairs.size());
      out.dbvt_tests += all.vertex_face.size() + all.edge_edge.size();
      out.patch_tests += kept.vertex_face.size() + kept.edge_edge.size();
      // Every contact the btDbvt's tests give must be among the patch tree's (sorted here).
      std::sort(kept.vertex_face.begin(), kept.vertex_face.end(), vf_less);
      std::sort(kept.edge_edge.begin(), kept.edge_edge.end(), ee_less);
      const ccd::BatchOutput hits = ccd::run_batch({b.start, b.end, all.vertex_face, all.edge_edge}, ccd::Options{}, 1);
      for (const auto& h : hits.vertex_face)
        out.lost_hits += !std::binary_search(kept.vertex_face.begin(), kept.vertex_face.end(), all.vertex_face[h.index], vf_less);
      for (const auto& h : hits.edge_edge)
        out.lost_hits += !std::binary_search(kept.edge_edge.begin(), kept.edge_edge.end(), all.edge_edge[h.index], ee_less);
      out.dbvt_hits += long(hits.vertex_face.size() + hits.edge_edge.size());
    }
    dbvt_ms.push_back(dbvt);
    patch_ms.push_back(patch);
  }
  out.dbvt_ms = ccd::median(dbvt_ms);
  out.patch_ms = ccd::median(patch_ms);
  return out;
}

// Where test i of a frame lives: its batch, kind and index there.
struct Located {
  const Batch* batch;
  bool vertex_face;
  std::size_t index;
};
Located locate(const Frame& frame, std::size_t i) {
  for (const Batch& b : frame.batches) {
    if (i < b.vertex_face.size()) return {&b, true, i};
    i -= b.vertex_face.size();
    if (i < b.edge_edge.size()) return {&b, false, i};
    i -= b.edge_edge.size();
  }
  return {nullptr, false, 0};
}

// Writes up to limit tests of each kind of the frame (an even sample when there are more), and
// every test where the methods differ, in the public query format; the truth column holds the
// conservative method's verdict.
void dump_frame(const Frame& frame, const fs::path& dir, const std::string& stem, std::size_t limit) {
  ccd::Options conservative;
  conservative.method = ccd::Method::Conservative;
  for (const ccd::QueryKind kind : {ccd::QueryKind::VertexFace, ccd::QueryKind::EdgeEdge}) {
    const bool vf = kind == ccd::QueryKind::VertexFace;
    std::size_t total = 0;
    for (const Batch& b : frame.batches) total += vf ? b.vertex_face.size() : b.edge_edge.size();
    const std::size_t stride = std::max<std::size_t>(1, (total + limit - 1) / std::max<std::size_t>(limit, 1));
    ccd::QueryFile file;
    file.kind = kind;
    std::size_t i = 0, global = 0;  // index among the kind's tests, and in frame order
    auto differing = frame.differing.begin();
    for (const Batch& b : frame.batches) {
      const ccd::BatchInput input{b.start, b.end, b.vertex_face, b.edge_edge};
      const std::size_t n = vf ? b.vertex_face.size() : b.edge_edge.size();
      const std::size_t offset = vf ? 0 : b.vertex_face.size();  // the kind's tests within the batch
      for (std::size_t k = 0; k < n; ++k, ++i) {
        const std::size_t at = global + offset + k;
        while (differing != frame.differing.end() && *differing < at) ++differing;
        const bool differs = differing != frame.differing.end() && *differing == at;
        if (i % stride != 0 && !differs) continue;
        const ccd::Query q = vf ? ccd::Query(ccd::gather(input, b.vertex_face[k])) : ccd::Query(ccd::gather(input, b.edge_edge[k]));
        file.queries.push_back(q);
        file.truth.push_back(ccd::elementary_ccd(kind, q, conservative).hit);
      }
      global += b.tests();
    }
    const fs::path folder = dir / std::string(ccd::kind_name(kind));
    fs::create_directories(folder);
    file.path = folder / (stem + ".csv");
    ccd::write_query_file(file.path, file);
    std::printf("wrote %s: %zu of the frame's %zu %s tests (a sample and every difference), %ld with contact "
                "(conservative's verdict)\n",
                file.path.c_str(), file.queries.size(), total, std::string(ccd::kind_name(kind)).c_str(),
                long(std::count(file.truth.begin(), file.truth.end(), true)));
  }
}

}  // namespace

int main(int argc, char** argv) {
  drape::keep_freed_memory();  // as the drape program does
  CLI::App app{
      "The paper's cloth benchmark on a scene: runs it once and, at the measured frames, times every CCD method "
      "on the identical elementary tests of the frame (every detection round of each of its steps), with cull "
      "rates, speed-ups and the agreement of their hits.\n\nExample: scene_bench scenes/pile.json --every 10 --check"};
  std::string scene_path, dump_dir;
  int frames = 0, every = 1, passes = 3, threads = 1, dump_frame_number = 0;
  int separation_depth = ccd::Options{}.separation_depth;
  std::size_t dump_limit = 200000;
  bool check = false, no_feature_boxes = false, twin = false;
  app.add_option("scene", scene_path, "Scene file")->required()->check(CLI::ExistingFile);
  app.add_option("--frames", frames, "Frames to run (default: the scene's)")->check(CLI::PositiveNumber);
  app.add_option("--every", every, "Measure every K-th frame")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--passes", passes, "Timed passes per method and frame, interleaved across the methods (the median is printed)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--threads", threads, "Threads of the simulation's own narrow phase (the timed ones use one)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--separation-depth", separation_depth,
                 "Levels of the filter's separation stage in the timed vincent and conservative runs (0: the paper's "
                 "filter alone; the simulation itself runs with the default, which decides the same)")
      ->capture_default_str()
      ->check(CLI::Range(0, 6));
  app.add_flag("--check", check, "Run the independent penetration check on every frame");
  app.add_flag("--vs-btdbvt", twin,
               "With self-collision: also run the scene with collisions.self_culling off (every round's self pairs from "
               "the btDbvt, as before the patch tree), frame by frame alternating with the main run, and print both "
               "frames' times; at measured frames also time both self-collision broad phases on the identical rounds");
  app.add_flag("--no-feature-boxes", no_feature_boxes,
               "Keep every feature pair of overlapping triangles (the paper's 15 tests per triangle pair)");
  app.add_option("--dump-ccd", dump_dir,
                 "Write the tests of one measured frame as query files DIR/vertex-face/*.csv and DIR/edge-edge/*.csv "
                 "(read back by `drape ccd DIR`); truth column: the conservative method's verdict");
  app.add_option("--dump-frame", dump_frame_number, "The frame to dump (default: the measured frame with most tests)");
  app.add_option("--dump-limit", dump_limit, "An even sample of about this many tests of each kind, plus every test where the methods differ")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);

  Model model, twin_model;
  try {
    Scene scene = load_scene(scene_path);
    if (no_feature_boxes) scene.collisions.feature_boxes = false;
    model = build_model(scene);
    scene.collisions.self_culling = false;
    if (twin) twin_model = build_model(scene);
  } catch (const SceneError& e) {
    std::fprintf(stderr, "scene_bench: %s\n", e.what());
    return 2;
  }
  if (frames <= 0) frames = model.scene.frames;
  if (twin && !(model.scene.collisions.self && model.scene.collisions.self_culling)) {
    std::fprintf(stderr, "scene_bench: --vs-btdbvt needs a scene with self-collision and self_culling on\n");
    return 2;
  }
  State state = initial_state(model);
  Integrator integrator(model, threads);
  State twin_state = twin ? initial_state(twin_model) : State{};
  std::unique_ptr<Integrator> twin_integrator = twin ? std::make_unique<Integrator>(twin_model, threads) : nullptr;
  if (!integrator.collisions()) {
    std::fprintf(stderr, "scene_bench: %s has no collision pipeline (no self-collision, no mesh obstacle)\n",
                 scene_path.c_str());
    return 2;
  }
  Frame current;
  bool measuring = false;  // only measured frames keep their tests (copies cost time and memory)
  integrator.collisions()->set_observer([&](const ccd::BatchInput& in, long triangle_pairs) {
    if (!measuring) return;
    current.triangle_pairs += triangle_pairs;
    Batch& b = current.batches.emplace_back();
    b.start.assign(in.start.begin(), in.start.end());
    b.end.assign(in.end.begin(), in.end.end());
    b.vertex_face.assign(in.vertex_face.begin(), in.vertex_face.end());
    b.edge_edge.assign(in.edge_edge.begin(), in.edge_edge.end());
  });

  std::printf("scene_bench %s: %zu vertices, %zu triangles, %d frames of %d steps (h = %.4g s), feature boxes %s, "
              "separation stage %d levels\n",
              scene_path.c_str(), model.vertex_count(), model.triangles.size(), frames, model.scene.frame_steps,
              model.scene.timestep(), model.scene.collisions.feature_boxes ? "on" : "off (paper's count)", separation_depth);
  std::printf("per measured frame: every detection round of each of its steps; one thread; median of %d passes, interleaved across the methods\n\n",
              passes);
  std::printf("%5s %9s %10s %7s %7s %8s %9s %9s %9s %9s %9s %8s %8s %8s %8s %6s %5s %6s %8s %9s %4s\n", "frame", "tri_pairs",
              "tests", "dnf%", "vin%", "vin%nc", "cubic_ms", "dnf_ms", "vin_ms", "cons_ms", "paper_ms", "vin/cub", "vin/dnf",
              "cons/vin", "pap/cub",
              "hits", "diff", "c-miss", "step_ms", "broad_ms", "pen");
  if (twin)
    std::printf("      with --vs-btdbvt, a second line: the run without self_culling (its step_ms), whether its state is still "
                "the same, and both self-collision broad phases on this frame's rounds (btDbvt, patch tree, ms, pairs, "
                "tests, and vincent's hits of the btDbvt's tests not among the patch tree's)\n");
  struct Measured {
    int frame;
    std::size_t tests, hits, culled_vincent;
    double ms[5];
    double broad_ms;  // the simulation's broad phase over the frame (all its steps and rounds)
    double step_ms = 0, twin_step_ms = 0;
    SelfBroadPhase self;
  };
  std::vector<Measured> measured;
  long disagreements = 0, beyond_conservative_total = 0, penetrations = 0;
  Frame dump;
  for (int f = 1; f <= frames; ++f) {
    current = Frame{};
    current.number = f;
    measuring = f % every == 0;
    const auto frame_begin = std::chrono::steady_clock::now();
    double broad_ms = 0;
    for (int step = 0; step < model.scene.frame_steps; ++step) {
      const StepReport r = integrator.step(state);
      broad_ms += r.collisions.broad_ms;
      if (!r.ok) {
        std::printf("stopped at frame %d: %s\n", f, r.failure.c_str());
        return 3;
      }
    }
    const double step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_begin).count() /
                           model.scene.frame_steps;
    double twin_step_ms = 0;
    bool same = false;
    if (twin) {
      const auto twin_begin = std::chrono::steady_clock::now();
      for (int step = 0; step < model.scene.frame_steps; ++step)
        if (const StepReport r = twin_integrator->step(twin_state); !r.ok) {
          std::printf("the run without self_culling stopped at frame %d: %s\n", f, r.failure.c_str());
          return 3;
        }
      twin_step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - twin_begin).count() /
                     model.scene.frame_steps;
      same = twin_state.positions == state.positions && twin_state.velocities == state.velocities;
    }
    int found = 0;
    if (check) penetrations += found = int(find_penetrations(model, state.positions, state.time).size());
    if (f % every != 0) continue;
    // The four methods, and vincent with the sign filter alone (no separation stage): the
    // paper's method, side by side.
    const std::array<MethodRun, 5> runs =
        time_methods(current, std::array<Timed, 5>{{{ccd::ALL_METHODS[CUBIC], separation_depth},
                                                     {ccd::ALL_METHODS[DNF], separation_depth},
                                                     {ccd::ALL_METHODS[VINCENT], separation_depth},
                                                     {ccd::ALL_METHODS[CONSERVATIVE], separation_depth},
                                                     {ccd::Method::Vincent, 0}}},
                     passes);
    // Disagreements: cubic, dnf or the paper's filter alone against vincent (no filter and no
    // stage of it may change a hit), and
    // hits of vincent the conservative method does not report (it answers exact contact; the
    // root-finding methods accept a distance of contact_tolerance times the extent at a root).
    long diff = 0, near = 0;
    std::size_t hits = 0;
    for (std::size_t i = 0; i < runs[VINCENT].hits.size(); ++i) {
      hits += runs[VINCENT].hits[i];
      const bool filter_differs = runs[CUBIC].hits[i] != runs[VINCENT].hits[i] || runs[DNF].hits[i] != runs[VINCENT].hits[i] ||
                                  runs[PAPER].hits[i] != runs[VINCENT].hits[i];
      const bool beyond_conservative = runs[CONSERVATIVE].hits[i] < runs[VINCENT].hits[i];
      diff += filter_differs;
      near += beyond_conservative;
      if (filter_differs || beyond_conservative) current.differing.push_back(i);
      if ((filter_differs && diff <= 10) || (beyond_conservative && near <= 3)) {
        const Located at = locate(current, i);
        std::printf("  differs: frame %d %s test %zu: cubic %d dnf %d vincent %d conservative %d\n", f,
                    at.vertex_face ? "vertex-face" : "edge-edge", at.index, int(runs[CUBIC].hits[i]),
                    int(runs[DNF].hits[i]), int(runs[VINCENT].hits[i]), int(runs[CONSERVATIVE].hits[i]));
      }
    }
    beyond_conservative_total += near;
    disagreements += diff;
    const std::size_t n = current.tests();
    const std::size_t culled = runs[VINCENT].counters.culled;
    const auto pct = [](double a, double b) { return b > 0 ? 100.0 * a / b : 0.0; };
    std::printf("%5d %9ld %10zu %6.2f%% %6.2f%% %7.2f%% %9.2f %9.2f %9.2f %9.2f %9.2f %7.2fx %7.2fx %7.2fx %7.2fx %6zu %5ld %6ld %8.1f %9.1f %4s\n",
                f, current.triangle_pairs, n, pct(double(runs[DNF].counters.culled), double(n)), pct(double(culled), double(n)),
                pct(double(culled), double(n - hits)), runs[CUBIC].ms, runs[DNF].ms, runs[VINCENT].ms, runs[CONSERVATIVE].ms,
                runs[PAPER].ms, runs[CUBIC].ms / runs[VINCENT].ms, runs[DNF].ms / runs[VINCENT].ms,
                runs[CONSERVATIVE].ms / runs[VINCENT].ms, runs[CUBIC].ms / runs[PAPER].ms,
                hits, diff, near, step_ms, broad_ms, check ? std::to_string(found).c_str() : "-");
    Measured row{f, n, hits, culled, {runs[0].ms, runs[1].ms, runs[2].ms, runs[3].ms, runs[PAPER].ms}, broad_ms, 0, 0, {}};
    if (twin) {
      row.step_ms = step_ms, row.twin_step_ms = twin_step_ms;
      row.self = time_self_broad_phase(current, model, passes);
      std::printf("      without culling: step_ms %.1f (%.2fx this run's), state %s; self broad phase: btDbvt %.1f ms "
                  "(%ld pairs, %zu tests), patch tree %.1f ms (%ld pairs, %zu tests), %.1fx; hits %ld, lost %ld\n",
                  twin_step_ms, twin_step_ms / step_ms, same ? "the same" : "differs", row.self.dbvt_ms, row.self.dbvt_pairs,
                  row.self.dbvt_tests, row.self.patch_ms, row.self.patch_pairs, row.self.patch_tests,
                  row.self.dbvt_ms / row.self.patch_ms, row.self.dbvt_hits, row.self.lost_hits);
    }
    std::fflush(stdout);
    measured.push_back(row);
    if (!dump_dir.empty() && (dump_frame_number == f || (dump_frame_number == 0 && n > dump.tests()))) dump = std::move(current);
  }
  if (measured.empty()) {
    std::printf("no frame measured\n");
    return 0;
  }

  // Totals over all measured frames, and over the heavy ones: at least a tenth of the most
  // tests any measured frame had.
  std::size_t most = 0;
  for (const auto& m : measured) most = std::max(most, m.tests);
  for (const bool heavy_only : {false, true}) {
    double ms[5] = {0, 0, 0, 0, 0}, broad = 0, step = 0, twin_step = 0, self_dbvt = 0, self_patch = 0;
    long lost = 0, self_hits = 0;
    std::size_t tests = 0, hits = 0, culled = 0, count = 0, least = SIZE_MAX;
    for (const auto& m : measured) {
      if (heavy_only && m.tests * 10 < most) continue;
      ++count;
      tests += m.tests, hits += m.hits, culled += m.culled_vincent, least = std::min(least, m.tests);
      for (int k = 0; k < 5; ++k) ms[k] += m.ms[k];
      broad += m.broad_ms;
      step += m.step_ms, twin_step += m.twin_step_ms, self_dbvt += m.self.dbvt_ms, self_patch += m.self.patch_ms;
      lost += m.self.lost_hits, self_hits += m.self.dbvt_hits;
    }
    std::printf("\n%s (%zu frames, %zu to %zu tests a frame, %zu in all):\n",
                heavy_only ? "heavy frames, at least a tenth of the most tests" : "all measured frames", count, least,
                most, tests);
    std::printf("  narrow phase: cubic %.1f ms, dnf %.1f ms, vincent %.1f ms, conservative %.1f ms\n", ms[0], ms[1], ms[2],
                ms[3]);
    std::printf("  broad phase (the simulation's, every round and contact search of the frames' steps) %.1f ms: %.2fx vincent's "
                "narrow phase\n",
                broad, broad / ms[2]);
    std::printf("  vincent %.2fx faster than cubic, %.2fx than dnf; conservative costs %.2fx vincent\n", ms[0] / ms[2],
                ms[1] / ms[2], ms[3] / ms[2]);
    std::printf("  the paper's filter alone (vincent, separation stage off) %.1f ms: %.2fx faster than cubic\n", ms[4],
                ms[0] / ms[4]);
    std::printf("  vincent culled %.2f%% of all tests and %.2f%% of the tests with no collision (%zu hits)\n",
                tests ? 100.0 * double(culled) / double(tests) : 0.0,
                tests > hits ? 100.0 * double(culled) / double(tests - hits) : 0.0, hits);
    if (twin)
      std::printf("  without self_culling (btDbvt self pairs), alternating frame by frame: a step %.1f ms against %.1f, "
                  "%.2fx; the self-collision broad phase on the identical rounds: btDbvt %.1f ms, patch tree %.1f ms, "
                  "%.2fx; %ld of the btDbvt tests' %ld hits not among the patch tree's\n",
                  twin_step / count, step / count, twin_step / step, self_dbvt, self_patch, self_dbvt / self_patch, lost,
                  self_hits);
  }
  std::printf("\n%ld tests where cubic, dnf or the paper's filter alone disagree with vincent; %ld hits of vincent that conservative does not report "
              "(c-miss: contact within the root-finders' tolerance, not exact contact)%s\n",
              disagreements, beyond_conservative_total,
              check ? (", " + std::to_string(penetrations) + " penetrating triangle pairs over the run").c_str() : "");
  if (!dump_dir.empty()) {
    if (dump.batches.empty()) {
      std::fprintf(stderr, "scene_bench: frame %d was not measured; nothing dumped\n", dump_frame_number);
      return 2;
    }
    try {
      dump_frame(dump, dump_dir, fs::path(scene_path).stem().string() + "_frame" + std::to_string(dump.number), dump_limit);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "scene_bench: %s\n", e.what());
      return 2;
    }
  }
  return 0;
}
