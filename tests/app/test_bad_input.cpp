// Bad input to the drape program, end to end: every malformed input kind gets a message naming
// the file and the place in it, and exit status 2; never a crash, a hang or a silent default.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "drape_process.h"

using drape::testing::Outcome;
using drape::testing::lines;
using drape::testing::run_drape;
namespace fs = std::filesystem;

namespace {

const std::string SOURCE = DRAPE_SOURCE_DIR;

fs::path temp_dir(const std::string& name) { return drape::testing::fresh_temp_path("bad_input", name); }

// A fresh run of the hanging cloth, frames 0 and 1, in its own folder.
fs::path hanging_run(const std::string& name) {
  const fs::path out = temp_dir(name);
  const Outcome run = run_drape("run " + SOURCE + "/scenes/hanging.json --frames 1 --out " + out.string() + " --quiet");
  EXPECT_EQ(run.status, 0) << run.output;
  return out;
}

void write_lines(const fs::path& path, const std::vector<std::string>& rows) {
  std::ofstream out(path);
  for (const auto& row : rows) out << row << "\n";
}

// drape check and drape render on the folder: both exit 2 (not killed: -1) with every expected
// piece of text in their message.
void expect_check_and_render_reject(const fs::path& folder, const std::vector<std::string>& expected) {
  for (const std::string& command : {"check " + folder.string(), "render " + folder.string() + " --resolution 64x48 --no-video --quiet"}) {
    const Outcome run = run_drape(command);
    EXPECT_EQ(run.status, 2) << command << ": " << run.output;
    for (const std::string& text : expected)
      EXPECT_NE(run.output.find(text), std::string::npos) << command << ": expected '" << text << "' in: " << run.output;
  }
}

}  // namespace

TEST(BadInput, CheckLooksForAtLeastOnePair) {
  // With --max-pairs 0 every frame would pass unchecked; -1 would wrap to a huge count.
  const fs::path out = hanging_run("max_pairs");
  for (const char* value : {"0", "-1", "99999999999"}) {
    const Outcome check = run_drape("check " + out.string() + " --max-pairs " + value);
    EXPECT_EQ(check.status, 2) << value << ": " << check.output;
    EXPECT_NE(check.output.find("--max-pairs"), std::string::npos) << value << ": " << check.output;
  }
  const Outcome one = run_drape("check " + out.string() + " --max-pairs 1");
  EXPECT_EQ(one.status, 0) << one.output;
}

TEST(BadInput, AFrameWithANonFiniteCoordinate) {
  const fs::path out = hanging_run("nan_frame");
  const fs::path frame = out / "frame_00001.obj";
  auto rows = lines(frame);
  const auto vertex = std::find_if(rows.begin(), rows.end(), [](const std::string& row) { return row.rfind("v ", 0) == 0; });
  ASSERT_NE(vertex, rows.end());
  *vertex = "v nan 0 0";
  write_lines(frame, rows);
  expect_check_and_render_reject(out, {frame.string() + ": vertex ", "has a non-finite coordinate"});
}

TEST(BadInput, AFrameWithAnExtraTriangle) {
  const fs::path out = hanging_run("extra_triangle");
  const fs::path frame = out / "frame_00001.obj";
  std::ofstream(frame, std::ios::app) << "\nf 1 2 3\n";
  // The hanging cloth: 24 x 24 quads, two triangles each.
  expect_check_and_render_reject(out, {frame.string() + ": expected 1152 triangles, found 1153"});
}

TEST(BadInput, AFrameNumberBeyondAnInt) {
  // Once an uncaught exception from std::stoi: the program aborted (status -1 here).
  const fs::path out = hanging_run("huge_frame_number");
  const fs::path huge = out / "frame_99999999999.obj";
  fs::copy_file(out / "frame_00001.obj", huge);
  expect_check_and_render_reject(out, {huge.string() + ": expected a frame number from 0 to 2147483647"});
}

TEST(BadInput, FoldersThatAreNotRuns) {
  const fs::path empty = temp_dir("empty_folder");
  fs::create_directories(empty);
  expect_check_and_render_reject(empty, {(empty / "scene.json").string() + ": not found"});

  const fs::path broken = temp_dir("broken_scene");
  fs::create_directories(broken);
  std::ofstream(broken / "scene.json") << "{";
  expect_check_and_render_reject(broken, {(broken / "scene.json").string() + ": line 1, column ", "invalid JSON"});

  const fs::path no_frames = temp_dir("no_frames");
  fs::create_directories(no_frames);
  fs::copy_file(SOURCE + "/scenes/hanging.json", no_frames / "scene.json");
  expect_check_and_render_reject(no_frames, {no_frames.string() + ": no frame_*.* meshes"});
}

TEST(BadInput, AnUnlistableRunFolderIsReported) {
  if (::geteuid() == 0) GTEST_SKIP() << "root lists every folder";
  const fs::path out = hanging_run("unlistable");
  // Search permission only: scene.json opens, the frames cannot be listed.
  fs::permissions(out, fs::perms::owner_exec);
  const Outcome check = run_drape("check " + out.string());
  fs::permissions(out, fs::perms::owner_all);
  EXPECT_EQ(check.status, 2) << check.output;
  EXPECT_NE(check.output.find(out.string() + ": cannot list the run's frames"), std::string::npos) << check.output;
}

