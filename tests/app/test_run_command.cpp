// drape run, validate and check-stats end to end: output files, stopping and interrupting
// without losing frames, determinism, and the golden-statistics regression of every scene.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <set>
#include <thread>
#include <vector>

#include "drape/core/stats_columns.h"
#include "drape_process.h"

using drape::testing::lines;
using drape::testing::REPRODUCIBLE_BLAS;
using drape::testing::run_drape;
using drape::testing::run_drape_reproducibly;
using drape::testing::Outcome;
namespace fs = std::filesystem;

namespace {

const std::string SOURCE = DRAPE_SOURCE_DIR;

fs::path temp_dir(const std::string& name) { return drape::testing::fresh_temp_path("run_test", name); }

fs::path write_scene(const std::string& name, const std::string& text) {
  const fs::path path = temp_dir(name + ".json");
  std::ofstream(path) << text;
  return path;
}

std::size_t count_fields(const std::string& line) { return std::count(line.begin(), line.end(), ',') + 1; }

// stats.csv without the timing columns (those the stats table's golden comparison ignores),
// for bit-for-bit comparison.
std::vector<std::string> without_timings(const fs::path& stats) {
  std::set<std::string> timings;
  for (const drape::StatsColumn& column : drape::stats_columns())
    if (column.tolerance.ignore) timings.insert(column.name);
  std::vector<std::string> out;
  std::vector<bool> keep;
  for (const std::string& line : lines(stats)) {
    std::stringstream in(line);
    std::string cell, kept;
    for (std::size_t column = 0; std::getline(in, cell, ','); ++column) {
      if (out.empty()) keep.push_back(!timings.count(cell));
      if (column < keep.size() && keep[column]) kept += cell + ",";
    }
    out.push_back(kept);
  }
  return out;
}

}  // namespace

TEST(RunCommand, WritesFramesStatisticsAndTheScene) {
  const fs::path out = temp_dir("hanging");
  const Outcome run = run_drape("run " + SOURCE + "/scenes/hanging.json --frames 3 --quiet --out " + out.string());
  ASSERT_EQ(run.status, 0) << run.output;
  for (int frame = 0; frame <= 3; ++frame)
    EXPECT_TRUE(fs::exists(out / ("frame_0000" + std::to_string(frame) + ".obj"))) << frame;
  EXPECT_TRUE(fs::exists(out / "scene.json"));
  const auto stats = lines(out / "stats.csv");
  ASSERT_EQ(stats.size(), 5u);
  for (const char* column : {"frame", "sim_time", "wall_ms", "solve_ms", "solver_iterations", "kinetic_energy",
                             "potential_energy", "max_stretch", "min_distance_obstacle"})
    EXPECT_NE(stats[0].find(column), std::string::npos) << column;
  EXPECT_EQ(stats[4].substr(0, 2), "3,");
}

TEST(RunCommand, ValidateAcceptsAndRejects) {
  const Outcome good = run_drape("validate " + SOURCE + "/scenes/flag.json");
  EXPECT_EQ(good.status, 0) << good.output;
  EXPECT_NE(good.output.find("valid"), std::string::npos);
  const fs::path bad = write_scene("bad", R"({"cloths": [{"grid": {"resolution": [0, 3]}}]})");
  const Outcome rejected = run_drape("validate " + bad.string());
  EXPECT_EQ(rejected.status, 2);
  EXPECT_NE(rejected.output.find(bad.string() + ": /cloths/0/grid/resolution/0: expected an integer from 1"),
            std::string::npos)
      << rejected.output;
  EXPECT_EQ(run_drape("run " + bad.string()).status, 2);
  EXPECT_EQ(run_drape("run /nonexistent.json").status, 2);
  EXPECT_EQ(run_drape("run " + SOURCE + "/scenes/flag.json --frames 0").status, 2);
}

