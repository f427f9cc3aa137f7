// Energy against its bound: a run's kinetic plus potential energy stays below its start plus
// the work of its sources (handles, wind, moving obstacles), on mesh obstacles too; the limits
// warn and stop a run that passes them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

#include "drape/core/model.h"
#include "drape/core/run.h"
#include "../temp_root.h"
#include "struck_curtain.h"

using namespace drape;
namespace fs = std::filesystem;

namespace {

const std::string SOURCE = DRAPE_SOURCE_DIR;

struct Ran {
  RunOutcome outcome;
  std::vector<FrameStats> frames;
  Scalar scale = 0;
};

Ran run(const Model& model, const std::string& name, int frames = 0, bool check = false) {
  RunSettings settings;
  settings.check_penetrations = check;
  settings.out = drape::testing::temp_root("energy") / name;
  fs::remove_all(settings.out);
  settings.frames = frames > 0 ? frames : model.scene.frames;
  settings.write_meshes = false;
  const std::atomic<bool> interrupt{false};
  Ran ran;
  ran.scale = energy_scale(model);
  ran.outcome = run_simulation(model, settings, interrupt, [&](const FrameStats& s) { ran.frames.push_back(s); });
  fs::remove_all(settings.out);
  return ran;
}

// Every frame within a hundredth of the energy scale of its bound, and no warning.
void expect_within_bound(const Ran& ran, const std::string& name) {
  EXPECT_EQ(ran.outcome.end, RunEnd::Completed) << name << ": " << ran.outcome.message;
  for (const FrameStats& s : ran.frames) {
    EXPECT_LE(s.energy_excess, 0.01 * ran.scale)
        << name << " frame " << s.frame << ": energy " << s.kinetic_energy + s.potential_energy << " J, bound "
        << s.kinetic_energy + s.potential_energy - s.energy_excess << " J";
    EXPECT_EQ(s.warnings, 0) << name << " frame " << s.frame;
  }
}

}  // namespace

// The shipped mesh scene in full: its energy grew from 1.7 J to 28 J in 40 frames while the
// cloth lay on the box (issue 19).
TEST(Energy, TheMeshObstacleSceneInFullStaysWithinItsBound) {
  const Model model = build_model(load_scene(SOURCE + "/scenes/mesh_obstacle.json"));
  const Ran ran = run(model, "mesh_obstacle");
  ASSERT_EQ(int(ran.frames.size()), model.scene.frames + 1);
  expect_within_bound(ran, "mesh_obstacle");
}

// A tablecloth on a table-like mesh (a top and four legs) at the default 10 steps a frame: it
// climbed from 4 J to about 2,400 J and crawled up the table (issue 19); at 7152cdc this one
// still rose from 3.77 J to 8.69 J by frame 44, stretch 1.13. Coarser than the shipped
// scenes/tablecloth.json, and without self-collision, to keep the suite quick; the shipped
// scene runs in full in bench/penetration_runs.sh.
TEST(Energy, ATableclothOnATableMeshStaysWithinItsBound) {
  const Model model = build_model(parse_scene(R"({
    "frames": 45,
    "cloths": [{"grid": {"size": [1.6, 1.6], "resolution": [30, 30]}, "transform": {"translate": [0, 0, 1.0]}}],
    "obstacles": [{"mesh": ")" + SOURCE + R"(/scenes/meshes/table.obj"}, {"plane": {}}],
    "friction": 0.4})", "table.json"));
  const Ran ran = run(model, "table");
  expect_within_bound(ran, "table");
  // It lies on the table: its lowest point above the floor, its middle on the top.
  EXPECT_GT(ran.frames.back().min_distance_obstacle.value_or(0), -1e-9);
}

// A ribbon held upright drops onto the ground and piles onto itself in folds (a smaller
// scenes/pile.json, 30 frames): the collision response stopped approaching layers, the spread
// of that change through the step freed the vertices lying on the ground (the solve's contacts
// and friction were left out of it), and the analytic response after it stopped them again:
// the stretch springs between ended each step compressed by up to 14 %, and frame 24 was
// 0.44 J above its bound (limit to warn 0.069 J). The run is chaotic: this guards the outcome,
// not the mechanism (the old spread with its matrix computed another way, equal up to
// rounding, passed it too; docs/collisions.md has the same-state comparison). Rounding alone
// moves the first touch of its layers from frame 18 to frame 25 (OpenBLAS's kernels for
// Sandybridge, Haswell and SkylakeX, picked by the machine, in CHOLMOD's factorisation): it
// runs 30 frames, so that it piles on every machine (25 gave 201 touches with SkylakeX's).
TEST(Energy, ARibbonPilingOnTheGroundStaysWithinItsBound) {
  const Model model = build_model(parse_scene(R"({
    "frame_time": 0.033333333333333333, "frame_steps": 10, "frames": 30,
    "cloths": [{"grid": {"size": [0.4, 1.5], "resolution": [20, 75]},
                "transform": {"translate": [0, 0, 0.8], "rotate": [85, 1, 0, 0]},
                "material": {"density": 0.15, "stretch": 2000, "shear": 200, "bend": 0.2, "damping": 0.002}}],
    "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
    "friction": 0.5,
    "collisions": {"self": true, "obstacles": true, "thickness": 0.004, "method": "vincent"}})", "ribbon.json"));
  const Ran ran = run(model, "ribbon");
  ASSERT_EQ(int(ran.frames.size()), model.scene.frames + 1);
  expect_within_bound(ran, "ribbon");
  // It does pile: the layers touch in the last frames (contacts held in the solve, and the
  // response's proximity impulses).
  long touches = 0;
  for (const FrameStats& s : ran.frames) touches += s.collisions.proximity_impulses + s.collisions.held_self_contacts;
  EXPECT_GT(touches, 1000);
}

