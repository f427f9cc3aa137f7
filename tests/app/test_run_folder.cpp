// A run's folder end to end: what a run writes is whole and complete by itself, an earlier run
// is never mixed with a new one, and a failed write (a full disk) stops the run with a message.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "drape_process.h"

using drape::testing::Outcome;
using drape::testing::lines;
using drape::testing::run_drape;
using drape::testing::run_shell;
namespace fs = std::filesystem;

namespace {

const std::string SOURCE = DRAPE_SOURCE_DIR;

fs::path temp_dir(const std::string& name) { return drape::testing::fresh_temp_path("run_folder", name); }

std::vector<std::string> frame_files(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().filename().string().rfind("frame_", 0) == 0) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST(RunFolder, AFolderHoldingAnotherRunIsRefusedUnlessOverwrite) {
  const fs::path out = temp_dir("overwrite");
  const std::string run = "run " + SOURCE + "/scenes/hanging.json --quiet --out " + out.string();
  ASSERT_EQ(run_drape(run + " --frames 4").status, 0);
  // A file of the user's own in the folder is never touched.
  std::ofstream(out / "notes.txt") << "mine";

  const Outcome refused = run_drape(run + " --frames 2");
  EXPECT_EQ(refused.status, 2) << refused.output;
  EXPECT_NE(refused.output.find(out.string() + ": the folder holds another run"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("--overwrite"), std::string::npos) << refused.output;
  EXPECT_EQ(frame_files(out).size(), 5u);  // untouched

  const Outcome replaced = run_drape(run + " --frames 2 --overwrite");
  ASSERT_EQ(replaced.status, 0) << replaced.output;
  EXPECT_EQ(frame_files(out), (std::vector<std::string>{"frame_00000.obj", "frame_00001.obj", "frame_00002.obj"}));
  EXPECT_EQ(lines(out / "stats.csv").size(), 4u);
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  const Outcome check = run_drape("check " + out.string());
  EXPECT_EQ(check.status, 0) << check.output;
}

// --overwrite removes what drape wrote and nothing else: folders named like a run's but
// holding other files stay, and a run folder can be run again in place from its own copy.
TEST(RunFolder, OverwriteRemovesOnlyWhatARunWrote) {
  const fs::path out = temp_dir("not_a_run");
  fs::create_directories(out / "meshes");
  fs::create_directories(out / "render");
  fs::copy_file(SOURCE + "/scenes/meshes/box.obj", out / "meshes/box.obj");
  std::ofstream(out / "render/notes.txt") << "mine";
  const Outcome run = run_drape("run " + SOURCE + "/scenes/hanging.json --frames 1 --quiet --overwrite --out " + out.string());
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_TRUE(fs::exists(out / "meshes/box.obj"));
  EXPECT_TRUE(fs::exists(out / "render/notes.txt"));

  const fs::path again = temp_dir("in_place");
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/mesh_obstacle.json --frames 1 --quiet --out " + again.string()).status, 0);
  const Outcome in_place =
      run_drape("run " + (again / "scene.json").string() + " --frames 2 --quiet --overwrite --out " + again.string());
  ASSERT_EQ(in_place.status, 0) << in_place.output;
  EXPECT_TRUE(fs::exists(again / "meshes/obstacle_0.obj"));
  const Outcome check = run_drape("check " + again.string());
  EXPECT_EQ(check.status, 0) << check.output;

  // A scene of the user's own named scene.json, run into its folder: refused, with or
  // without --overwrite, and left as it was (the run's copy would have replaced it).
  const fs::path mine = temp_dir("users_scene");
  fs::create_directories(mine);
  fs::copy_file(SOURCE + "/scenes/hanging.json", mine / "scene.json");
  const auto bytes = fs::file_size(mine / "scene.json");
  for (const std::string flag : {"", " --overwrite"}) {
    const Outcome refused = run_drape("run " + (mine / "scene.json").string() + " --frames 1 --quiet --out " + mine.string() + flag);
    EXPECT_EQ(refused.status, 2) << refused.output;
    EXPECT_NE(refused.output.find("the scene is the output folder's scene.json"), std::string::npos) << refused.output;
    EXPECT_EQ(fs::file_size(mine / "scene.json"), bytes);
    EXPECT_FALSE(fs::exists(mine / "stats.csv"));
  }
}

// check and render read the scene and its meshes from the folder: the original files may move.
TEST(RunFolder, ARunFolderIsCompleteByItself) {
  const fs::path source = temp_dir("source");
  fs::create_directories(source / "meshes");
  fs::copy_file(SOURCE + "/scenes/mesh_obstacle.json", source / "scene.json");
  fs::copy_file(SOURCE + "/scenes/meshes/box.obj", source / "meshes/box.obj");
  const fs::path out = temp_dir("self_contained");
  const Outcome run = run_drape("run " + (source / "scene.json").string() + " --frames 2 --quiet --out " + out.string());
  ASSERT_EQ(run.status, 0) << run.output;
  fs::remove_all(source);
  EXPECT_TRUE(fs::exists(out / "meshes/obstacle_0.obj"));
  const Outcome check = run_drape("check " + out.string());
  EXPECT_EQ(check.status, 0) << check.output;
  // The copy names the copied mesh, and the copied mesh is the original's bytes.
  bool names_copy = false;
  for (const std::string& line : lines(out / "scene.json")) names_copy |= line.find("\"meshes/obstacle_0.obj\"") != std::string::npos;
  EXPECT_TRUE(names_copy);
  EXPECT_EQ(fs::file_size(out / "meshes/obstacle_0.obj"), fs::file_size(SOURCE + "/scenes/meshes/box.obj"));
}

TEST(RunFolder, CheckAndRenderReportAMissingFrame) {
  const fs::path out = temp_dir("missing");
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/hanging.json --frames 3 --quiet --out " + out.string()).status, 0);
  fs::remove(out / "frame_00001.obj");
  // A frame number twice (another format beside it) hides no gap.
  fs::copy_file(out / "frame_00000.obj", out / "frame_00000.ply");
  for (const std::string& command : {"check " + out.string(), "render --no-video --quiet --resolution 32x32 " + out.string()}) {
    const Outcome outcome = run_drape(command);
    EXPECT_EQ(outcome.status, 2) << command << ": " << outcome.output;
    EXPECT_NE(outcome.output.find(out.string() + ": frame 1 missing (the folder has frames up to 3, stats.csv rows up to 3)"),
              std::string::npos)
        << command << ": " << outcome.output;
  }
}

// Frames lost from the end leave no gap among the others: stats.csv, written after each frame's
// mesh, still lists them.
TEST(RunFolder, CheckAndRenderReportFramesLostFromTheEnd) {
  const fs::path out = temp_dir("missing_last");
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/hanging.json --frames 4 --quiet --out " + out.string()).status, 0);
  fs::remove(out / "frame_00003.obj");
  fs::remove(out / "frame_00004.obj");
  for (const std::string& command : {"check " + out.string(), "render --no-video --quiet --resolution 32x32 " + out.string()}) {
    const Outcome outcome = run_drape(command);
    EXPECT_EQ(outcome.status, 2) << command << ": " << outcome.output;
    EXPECT_NE(outcome.output.find(out.string() + ": frames 3, 4 missing (the folder has frames up to 2, stats.csv rows up to 4)"),
              std::string::npos)
        << command << ": " << outcome.output;
  }
}

// A disk that fills during the run, made with a file-size limit (ulimit -f; SIGXFSZ ignored so
// the write fails with an error instead of killing the process): the run stops with status 3
// naming the file, stats.csv ends with a whole row, and every frame it lists is whole.
TEST(RunFolder, AFullDiskStopsTheRunAndKeepsWhatIsWhole) {
  // A small cloth: its frames are small beside 200 rows of statistics.
  const fs::path scene = temp_dir("small.json");
  std::ofstream(scene) << R"({"frames": 200, "frame_steps": 1, "cloths": [{"grid": {"resolution": [3, 3]}}],
                              "handles": [{"corners": ["top-left", "top-right"]}]})";
  const fs::path probe = temp_dir("disk_probe");
  ASSERT_EQ(run_drape("run " + scene.string() + " --frames 1 --quiet --out " + probe.string()).status, 0);
  const auto frame_bytes = fs::file_size(probe / "frame_00000.obj");
  const auto row_bytes = fs::file_size(probe / "stats.csv") / 2;
  // Room for every frame file but not for 200 rows of statistics: limits are per file.
  const auto limit_blocks = (std::max(frame_bytes, fs::file_size(probe / "scene.json")) + 8 * row_bytes) / 512 + 1;
  ASSERT_LT(limit_blocks * 1024, 150 * row_bytes) << "the rows must outgrow the limit in either block size";

  const fs::path out = temp_dir("full_disk");
  const Outcome run = run_shell("trap '' XFSZ; ulimit -f " + std::to_string(limit_blocks) + "; exec " + DRAPE_EXECUTABLE +
                                " run " + scene.string() + " --quiet --out " + out.string());
  EXPECT_EQ(run.status, 3) << run.output;
  EXPECT_NE(run.output.find("drape run: stopped: cannot write frame"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find((out / "stats.csv").string() + ": cannot write the file: File too large"), std::string::npos)
      << run.output;
  const std::vector<std::string> rows = lines(out / "stats.csv");
  ASSERT_GE(rows.size(), 2u);
  const auto fields = [](const std::string& row) { return std::count(row.begin(), row.end(), ',') + 1; };
  for (const std::string& row : rows) EXPECT_EQ(fields(row), fields(rows[0])) << row;
  // The file ends with a newline: the last row is whole.
  std::ifstream stats(out / "stats.csv", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(stats)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.back(), '\n');
  EXPECT_LT(rows.size(), 150u);
  // No partial file is left, and check accepts every frame written.
  for (const auto& entry : fs::directory_iterator(out)) EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
  const Outcome check = run_drape("check " + out.string());
  EXPECT_EQ(check.status, 0) << check.output;
}
