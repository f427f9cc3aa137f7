// drape batch end to end, and drape batch and sweep under mpirun: the table, the outcomes of
// bad and stopping runs, resuming, and the gathered table of two ranks against one process's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "drape_process.h"

using namespace drape::testing;
namespace fs = std::filesystem;

namespace {

const std::string HANGING = DRAPE_SOURCE_DIR "/scenes/hanging.json";

// Four runs: two ok (one with overrides and its own folder), a bad scene, one that stops at
// its first frame (a stretch limit of 1).
fs::path write_manifest(const fs::path& dir) {
  fs::create_directories(dir);
  std::ofstream(dir / "broken.json") << R"({"cloths": [{"grid": {"size": [1, -1]}}]})";
  const fs::path manifest = dir / "runs.json";
  std::ofstream(manifest) << R"({"runs": [
    {"scene": ")" + HANGING + R"(", "frames": 3},
    {"scene": ")" + HANGING + R"(", "frames": 2, "out": "coarse", "overrides": {"frame_steps": 5}},
    {"scene": "broken.json", "frames": 2},
    {"scene": ")" + HANGING + R"(", "frames": 4, "overrides": {"limits": {"stretch_warn": 1, "stretch_stop": 1}}}
  ]})";
  return manifest;
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  bool quoted = false;
  for (const char c : line) {
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) fields.push_back(field), field.clear();
    else field += c;
  }
  fields.push_back(field);
  return fields;
}

// A CSV table without the columns that hold times (named *_ms, *_s, wall_ms_per_frame) and
// without pareto (decided by time).
std::vector<std::string> timeless(const fs::path& table) {
  const std::vector<std::string> rows = lines(table);
  if (rows.empty()) return {};
  const std::vector<std::string> header = split(rows[0]);
  std::vector<bool> keep;
  for (const std::string& name : header) {
    const bool time = name.size() > 3 && (name.substr(name.size() - 3) == "_ms" || name.substr(name.size() - 2) == "_s");
    keep.push_back(!time && name != "wall_ms_per_frame" && name != "pareto");
  }
  std::vector<std::string> out;
  for (const std::string& row : rows) {
    const std::vector<std::string> fields = split(row);
    std::string kept;
    for (std::size_t k = 0; k < fields.size(); ++k)
      if (k >= keep.size() || keep[k]) kept += fields[k] + ",";
    out.push_back(kept);
  }
  return out;
}

std::string column(const std::vector<std::string>& header, const std::vector<std::string>& row, const std::string& name) {
  const auto at = std::find(header.begin(), header.end(), name);
  return at == header.end() || std::size_t(at - header.begin()) >= row.size() ? "<none>" : row[at - header.begin()];
}

// mpirun with two ranks on this machine (as root too), or "" when Open MPI is missing. Under
// the sanitizers, leak checking is off for the ranks: Open MPI keeps allocations past
// MPI_Finalize in components it has unloaded, which LeakSanitizer can neither name nor
// suppress (the other checks stay on, and the batch tests without MPI check leaks).
std::string mpirun_two() {
  if (run_shell("command -v mpirun").status != 0) return "";
  const char* asan = std::getenv("ASAN_OPTIONS");
  // The last value of an option wins.
  return "env ASAN_OPTIONS='" + std::string(asan ? std::string(asan) + ":" : "") +
         "detect_leaks=0' mpirun --allow-run-as-root --oversubscribe -np 2 ";
}

}  // namespace