// The same table with the step never halved: the step itself keeps the bound, not the
// halving that takes an energy-making step again. Before the contacts with obstacles were held
// in the solve (Integrator::find_contacts) the landing alone rose from 3.77 J to 4.10 J, stretch
// 1.037, and the response then stopped rim vertices the solve had moved.
TEST(Energy, ATableclothOnATableMeshStaysWithinItsBoundWithoutHalving) {
  const Model model = build_model(parse_scene(R"({
    "frames": 20,
    "cloths": [{"grid": {"size": [1.6, 1.6], "resolution": [30, 30]}, "transform": {"translate": [0, 0, 1.0]}}],
    "obstacles": [{"mesh": ")" + SOURCE + R"(/scenes/meshes/table.obj"}, {"plane": {}}],
    "friction": 0.4, "solver": {"max_halvings": 0}})", "table_unhalved.json"));
  const Ran ran = run(model, "table_unhalved");
  expect_within_bound(ran, "table_unhalved");
  for (const FrameStats& s : ran.frames) {
    EXPECT_EQ(s.step_halvings, 0);
    EXPECT_LT(s.max_stretch, 1.02) << "frame " << s.frame;
  }
}

// The shipped tablecloth with the projective solver: the cloth's vertices resting on the top
// held as constraints (one mesh contact each; a vertex near an edge keeps its penalty), as the
// spheres and planes are. With the penalty alone the top's vertices sank within the thickness,
// the response's repulsion pushed them out every step and strained the cloth (in full: stretch
// 1.15, energy 0.98 J over its bound, 24 frames past the warning limit; with the constraints
// 1.07, 0.385 J, none).
// Its first 24 frames (landing, the flaps falling past the top's edges; 7 s).
TEST(Energy, ATableclothOnATableMeshWithTheProjectiveSolverStaysWithinTheWarningLimit) {
  Scene scene = load_scene(SOURCE + "/scenes/tablecloth.json");
  scene.solver = SolverSpec{};
  scene.solver.kind = SolverKind::Projective;
  scene.solver.tolerance = default_tolerance(SolverKind::Projective);
  const Model model = build_model(scene);
  const Ran ran = run(model, "table_projective", 24);
  // Not yet within a hundredth of the scale like the reference (0.385 J over at frame 12, 3 %
  // of the scale): within the scene's warning limit, and stretched less.
  EXPECT_EQ(ran.outcome.end, RunEnd::Completed) << ran.outcome.message;
  for (const FrameStats& s : ran.frames) {
    EXPECT_EQ(s.warnings, 0) << "frame " << s.frame;
    EXPECT_LT(s.max_stretch, 1.1) << "frame " << s.frame;
  }
}

// A handle that moves does work: counted, so the energy it gives is within the bound.
TEST(Energy, AMovingHandlesWorkIsCountedInTheBound) {
  const Model model = build_model(parse_scene(R"({
    "frames": 20,
    "cloths": [{"grid": {"resolution": [8, 8]}}],
    "handles": [{"corners": ["top-left", "top-right"], "motion": {"velocity": [0, 0, 2]}}]})", "lift.json"));
  const Ran ran = run(model, "lift");
  expect_within_bound(ran, "lift");
  // Lifted: its potential energy rose, and the handles' counted work paid for it.
  EXPECT_GT(ran.frames.back().potential_energy, ran.frames.front().potential_energy + 0.1);
  EXPECT_GT(ran.frames.back().external_work, ran.frames.back().potential_energy - ran.frames.front().potential_energy);
}

// A sphere that rises under a cloth lifts it: the contacts held in the solve push the cloth at
// the sphere's velocity, and their work (normal impulses and friction at the surface's velocity)
// is counted, so the energy it gives is within the bound.
TEST(Energy, ARisingSpheresWorkThroughHeldContactsIsCountedInTheBound) {
  const Model model = build_model(parse_scene(R"({
    "frame_time": 0.04, "frame_steps": 4, "frames": 15,
    "cloths": [{"grid": {"size": [0.5, 0.5], "resolution": [6, 6]}, "transform": {"translate": [0, 0, 0.31]}}],
    "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.3}, "motion": {"velocity": [0, 0, 1]}}],
    "collisions": {"thickness": 0.01}, "friction": 1.0})", "rising.json"));
  const Ran ran = run(model, "rising");
  expect_within_bound(ran, "rising");
  // Lifted by about 0.6 m, and the counted work paid for it.
  EXPECT_GT(ran.frames.back().potential_energy, ran.frames.front().potential_energy + 0.1);
  EXPECT_GT(ran.frames.back().external_work, ran.frames.back().potential_energy - ran.frames.front().potential_energy);
}