// The summaries name what holds the cloth: a mesh cloth whose membrane is triangles has a
// membrane triangle for each of its mesh's faces, not only springs, and which bending model.
TEST(RunCommand, ValidateCountsAMembranesTriangles) {
  const std::string mesh = SOURCE + "/scenes/meshes/disc_30cm_cells_12mm.obj";
  std::ifstream obj(mesh);
  int faces = 0;
  for (std::string line; std::getline(obj, line);) faces += line.rfind("f ", 0) == 0;
  ASSERT_GT(faces, 0);
  const fs::path scene = write_scene("membrane", R"({"cloths": [{"mesh": ")" + mesh +
                                                     R"(", "material": {"preset": "royal-target", "membrane": "triangles"}}]})");
  const Outcome outcome = run_drape("validate " + scene.string());
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  EXPECT_NE(outcome.output.find(", " + std::to_string(faces) + " membrane triangles, "), std::string::npos) << outcome.output;
  // The disc of half cells lies on a grid's lattice: the grid's bending stencils; the ring
  // disc's triangles are not a lattice's: hinges.
  EXPECT_NE(outcome.output.find(" bending stencils (a grid's), "), std::string::npos) << outcome.output;
  const fs::path ring = write_scene("ring", R"({"cloths": [{"mesh": ")" + SOURCE + R"(/scenes/meshes/disc_30cm_12mm.obj", "material": {"preset": "royal-target"}}]})");
  const Outcome hinges = run_drape("validate " + ring.string());
  EXPECT_EQ(hinges.status, 0) << hinges.output;
  EXPECT_NE(hinges.output.find(" bending hinges, "), std::string::npos) << hinges.output;
}

// A scene whose cloth starts through a mesh obstacle is bad input (core's
// StartCheck.RefusesMeshesThatMeetAtTheStartAndNamesThem has the cases): validate and run say so,
// naming the scene, and the run writes nothing.
TEST(RunCommand, AClothStartingThroughAMeshObstacleIsRefused) {
  const fs::path scene = write_scene("through_box", R"({"cloths": [{"grid": {"resolution": [5, 5]}, "transform": {"translate": [0, 0, 0.1]}}],
      "obstacles": [{"mesh": ")" + SOURCE + R"(/scenes/meshes/box.obj", "transform": {"scale": 0.5}}]})");
  const Outcome validated = run_drape("validate " + scene.string());
  EXPECT_EQ(validated.status, 2) << validated.output;
  EXPECT_NE(validated.output.find(scene.string() + ": the scene starts with its meshes meeting"), std::string::npos)
      << validated.output;
  const fs::path out = temp_dir("through_box_run");
  const Outcome ran = run_drape("run " + scene.string() + " --quiet --out " + out.string());
  EXPECT_EQ(ran.status, 2) << ran.output;
  EXPECT_NE(ran.output.find("passes through /obstacles/0 (box.obj) triangle"), std::string::npos) << ran.output;
  EXPECT_FALSE(fs::exists(out / "stats.csv"));
}

TEST(RunCommand, EveryUserSceneInBenchValidatesAndRuns) {
  // bench/user_scenes/ (the scenes of the kind users bring, run in full by a benchmark) must
  // not rot as the scene format changes: each validates, runs two frames under --check and
  // passes drape check.
  std::size_t scenes = 0;
  for (const auto& entry : fs::directory_iterator(SOURCE + "/bench/user_scenes")) {
    if (entry.path().extension() != ".json") continue;
    const Outcome valid = run_drape("validate " + entry.path().string());
    EXPECT_EQ(valid.status, 0) << valid.output;
    const fs::path out = temp_dir("user_" + entry.path().stem().string());
    const Outcome run = run_drape("run " + entry.path().string() + " --frames 2 --check --quiet --out " + out.string());
    EXPECT_EQ(run.status, 0) << entry.path() << ": " << run.output;
    const Outcome check = run_drape("check " + out.string());
    EXPECT_EQ(check.status, 0) << entry.path() << ": " << check.output;
    ++scenes;
  }
  EXPECT_GE(scenes, 5u);
}