TEST(BatchCommand, RecordsEveryRunsOutcomeAndGoesOnAfterFailures) {
  const fs::path dir = fresh_temp_path("batch", "outcomes"), out = dir / "out";
  const Outcome run = run_drape("batch " + write_manifest(dir).string() + " --out " + out.string());
  EXPECT_EQ(run.status, 1) << run.output;  // some runs failed
  const std::vector<std::string> rows = lines(out / "batch.csv");
  ASSERT_EQ(rows.size(), 5u) << run.output;
  const std::vector<std::string> header = split(rows[0]);
  const std::string expected[][3] = {{"ok", "0", "3"}, {"ok", "0", "2"}, {"bad_input", "2", "0"}, {"stopped", "3", "1"}};
  for (std::size_t i = 0; i < 4; ++i) {
    const std::vector<std::string> row = split(rows[i + 1]);
    EXPECT_EQ(column(header, row, "index"), std::to_string(i));
    EXPECT_EQ(column(header, row, "status"), expected[i][0]) << rows[i + 1];
    EXPECT_EQ(column(header, row, "exit_status"), expected[i][1]) << rows[i + 1];
    EXPECT_EQ(column(header, row, "frames"), expected[i][2]) << rows[i + 1];
  }
  // The last stats row: frame 3 of run 0, frame 2 of run 1, none for the bad scene.
  EXPECT_EQ(column(header, split(rows[1]), "frame"), "3");
  EXPECT_EQ(column(header, split(rows[2]), "frame"), "2");
  EXPECT_EQ(column(header, split(rows[3]), "frame"), "");
  EXPECT_NE(rows[3].find("broken.json: /cloths/0/grid/size"), std::string::npos) << rows[3];
  EXPECT_NE(rows[4].find("stretch"), std::string::npos) << rows[4];
  EXPECT_EQ(column(header, split(rows[2]), "out"), "coarse");
  EXPECT_TRUE(fs::exists(out / "000_hanging" / "frame_00003.obj"));
  EXPECT_TRUE(fs::exists(out / "coarse" / "stats.csv"));
  EXPECT_TRUE(fs::exists(out / "003_hanging" / "frame_00001.obj"));  // kept up to where it stopped
  for (const auto& entry : fs::recursive_directory_iterator(out))
    EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos) << entry.path();
  // The overridden scene is the one the run folder keeps: drape render and check see it.
  EXPECT_NE(lines(out / "coarse" / "scene.json").size(), 0u);
  std::ifstream copy(out / "coarse" / "scene.json");
  const std::string text((std::istreambuf_iterator<char>(copy)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"frame_steps\": 5"), std::string::npos) << text;
}

TEST(BatchCommand, StartedAgainItRunsOnlyWhatIsNotDone) {
  const fs::path dir = fresh_temp_path("batch", "resume"), out = dir / "out";
  const fs::path manifest = write_manifest(dir);
  ASSERT_EQ(run_drape("batch " + manifest.string() + " --out " + out.string()).status, 1);
  const std::vector<std::string> first = timeless(out / "batch.csv");
  // Everything done: nothing runs, the table is the same.
  const Outcome again = run_drape("batch " + manifest.string() + " --out " + out.string());
  EXPECT_EQ(again.status, 1);
  EXPECT_NE(again.output.find("4 runs, 4 complete already, 0 to run"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("run 0 (" + (out / "000_hanging").string() + "): complete already, skipped"), std::string::npos)
      << again.output;
  EXPECT_EQ(timeless(out / "batch.csv"), first);
  // A job killed during run 0: its record gone, its folder half-written (a partial folder with
  // a stale frame of another run). Only run 0 runs again, from scratch.
  fs::remove(out / "records" / "run_00000.json");
  fs::rename(out / "000_hanging", out / "000_hanging.partial");
  std::ofstream(out / "000_hanging.partial" / "frame_00009.obj") << "stale";
  const Outcome resumed = run_drape("batch " + manifest.string() + " --out " + out.string());
  EXPECT_EQ(resumed.status, 1);
  EXPECT_NE(resumed.output.find("4 runs, 3 complete already, 1 to run"), std::string::npos) << resumed.output;
  EXPECT_FALSE(fs::exists(out / "000_hanging.partial"));
  EXPECT_FALSE(fs::exists(out / "000_hanging" / "frame_00009.obj"));
  EXPECT_TRUE(fs::exists(out / "000_hanging" / "frame_00003.obj"));
  EXPECT_EQ(timeless(out / "batch.csv"), first);
  // An edited manifest entry (more frames) is a different run: done again.
  std::ifstream in(manifest);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("\"frames\": 3"), 11, "\"frames\": 4");
  std::ofstream(manifest) << text;
  const Outcome edited = run_drape("batch " + manifest.string() + " --out " + out.string());
  EXPECT_NE(edited.output.find("4 runs, 3 complete already, 1 to run"), std::string::npos) << edited.output;
  EXPECT_TRUE(fs::exists(out / "000_hanging" / "frame_00004.obj"));
}