// A curtain of 6 cm cells, pinned along its top, struck at mid-height by a 10 cm ball moving
// at 2, 4 and 8 m/s (at 8 with friction 0.3 and without): the ball comes between the vertices of a cell, so a
// response that holds the cloth out of a sphere vertex by vertex let it pass through the cloth
// (issue 19: triangles 3.7 cm inside the sphere, 29 crossing pairs in 25 frames at 2 m/s with
// vertices alone). The faces' contacts keep every triangle out of the ball (and the cloth out
// of itself as it swings back) in every frame, the energy within its bound, and the cloth from
// stretching. At 8 m/s the impact's frame ends 0.08 J (3.5 % of the energy scale) above the
// bound: within the scene's warning limit, not within the hundredth the slower strikes keep.
TEST(Energy, APinnedCurtainStruckByABallStaysOutOfItWithinItsBound) {
  for (const auto& [speed, friction] : {std::pair{2.0, 0.3}, std::pair{4.0, 0.3}, std::pair{8.0, 0.3}, std::pair{8.0, 0.0}}) {
    const std::string json =
        struck_curtain_json(R"({"density": 0.15, "stretch": 2000, "shear": 200, "bend": 0.2, "damping": 0.002})", speed, friction);
    const Model model = build_model(parse_scene(json, "curtain.json"));
    const std::string name = "curtain at " + std::to_string(speed) + " m/s, friction " + std::to_string(friction);
    const Ran ran = run(model, "curtain", 0, true);
    if (speed < 5) {
      expect_within_bound(ran, name);
    } else {
      EXPECT_EQ(ran.outcome.end, RunEnd::Completed) << name << ": " << ran.outcome.message;
      for (const FrameStats& s : ran.frames) EXPECT_EQ(s.warnings, 0) << name << " frame " << s.frame;
    }
    for (const FrameStats& s : ran.frames) {
      EXPECT_EQ(s.penetrations.value_or(-1), 0) << name << " frame " << s.frame;
      EXPECT_LT(s.max_stretch, 1.05) << name << " frame " << s.frame;
    }
    EXPECT_GT(ran.frames.back().external_work, 0) << name;  // the ball did push the cloth
  }
}

// A cloth placed 5 cm under the ground is pushed out of it: energy no source gave (about 4 %
// of the scale), so low limits warn and stop, keeping the frame that passed them.
TEST(Limits, EnergyBeyondTheLimitsWarnsThenStops) {
  const std::string scene = R"({"frames": 5, "cloths": [{"grid": {"resolution": [4, 4]}, "transform": {"translate": [0, 0, -0.05]}}],
    "obstacles": [{"plane": {}}], "limits": {"energy_warn": 0.01, "energy_stop": %s}})";
  const auto with_stop = [&](const char* stop) {
    std::string text = scene;
    text.replace(text.find("%s"), 2, stop);
    return build_model(parse_scene(text, "under.json"));
  };
  const Ran warned = run(with_stop("1"), "warned");
  EXPECT_EQ(warned.outcome.end, RunEnd::Completed);
  ASSERT_GE(warned.frames.size(), 2u);
  EXPECT_EQ(warned.frames[1].warnings, 1);
  ASSERT_EQ(warned.frames[1].messages.size(), 1u);
  EXPECT_NE(warned.frames[1].messages[0].find("above its start plus the sources' work"), std::string::npos)
      << warned.frames[1].messages[0];
  const Ran stopped = run(with_stop("0.02"), "stopped");
  EXPECT_EQ(stopped.outcome.end, RunEnd::Stopped);
  EXPECT_NE(stopped.outcome.message.find("frame 1: energy"), std::string::npos) << stopped.outcome.message;
  EXPECT_EQ(stopped.frames.size(), 2u);  // frames 0 and 1 written, then the stop
}

TEST(Limits, StretchBeyondTheLimitsWarnsThenStops) {
  // Two corners yanked apart at 20 m/s.
  const std::string scene = R"({"frames": 10, "gravity": [0, 0, 0], "cloths": [{"grid": {"resolution": [4, 4]}}],
    "handles": [{"corners": ["top-left"], "motion": {"velocity": [-20, 0, 0]}},
                {"corners": ["bottom-right"], "motion": {"velocity": [20, 0, 0]}}],
    "limits": {"stretch_warn": 1.1, "stretch_stop": 3, "energy_warn": 1e6, "energy_stop": 1e6}})";
  const Ran ran = run(build_model(parse_scene(scene, "yank.json")), "yank");
  EXPECT_EQ(ran.outcome.end, RunEnd::Stopped);
  EXPECT_NE(ran.outcome.message.find("stretched to"), std::string::npos) << ran.outcome.message;
  int warned = 0;
  for (const FrameStats& s : ran.frames) warned += s.warnings;
  EXPECT_GE(warned, 2);
  EXPECT_GT(ran.frames.back().max_stretch, 3);
}