TEST(RunCommand, ValidateWarnsWhenTheThicknessIsLargeAgainstTheEdges) {
  // The Cusick disc: edges of about 6 mm against the default 5 mm thickness, self-collision on.
  const Outcome fine = run_drape("validate " + SOURCE + "/scenes/cusick_drape.json");
  EXPECT_EQ(fine.status, 0) << fine.output;
  EXPECT_NE(fine.output.find("warning: the thickness (0.005 m) is large against the cloth's shortest edge"),
            std::string::npos)
      << fine.output;
  EXPECT_NE(fine.output.find("rest_clamped_pairs"), std::string::npos) << fine.output;
  // Self-collision off, or edges long enough: nothing to say.
  const Outcome coarse = run_drape("validate " + SOURCE + "/scenes/flag.json");
  EXPECT_EQ(coarse.output.find("warning"), std::string::npos) << coarse.output;
}

TEST(RunCommand, AStoppedRunSaysWhyAndKeepsItsFrames) {
  // The cloth falls out of the scene bounds during its fourth frame or so.
  const fs::path scene = write_scene("falls", R"({"comment": "falls out of its bounds",
    "frame_time": 0.04, "frame_steps": 2, "frames": 50,
    "cloths": [{"grid": {"resolution": [4, 4]}, "transform": {"translate": [0, 0, 1]}}],
    "bounds": {"min": [-1, -1, 0.95], "max": [1, 1, 2]}})");
  const fs::path out = temp_dir("falls_out");
  const Outcome run = run_drape("run " + scene.string() + " --quiet --out " + out.string());
  EXPECT_EQ(run.status, 3) << run.output;
  EXPECT_NE(run.output.find("the cloth exploded"), std::string::npos) << run.output;
  const auto stats = lines(out / "stats.csv");
  ASSERT_GE(stats.size(), 3u);
  const int last_frame = std::stoi(stats.back().substr(0, stats.back().find(',')));
  EXPECT_NE(run.output.find("frame " + std::to_string(last_frame + 1)), std::string::npos) << run.output;
  for (int frame = 0; frame <= last_frame; ++frame) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.obj", frame);
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  for (const auto& line : stats) EXPECT_EQ(count_fields(line), count_fields(stats[0]));
}

// A cloth placed 5 cm under the ground is pushed out of it, energy no source gave: with low
// limits the run says so on the terminal even with --quiet, counts it in stats.csv, and stops
// with status 3 past the second limit, keeping its frames.
TEST(RunCommand, EnergyPastTheLimitsWarnsOnTheTerminalAndStops) {
  const std::string under = R"({"frames": 5, "cloths": [{"grid": {"resolution": [4, 4]}, "transform": {"translate": [0, 0, -0.05]}}],
    "obstacles": [{"plane": {}}], "limits": {"energy_warn": 0.01, "energy_stop": )";
  const fs::path warned = temp_dir("under_warned");
  const Outcome warn = run_drape("run " + write_scene("under_warn", under + "1}}").string() + " --quiet --out " + warned.string());
  EXPECT_EQ(warn.status, 0) << warn.output;
  EXPECT_NE(warn.output.find("drape run: warning: frame 1: energy"), std::string::npos) << warn.output;
  EXPECT_NE(warn.output.find(" frame(s) passed a limit (column warnings of stats.csv"), std::string::npos) << warn.output;
  const auto rows = lines(warned / "stats.csv");
  ASSERT_EQ(rows.size(), 7u);
  EXPECT_EQ(rows[2].substr(rows[2].rfind(',') + 1), "1") << rows[2];  // warnings, the last column
  const fs::path stopped = temp_dir("under_stopped");
  const Outcome stop = run_drape("run " + write_scene("under_stop", under + "0.02}}").string() + " --quiet --out " + stopped.string());
  EXPECT_EQ(stop.status, 3) << stop.output;
  EXPECT_NE(stop.output.find("drape run: stopped: frame 1: energy"), std::string::npos) << stop.output;
  EXPECT_TRUE(fs::exists(stopped / "frame_00001.obj"));
  EXPECT_EQ(lines(stopped / "stats.csv").size(), 3u);
}