TEST(BadInput, ValidateChecksTheRenderSection) {
  const fs::path scene = temp_dir("render_samples.json");
  std::ofstream(scene) << R"({"cloths": [{"grid": {}}], "render": {"samples": 9}})";
  const Outcome validate = run_drape("validate " + scene.string());
  EXPECT_EQ(validate.status, 2);
  EXPECT_NE(validate.output.find(scene.string() + ": /render/samples: expected an integer from 1 to 4"), std::string::npos)
      << validate.output;
  const Outcome good = run_drape("validate " + SOURCE + "/scenes/drape_sphere.json");
  EXPECT_EQ(good.status, 0) << good.output;
}

TEST(BadInput, RunChecksTheResolutionFlagBeforeSimulating) {
  const fs::path out = temp_dir("resolution_flag");
  const Outcome run = run_drape("run " + SOURCE + "/scenes/hanging.json --frames 1 --quiet --render --resolution 5x5 --out " +
                                out.string());
  EXPECT_EQ(run.status, 2) << run.output;
  EXPECT_NE(run.output.find("--resolution: expected WIDTHxHEIGHT from 16x16 to 8192x8192, found '5x5'"), std::string::npos)
      << run.output;
  EXPECT_FALSE(fs::exists(out / "frame_00000.obj"));
}

TEST(BadInput, CheckStatsNamesTheFile) {
  const std::string golden = SOURCE + "/tests/golden/hanging.csv";
  const fs::path empty = temp_dir("empty_golden.csv");
  std::ofstream(empty).close();
  const Outcome empty_golden = run_drape("check-stats " + golden + " " + empty.string());
  EXPECT_EQ(empty_golden.status, 2);
  EXPECT_NE(empty_golden.output.find(empty.string() + ": the statistics file is empty"), std::string::npos) << empty_golden.output;

  const fs::path no_stats = temp_dir("no_stats");
  fs::create_directories(no_stats);
  const Outcome missing = run_drape("check-stats " + no_stats.string() + " " + golden);
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.output.find((no_stats / "stats.csv").string() + ": no such statistics file"), std::string::npos)
      << missing.output;

  // A row cut short: an error naming the line, not a difference against "(empty)".
  auto rows = lines(golden);
  ASSERT_GE(rows.size(), 3u);
  rows[2] = rows[2].substr(0, rows[2].find(',', rows[2].find(',') + 1));  // its first two cells
  const fs::path ragged = temp_dir("ragged.csv");
  write_lines(ragged, rows);
  for (const std::string& order : {ragged.string() + " " + golden, golden + " " + ragged.string()}) {
    const Outcome check = run_drape("check-stats " + order);
    EXPECT_EQ(check.status, 2) << order << ": " << check.output;
    EXPECT_NE(check.output.find(ragged.string() + ": line 3: expected "), std::string::npos) << order << ": " << check.output;
    EXPECT_NE(check.output.find("found 2"), std::string::npos) << order << ": " << check.output;
  }
}

// Files that are not files: a device read whole would exhaust the memory, a symlink loop threw
// an uncaught filesystem_error (validate, run and check died on a signal).
TEST(BadInput, DevicesAndSymlinkLoopsAreRefusedWithAMessage) {
  const Outcome device = run_drape("validate /dev/zero");
  EXPECT_EQ(device.status, 2) << device.output;
  EXPECT_NE(device.output.find("/dev/zero: expected a scene file, found a device, pipe or socket"), std::string::npos)
      << device.output;
  const Outcome queries = run_drape("ccd /dev/zero --kind vertex-face");
  EXPECT_EQ(queries.status, 2) << queries.output;
  EXPECT_NE(queries.output.find("/dev/zero: expected a query file, found a device"), std::string::npos) << queries.output;

  const fs::path dir = temp_dir("symlink_loop");
  fs::create_directories(dir);
  fs::create_symlink("loop_b.obj", dir / "loop_a.obj");
  fs::create_symlink("loop_a.obj", dir / "loop_b.obj");
  std::ofstream(dir / "scene.json") << R"({"frames": 1, "cloths": [{"mesh": "loop_a.obj"}]})";
  for (const std::string& command : {std::string("validate"), std::string("run")}) {
    const Outcome run = run_drape(command + " " + (dir / "scene.json").string() + (command == "run" ? " --quiet" : ""));
    EXPECT_EQ(run.status, 2) << command << ": " << run.output;
    EXPECT_NE(run.output.find("/cloths/0/mesh: " + (dir / "loop_a.obj").string() + ": cannot read the mesh file: Too many levels of symbolic links"),
              std::string::npos)
        << command << ": " << run.output;
  }
  // A scene file that is itself a loop.
  fs::create_symlink("loop_d.json", dir / "loop_c.json");
  fs::create_symlink("loop_c.json", dir / "loop_d.json");
  const Outcome scene = run_drape("validate " + (dir / "loop_c.json").string());
  EXPECT_EQ(scene.status, 2) << scene.output;
  EXPECT_EQ(scene.output.find("terminate"), std::string::npos) << scene.output;
  EXPECT_NE(scene.output.find((dir / "loop_c.json").string() + ": Too many levels of symbolic links"), std::string::npos)
      << scene.output;
  const Outcome folder = run_drape("run " + dir.string());
  EXPECT_EQ(folder.status, 2) << folder.output;
  EXPECT_NE(folder.output.find(dir.string() + " is a folder; expected a file"), std::string::npos) << folder.output;
}