// The whole job killed (SIGKILL, nothing cleaned up) once the first of six runs is recorded
// (the longest, handed out first):
// started again, it runs only the runs without a record.
TEST(BatchCommand, AJobKilledMidwayCompletesOnlyTheRemainingRuns) {
  const fs::path dir = fresh_temp_path("batch", "killed"), out = dir / "out";
  fs::create_directories(dir);
  const fs::path manifest = dir / "six.csv";
  {
    std::ofstream m(manifest);
    m << "scene,frames\n";
    for (int i = 0; i < 6; ++i) m << HANGING << "," << 6 + i << "\n";
  }
  const std::string command = std::string(DRAPE_EXECUTABLE) + " batch " + manifest.string() + " --out " + out.string();
  const Outcome killed = run_shell("(" + command + " > " + (dir / "log").string() + " 2>&1 & pid=$!; "
                                   "until ls " + (out / "records").string() + "/*.json >/dev/null 2>&1; do sleep 0.02; done; "
                                   "kill -9 $pid; wait $pid; echo killed)");
  ASSERT_NE(killed.output.find("killed"), std::string::npos) << killed.output;
  std::size_t recorded = 0;
  for (const auto& entry : fs::directory_iterator(out / "records")) recorded += entry.path().extension() == ".json";
  ASSERT_GE(recorded, 1u);
  ASSERT_LT(recorded, 6u) << "the job finished before it was killed";
  const Outcome resumed = run_shell(command);
  EXPECT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("6 runs, " + std::to_string(recorded) + " complete already, " + std::to_string(6 - recorded) +
                                " to run"),
            std::string::npos)
      << resumed.output;
  const std::vector<std::string> rows = lines(out / "batch.csv");
  ASSERT_EQ(rows.size(), 7u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(split(rows[i + 1])[3], "ok") << rows[i + 1];
  for (const auto& entry : fs::recursive_directory_iterator(out))
    EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos) << entry.path();
}

// A batch replaces only folders it made: a folder of a drape run, or one holding other files,
// is left alone and the run is bad input, done again once the folder is moved (not a final
// outcome). A base scene invalid by itself is refused with its own file's message even with
// overrides. A changed mesh is a different run.
TEST(BatchCommand, ItReplacesOnlyFoldersItMadeAndRerunsWhenInputsChange) {
  const fs::path dir = fresh_temp_path("batch", "folders"), out = dir / "out";
  fs::create_directories(dir);
  ASSERT_EQ(run_drape("run " + HANGING + " --frames 3 --quiet --out " + (dir / "mine").string()).status, 0);
  fs::copy_file(DRAPE_SOURCE_DIR "/scenes/mesh_obstacle.json", dir / "box_scene.json");
  fs::create_directories(dir / "meshes");
  fs::copy_file(DRAPE_SOURCE_DIR "/scenes/meshes/box.obj", dir / "meshes" / "box.obj");
  std::ofstream(dir / "twice.json") << R"({"frames": 2, "frames": 3, "cloths": [{"grid": {}}]})";
  std::ofstream(dir / "runs.json") << R"([{"scene": ")" + HANGING + R"(", "frames": 1, "out": ")" + (dir / "mine").string() + R"("},
      {"scene": "twice.json", "overrides": {"frame_steps": 2}},
      {"scene": "box_scene.json", "frames": 1}])";
  const std::string command = "batch " + (dir / "runs.json").string() + " --out " + out.string();
  const Outcome first = run_drape(command);
  EXPECT_EQ(first.status, 1) << first.output;
  const std::vector<std::string> rows = lines(out / "batch.csv");
  ASSERT_EQ(rows.size(), 4u) << first.output;
  EXPECT_NE(rows[1].find("the folder exists and this batch did not make it"), std::string::npos) << rows[1];
  EXPECT_TRUE(fs::exists(dir / "mine" / "frame_00003.obj"));  // the user's run untouched
  EXPECT_NE(rows[2].find("twice.json: line 1, column 15"), std::string::npos) << rows[2];
  EXPECT_NE(rows[2].find("appears twice"), std::string::npos) << rows[2];
  EXPECT_EQ(split(rows[3])[3], "ok") << rows[3];
  // The folder moved away: run 0 runs; the bad scene stays recorded; the box run is done.
  fs::rename(dir / "mine", dir / "moved");
  const Outcome second = run_drape(command);
  EXPECT_NE(second.output.find("3 runs, 2 complete already, 1 to run"), std::string::npos) << second.output;
  EXPECT_EQ(split(lines(out / "batch.csv")[1])[3], "ok");
  // The box mesh edited: its run is done again.
  std::ofstream(dir / "meshes" / "box.obj", std::ios::app) << "# edited\n";
  const Outcome third = run_drape(command);
  EXPECT_NE(third.output.find("3 runs, 2 complete already, 1 to run"), std::string::npos) << third.output;
  EXPECT_NE(third.output.find("run 2 (box_scene.json): ok"), std::string::npos) << third.output;
}