// A frame in which the collision response's fail-safe froze colliding vertices is said and
// counted as a warning: with no impulse or impact-zone round allowed, a cloth thrown at a mesh
// box at 30 m/s (the cg solver: its contacts are the response's alone) reaches the fail-safe
// on its first contact.
TEST(RunCommand, TheCollisionFailSafeWarnsOnTheTerminal) {
  const fs::path scene = write_scene("fail_safe", R"({"frames": 4, "cloths": [{"grid": {"resolution": [6, 6]},
      "transform": {"translate": [0, 0, 0.62]}, "velocity": [0, 0, -30]}],
      "obstacles": [{"mesh": ")" + SOURCE + R"(/scenes/meshes/box.obj"}], "solver": {"type": "cg"},
      "collisions": {"max_impulse_iterations": 0, "max_zone_iterations": 0}})");
  const fs::path out = temp_dir("fail_safe_run");
  const Outcome ran = run_drape("run " + scene.string() + " --quiet --out " + out.string());
  EXPECT_EQ(ran.status, 0) << ran.output;
  EXPECT_NE(ran.output.find("the collision response's fail-safe held colliding cloth vertices"), std::string::npos) << ran.output;
  const auto rows = lines(out / "stats.csv");
  ASSERT_EQ(rows.size(), 6u);
  int warned = 0;
  for (std::size_t r = 1; r < rows.size(); ++r) warned += rows[r].substr(rows[r].rfind(',') + 1) != "0";
  EXPECT_GT(warned, 0);
}

TEST(RunCommand, InterruptKeepsEveryFinishedFrame) {
  const fs::path out = temp_dir("interrupted");
  const pid_t child = fork();
  if (child == 0) {
    const std::string scene = SOURCE + "/scenes/drape_sphere.json";
    execl(DRAPE_EXECUTABLE, DRAPE_EXECUTABLE, "run", scene.c_str(), "--quiet", "--out", out.c_str(), nullptr);
    _exit(127);
  }
  // Wait for two finished frames, then press Ctrl-C.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (lines(out / "stats.csv").size() < 3 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  kill(child, SIGINT);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
  const auto stats = lines(out / "stats.csv");
  ASSERT_GE(stats.size(), 3u);
  for (const auto& line : stats) EXPECT_EQ(count_fields(line), count_fields(stats[0]));
  const int last_frame = std::stoi(stats.back().substr(0, stats.back().find(',')));
  for (int frame = 0; frame <= last_frame; ++frame) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.obj", frame);
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  for (const auto& entry : fs::directory_iterator(out)) EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
}

TEST(RunCommand, DeterministicBitForBit) {
  const fs::path a = temp_dir("same_a"), b = temp_dir("same_b");
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/flag.json --frames 4 --quiet --out " + a.string()).status, 0);
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/flag.json --frames 4 --quiet --out " + b.string()).status, 0);
  EXPECT_EQ(without_timings(a / "stats.csv"), without_timings(b / "stats.csv"));
}

