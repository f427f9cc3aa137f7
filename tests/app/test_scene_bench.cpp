// The cloth benchmark end to end: scene_bench on a short run, and its dumped tests read back
// by drape ccd with the same verdicts.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "drape_process.h"

using namespace drape::testing;
namespace fs = std::filesystem;

namespace {

// scene_bench with these arguments: its exit status and what it printed (both streams).
std::pair<int, std::string> scene_bench(const std::string& arguments) {
  const std::string command = std::string(DRAPE_SCENE_BENCH) + " " + arguments + " 2>&1";
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  return {pclose(pipe), output};
}

}  // namespace

TEST(SceneBench, DumpedTestsReadBackByDrapeCcd) {
  const fs::path dump = fresh_temp_path("scene_bench", "dump");
  const auto [status, output] = scene_bench(DRAPE_SOURCE_DIR "/scenes/fast_drop.json --frames 1 --passes 1 --dump-limit 2000 "
                                            "--dump-ccd " + dump.string());
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("0 tests where cubic, dnf or the paper's filter alone disagree with vincent"), std::string::npos) << output;
  ASSERT_TRUE(fs::exists(dump / "vertex-face" / "fast_drop_frame1.csv")) << output;
  ASSERT_TRUE(fs::exists(dump / "edge-edge" / "fast_drop_frame1.csv")) << output;

  // The truth column is the conservative verdict: read back, conservative must agree on every
  // query (the coordinates are written as exact rationals), and the files hold what was said.
  const Outcome ccd = run_drape("ccd --json --passes 1 " + dump.string());
  ASSERT_EQ(ccd.status, 0) << ccd.output;
  const auto rows = nlohmann::json::parse(ccd.output);
  std::uint64_t queries = 0;
  for (const auto& row : rows) {
    if (row["kind"] == "all") continue;
    if (row["method"] == "conservative") {
      EXPECT_EQ(row["false_negatives"], 0) << row.dump();
      EXPECT_EQ(row["false_positives"], 0) << row.dump();
      queries += row["queries"].get<std::uint64_t>();
    }
  }
  EXPECT_GT(queries, 1000u);
  EXPECT_LE(queries, 4000u);
}

TEST(SceneBench, SelfCullingBesideTheBtDbvtInOneRun) {
  // fast_drop's first frames: the run without culling keeps the same state, and the patch
  // tree's tests lose none of the btDbvt's hits (vincent's) on the identical rounds.
  const auto [status, output] = scene_bench(DRAPE_SOURCE_DIR "/scenes/fast_drop.json --frames 2 --passes 1 --vs-btdbvt");
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("without culling: step_ms"), std::string::npos) << output;
  EXPECT_EQ(output.find("state differs"), std::string::npos) << output;
  const std::size_t summary = output.find("without self_culling (btDbvt self pairs), alternating frame by frame");
  ASSERT_NE(summary, std::string::npos) << output;
  const std::size_t lost = output.find(" of the btDbvt tests' ", summary);
  ASSERT_NE(lost, std::string::npos) << output;
  EXPECT_EQ(output.substr(output.rfind("; ", lost) + 2, lost - output.rfind("; ", lost) - 2), "0") << output;
  // Hits there were to lose: "0 of the btDbvt tests' N hits" with N > 0.
  EXPECT_EQ(output.find(" of the btDbvt tests' 0 hits", summary), std::string::npos) << output;
}