// Two batches on one folder: the second is refused while the first holds the lock.
TEST(BatchCommand, ASecondBatchOnTheSameFolderIsRefused) {
  const fs::path dir = fresh_temp_path("batch", "locked"), out = dir / "out";
  const fs::path manifest = write_manifest(dir);
  fs::create_directories(out);
  const Outcome locked = run_shell("flock " + (out / "batch.lock").string() + " " + DRAPE_EXECUTABLE + " batch " +
                                   manifest.string() + " --out " + out.string());
  EXPECT_EQ(locked.status, 2) << locked.output;
  EXPECT_NE(locked.output.find("another drape batch or sweep is running on this folder"), std::string::npos) << locked.output;
}

// Records that cannot be written (records/ is a file): no crash, no hang, the runs reported
// as not done, on one process and on two ranks.
TEST(BatchCommand, AnUnwritableRecordFolderEndsTheBatchCleanly) {
  const fs::path dir = fresh_temp_path("batch", "unwritable");
  const fs::path manifest = write_manifest(dir);
  for (const std::string& launcher : {std::string(), mpirun_two()}) {
    const fs::path out = dir / (launcher.empty() ? "serial" : "mpi");
    fs::create_directories(out);
    std::ofstream(out / "records") << "in the way";
    const Outcome run = run_shell("timeout 120 " + launcher + DRAPE_EXECUTABLE + " batch " + manifest.string() + " --out " + out.string());
    EXPECT_EQ(run.status, 3) << launcher << run.output;
    EXPECT_NE(run.output.find("runs not done"), std::string::npos) << run.output;
  }
}

TEST(BatchCommand, ACsvManifestIsTheSameAsItsJson) {
  const fs::path dir = fresh_temp_path("batch", "csv");
  const fs::path json_out = dir / "json_out", csv_out = dir / "csv_out";
  const fs::path manifest = write_manifest(dir);
  std::ofstream(dir / "runs.csv") << "scene,frames,out,overrides\n"
                                  << HANGING << ",3,,\n"
                                  << HANGING << ",2,coarse,\"{\"\"frame_steps\"\": 5}\"\n"
                                  << "# a comment line\n"
                                  << "broken.json,2,,\n"
                                  << HANGING << ",4,,\"{\"\"limits\"\": {\"\"stretch_warn\"\": 1, \"\"stretch_stop\"\": 1}}\"\n";
  run_drape("batch " + manifest.string() + " --quiet --out " + json_out.string());
  const Outcome csv = run_drape("batch " + (dir / "runs.csv").string() + " --quiet --out " + csv_out.string());
  EXPECT_EQ(csv.status, 1) << csv.output;
  // The same runs: only the folders of the default-named runs differ (000_hanging in both).
  EXPECT_EQ(timeless(csv_out / "batch.csv"), timeless(json_out / "batch.csv"));
}