TEST(CheckStats, GoldenStatisticsOfEveryShippedScene) {
  // tests/golden/<scene>.csv holds the first frames of each shipped scene, written by
  // tools/update-golden.sh (and only by it); the frame count is read from the golden file.
  // Both run with the BLAS kernels pinned, so the bits do not depend on the processor.
  std::size_t checked = 0;
  for (const auto& entry : fs::directory_iterator(SOURCE + "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    const fs::path golden = SOURCE + "/tests/golden/" + entry.path().stem().string() + ".csv";
    ASSERT_TRUE(fs::exists(golden)) << "no golden statistics for " << entry.path() << ": run tools/update-golden.sh";
    const int frames = int(lines(golden).size()) - 2;
    const fs::path out = temp_dir("golden_" + entry.path().stem().string());
    const Outcome run = run_drape_reproducibly("run " + entry.path().string() + " --quiet --frames " + std::to_string(frames) + " --out " + out.string());
    ASSERT_EQ(run.status, 0) << run.output;
    const Outcome check = run_drape("check-stats " + out.string() + " " + golden.string());
    EXPECT_EQ(check.status, 0) << entry.path() << ": " << check.output << "(run with " << REPRODUCIBLE_BLAS
                               << "; another BLAS than OpenBLAS, chosen by update-alternatives, also changes the bits)";
    ++checked;
  }
  EXPECT_GE(checked, 3u);
}

TEST(CheckStats, ReportsADifferenceWithStatusOne) {
  const fs::path golden = SOURCE + "/tests/golden/hanging.csv";
  auto rows = lines(golden);
  ASSERT_GE(rows.size(), 3u);
  // Change one kinetic energy (column 6) well beyond its tolerance.
  std::stringstream in(rows[2]);
  std::vector<std::string> cells;
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  cells[5] = std::to_string(std::stod(cells[5]) * 1.1 + 1);
  std::string changed;
  for (std::size_t i = 0; i < cells.size(); ++i) changed += (i ? "," : "") + cells[i];
  rows[2] = changed + (rows[2].back() == ',' ? "," : "");
  const fs::path edited = temp_dir("edited.csv");
  std::ofstream file(edited);
  for (const auto& row : rows) file << row << "\n";
  file.close();
  const Outcome check = run_drape("check-stats " + edited.string() + " " + golden.string());
  EXPECT_EQ(check.status, 1);
  EXPECT_NE(check.output.find("frame 1, column kinetic_energy"), std::string::npos) << check.output;
}

namespace {

// Column values of a stats file, by column name, one vector per frame row.
std::vector<std::map<std::string, std::string>> table(const fs::path& stats) {
  const auto rows = lines(stats);
  std::vector<std::string> header;
  std::stringstream head(rows[0]);
  for (std::string cell; std::getline(head, cell, ',');) header.push_back(cell);
  std::vector<std::map<std::string, std::string>> out;
  for (std::size_t r = 1; r < rows.size(); ++r) {
    std::map<std::string, std::string> row;
    std::stringstream in(rows[r]);
    std::string cell;
    for (std::size_t c = 0; c < header.size(); ++c) {
      if (!std::getline(in, cell, ',')) cell.clear();
      row[header[c]] = cell;
    }
    out.push_back(row);
  }
  return out;
}

// A small cloth dropped onto another lying on the ground: cloth-cloth collisions within a few
// frames (both cloths are one self-collision set).
// Thrown down at 4 m/s: a step's fall (13 mm and more) passes the reach of the contacts the
// solve holds (5.5 mm), so the landing is the CCD's, with hits (dropped from rest, the solve's
// contacts stopped it with none).
const char* LANDING = R"({"comment": "a cloth lands on another", "frame_time": 0.0333333333333, "frame_steps": 10,
  "frames": 12,
  "cloths": [{"grid": {"size": [0.5, 0.5], "resolution": [10, 10]}, "transform": {"translate": [0, 0, 0.006]}},
             {"grid": {"size": [0.4, 0.4], "resolution": [8, 8]}, "transform": {"translate": [0.05, 0, 0.3], "rotate": [30, 0, 0, 1]},
              "velocity": [0, 0, -4]}],
  "obstacles": [{"plane": {}}], "friction": 0.5, "collisions": {"self": true, "thickness": 0.005}})";

// The columns that describe the simulation itself (not the cost of computing it).
const char* SIMULATION_COLUMNS[] = {"frame", "sim_time", "kinetic_energy", "potential_energy", "max_stretch",
                                    "min_distance_obstacle", "obstacle_contacts", "solver_iterations", "penetrations"};

}  // namespace

TEST(Collisions, NoPenetrationInAnyShippedSceneWithVincentOrConservative) {
  // Short runs (the benchmark runs them in full); the independent check runs on every frame.
  const std::map<std::string, int> frames = {{"cloth_fold", 14}, {"mesh_obstacle", 10}, {"fast_drop", 3},
                                             {"drape_sphere", 10}, {"hanging", 6}, {"flag", 6}, {"cantilever", 60}};
  // The benchmark scene takes about 2 s a frame and meets itself from frame 8 on, the
  // tablecloth about 1 s a frame once on the table, the Cusick disc about 5 s a frame: their
  // full runs under the check belong to bench/penetration_runs.sh (and scene_bench --check).
  const std::set<std::string> benchmark_only = {"pile", "tablecloth", "cusick_drape"};
  for (const auto& entry : fs::directory_iterator(SOURCE + "/scenes")) {  // a new scene must be listed here
    const std::string name = entry.path().stem().string();
    if (entry.path().extension() == ".json") {
      EXPECT_TRUE(frames.count(name) || benchmark_only.count(name)) << entry.path();
    }
  }
  for (const auto& [scene, count] : frames) {
    for (const char* method : {"vincent", "conservative"}) {
      const fs::path out = temp_dir(std::string("penetration_") + scene + "_" + method);
      const Outcome run = run_drape("run " + SOURCE + "/scenes/" + scene + ".json --quiet --check --ccd " + method +
                                    " --frames " + std::to_string(count) + " --out " + out.string());
      ASSERT_EQ(run.status, 0) << scene << " " << method << ": " << run.output;
      for (const auto& row : table(out / "stats.csv")) EXPECT_EQ(row.at("penetrations"), "0") << scene << " " << method << " frame " << row.at("frame");
      const Outcome check = run_drape("check " + out.string());
      EXPECT_EQ(check.status, 0) << scene << " " << method << ": " << check.output;
    }
  }
}

TEST(Collisions, TheFilterChangesCostNeverTheSimulation) {
  const fs::path a = temp_dir("filter_vincent"), b = temp_dir("filter_cubic");
  const std::string scene = write_scene("landing", LANDING).string() + " --quiet --out ";
  ASSERT_EQ(run_drape("run " + scene + a.string() + " --ccd vincent").status, 0);
  ASSERT_EQ(run_drape("run " + scene + b.string() + " --ccd cubic").status, 0);
  const auto ta = table(a / "stats.csv"), tb = table(b / "stats.csv");
  ASSERT_EQ(ta.size(), tb.size());
  long hits = 0;
  for (std::size_t r = 0; r < ta.size(); ++r) {
    for (const char* column : SIMULATION_COLUMNS) EXPECT_EQ(ta[r].at(column), tb[r].at(column)) << "frame " << r << " " << column;
    hits += std::stol(ta[r].at("ccd_hits"));
  }
  EXPECT_GT(hits, 0);  // the scene did collide
  EXPECT_EQ(lines(a / "frame_00012.obj"), lines(b / "frame_00012.obj"));
}

TEST(Collisions, ThreadCountDoesNotChangeResults) {
  const fs::path a = temp_dir("threads_1"), b = temp_dir("threads_2");
  const std::string scene = write_scene("landing_threads", LANDING).string() + " --quiet --out ";
  ASSERT_EQ(run_drape("run " + scene + a.string() + " -j 1").status, 0);
  ASSERT_EQ(run_drape("run " + scene + b.string() + " -j 2").status, 0);
  EXPECT_EQ(without_timings(a / "stats.csv"), without_timings(b / "stats.csv"));
  EXPECT_EQ(lines(a / "frame_00012.obj"), lines(b / "frame_00012.obj"));
}