TEST(BatchCommand, BadManifestsNameTheFileThePlaceAndWhatWasExpected) {
  const fs::path dir = fresh_temp_path("batch", "bad");
  fs::create_directories(dir);
  const struct {
    std::string name, text, expected;
  } cases[] = {
      {"a.json", R"({"runs": []})", "a.json: /runs: expected a non-empty array of runs"},
      {"b.json", R"({"run": []})", "b.json: /run: unknown key (expected runs)"},
      {"c.json", R"([{"frames": 3}])", "c.json: /0/scene: expected the scene file's path"},
      {"d.json", R"([{"scene": "x.json", "frames": 0}])", "d.json: /0/frames: expected an integer from 1 to 1000000, found 0"},
      {"e.json", R"([{"scene": "x.json", "frame": 3}])", "e.json: /0/frame: unknown key (expected one of: scene, frames, out, overrides)"},
      {"f.json", R"([{"scene": "x.json", "out": "same"}, {"scene": "y.json", "out": "same"}])", "f.json: /1: writes to"},
      {"g.json", R"([{"scene": "x.json", "overrides": [1]}])", "g.json: /0/overrides: expected an object of scene keys"},
      {"h.json", R"({"runs": [)", "h.json: invalid JSON"},
      {"i.csv", "scene,steps\nx.json,3\n", "i.csv: line 1: unknown column 'steps' (expected a header of: scene, frames, out, overrides)"},
      {"j.csv", "scene,frames\nx.json\n", "j.csv: line 2: expected 2 fields (1 found)"},
      {"k.csv", "scene,frames\nx.json,\"3\n", "k.csv: line 2: a quoted field is not closed"},
      {"l.csv", "scene,frames\nx.json,three\n", "l.csv: line 2: column frames: expected an integer from 1 to 1000000"},
      {"m.csv", "frames\n3\n", "m.csv: line 1: the header has no 'scene' column"},
      {"n.csv", "scene,overrides\nx.json,{\"\"a\n", "n.csv: line 2: column overrides: expected a JSON object"},
      {"o.json", R"([{"scene": "x.json", "out": "a"}, {"scene": "y.json", "out": "a/b"}])", "o.json: /1: out"},
      {"p.json", R"([{"scene": "x.json", "out": "a.partial"}])", "p.json: /0: out"},
      {"q.json", R"([{"scene": "x.json", "out": "records"}])", "is or holds the batch's own folder"},
      {"r.json", R"([{"scene": "x.json", "out": ".."}])", "is or holds the batch's own folder"},
      {"s.json", R"([{"scene": "x.json", "out": "."}])", "is or holds the batch's own folder"},
  };
  for (const auto& c : cases) {
    std::ofstream(dir / c.name) << c.text;
    const Outcome run = run_drape("batch " + (dir / c.name).string() + " --out " + (dir / "out").string() + "/");
    EXPECT_EQ(run.status, 2) << c.name << "\n" << run.output;
    EXPECT_NE(run.output.find(c.expected), std::string::npos) << c.name << "\n" << run.output;
  }
  EXPECT_EQ(run_drape("batch " + (dir / "missing.json").string()).status, 2);
}

// Two MPI ranks gather the same table as one process, all but the time columns: a batch with
// a bad scene and a run that stops, and a sweep.
TEST(BatchCommand, TwoMpiRanksGatherWhatOneProcessWrites) {
  const std::string mpirun = mpirun_two();
  ASSERT_FALSE(mpirun.empty()) << "mpirun is not installed (Debian package openmpi-bin; tools/install-deps.sh installs it)";
  const fs::path dir = fresh_temp_path("batch", "mpi");
  const fs::path manifest = write_manifest(dir);
  const Outcome serial = run_drape("batch " + manifest.string() + " --quiet --out " + (dir / "serial").string());
  const Outcome ranks = run_shell(mpirun + DRAPE_EXECUTABLE + " batch " + manifest.string() + " --out " + (dir / "mpi").string());
  EXPECT_EQ(serial.status, 1) << serial.output;
  EXPECT_EQ(ranks.status, 1) << ranks.output;
  EXPECT_NE(ranks.output.find("to run on 2 MPI ranks"), std::string::npos) << ranks.output;
  EXPECT_NE(ranks.output.find("rank 1/2: run"), std::string::npos) << ranks.output;  // rank 1 ran some
  EXPECT_EQ(timeless(dir / "mpi" / "batch.csv"), timeless(dir / "serial" / "batch.csv"));
  EXPECT_EQ(lines(dir / "mpi" / "batch.csv").size(), 5u);

  const std::string sweep = std::string(" sweep ") + HANGING + " --frames 2 --steps 1,2 --solvers cholmod,cg:1e-4 --methods vincent --no-plot --out ";
  const Outcome sweep_serial = run_drape(sweep + (dir / "sweep_serial").string());
  const Outcome sweep_ranks = run_shell(mpirun + DRAPE_EXECUTABLE + sweep + (dir / "sweep_mpi").string());
  EXPECT_EQ(sweep_serial.status, 0) << sweep_serial.output;
  EXPECT_EQ(sweep_ranks.status, 0) << sweep_ranks.output;
  EXPECT_EQ(lines(dir / "sweep_mpi" / "sweep.csv").size(), 6u);
  EXPECT_EQ(timeless(dir / "sweep_mpi" / "sweep.csv"), timeless(dir / "sweep_serial" / "sweep.csv"));
}
