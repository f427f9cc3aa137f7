// `drape ccd` end to end: the table, the JSON document, and the errors on bad input.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "drape_process.h"
#include "../temp_root.h"

namespace fs = std::filesystem;

namespace {

using drape::testing::run_drape;
using drape::testing::Outcome;

std::string data(const std::string& relative) { return std::string(DRAPE_TEST_DATA) + "/ccd-queries/" + relative; }

}  // namespace

TEST(CcdCommand, HelpTeaches) {
  const Outcome top = run_drape("--help");
  EXPECT_EQ(top.status, 0);
  EXPECT_NE(top.output.find("ccd"), std::string::npos);
  const Outcome ccd = run_drape("ccd --help");
  EXPECT_EQ(ccd.status, 0);
  for (const char* word : {"cubic", "dnf", "vincent", "conservative", "--json", "--kind", "Examples"})
    EXPECT_NE(ccd.output.find(word), std::string::npos) << word;
}

TEST(CcdCommand, JsonHasExactlyTheDocumentedKeys) {
  const Outcome run = run_drape("ccd --passes 1 --json " + data("unit-tests"));
  ASSERT_EQ(run.status, 0) << run.output;
  const auto doc = nlohmann::json::parse(run.output);
  ASSERT_TRUE(doc.is_array());
  ASSERT_EQ(doc.size(), 12u);  // 4 methods x (vertex-face, edge-edge, all)
  const std::set<std::string> keys = {"method", "kind", "queries", "positives", "true_positives",
                                      "false_negatives", "false_positives", "culled", "ns_per_query"};
  for (const auto& row : doc) {
    std::set<std::string> found;
    for (const auto& [key, value] : row.items()) found.insert(key);
    EXPECT_EQ(found, keys);
  }
  // Results are summed over the files: unit-tests hold 74 edge-edge and 250 vertex-face queries.
  for (const auto& row : doc) {
    if (row["kind"] == "all") {
      EXPECT_EQ(row["queries"], 324);
    }
    if (row["kind"] == "edge-edge") {
      EXPECT_EQ(row["positives"], 36);
    }
    if (row["method"] == "conservative") {
      EXPECT_EQ(row["false_negatives"], 0);
    }
    const int positives = row["positives"];
    const int found = row["true_positives"];
    const int missed = row["false_negatives"];
    EXPECT_EQ(found + missed, positives);
  }
}

TEST(CcdCommand, OneMethodAndAnExplicitKind) {
  const Outcome run = run_drape("ccd --passes 1 --method vincent --kind edge-edge --json " +
                        data("unit-tests/edge-edge/data_0_1.csv"));
  ASSERT_EQ(run.status, 0) << run.output;
  const auto doc = nlohmann::json::parse(run.output);
  ASSERT_EQ(doc.size(), 2u);  // edge-edge and all
  EXPECT_EQ(doc[0]["method"], "vincent");
  EXPECT_EQ(doc[0]["queries"], 20);
}

TEST(CcdCommand, TablePrintsEveryMethod) {
  const Outcome run = run_drape("ccd --passes 1 " + data("erleben-wedges"));
  ASSERT_EQ(run.status, 0) << run.output;
  for (const char* word : {"cubic", "dnf", "vincent", "conservative", "false_neg", "ns/query"})
    EXPECT_NE(run.output.find(word), std::string::npos) << word;
}

TEST(CcdCommand, BadInputExitsWithStatusTwo) {
  const fs::path dir = drape::testing::temp_root("ccd_cmd") / "edge-edge";
  fs::create_directories(dir);
  std::ofstream(dir / "bad.csv") << "0,1,0,1,0,1,0\n0,1,0,1,0,1\n";
  const Outcome bad = run_drape("ccd " + (dir / "bad.csv").string());
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.output.find((dir / "bad.csv").string() + ":2:"), std::string::npos) << bad.output;
  // A coordinate whose cubic would overflow a double (every method but the conservative one
  // missed such a contact), and one that rounds to zero.
  const std::string row = ",1,0,1,0,1,0\n";
  std::ofstream(dir / "huge.csv") << "1" + std::string(95, '0') << row << "0" << row << "0" << row << "0" << row << "0" << row
                                  << "0" << row << "0" << row << "0" << row;
  const Outcome huge = run_drape("ccd " + (dir / "huge.csv").string());
  EXPECT_EQ(huge.status, 2);
  EXPECT_NE(huge.output.find("huge.csv:1: column 1: expected a coordinate within +-1e90"), std::string::npos) << huge.output;
  std::ofstream(dir / "tiny.csv") << "0,1,1,1" + std::string(400, '0') + ",0,1,0\n" << "0" << row << "0" << row << "0" << row
                                  << "0" << row << "0" << row << "0" << row << "0" << row;
  const Outcome tiny = run_drape("ccd " + (dir / "tiny.csv").string());
  EXPECT_EQ(tiny.status, 2);
  EXPECT_NE(tiny.output.find("tiny.csv:1: column 4: the value is too small for a double"), std::string::npos) << tiny.output;

  // Each message names what was wrong: the path, the flag.
  const Outcome missing = run_drape("ccd /nonexistent.csv");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.output.find("/nonexistent.csv"), std::string::npos) << missing.output;
  const Outcome method = run_drape("ccd --method quartic " + data("unit-tests"));
  EXPECT_EQ(method.status, 2);
  EXPECT_NE(method.output.find("--method"), std::string::npos) << method.output;
  const Outcome passes = run_drape("ccd --passes 0 " + data("unit-tests"));
  EXPECT_EQ(passes.status, 2);
  EXPECT_NE(passes.output.find("--passes"), std::string::npos) << passes.output;
  const Outcome depth = run_drape("ccd --max-subdivision-depth 61 " + data("unit-tests"));
  EXPECT_EQ(depth.status, 2);
  EXPECT_NE(depth.output.find("--max-subdivision-depth"), std::string::npos) << depth.output;
  const Outcome negative = run_drape("ccd --thickness -1 " + data("unit-tests"));
  EXPECT_EQ(negative.status, 2);
  EXPECT_NE(negative.output.find("--thickness"), std::string::npos) << negative.output;
  const Outcome kind = run_drape("ccd --kind face-face " + data("unit-tests"));
  EXPECT_EQ(kind.status, 2);
  EXPECT_NE(kind.output.find("--kind"), std::string::npos) << kind.output;
  const Outcome no_files = run_drape("ccd");
  EXPECT_EQ(no_files.status, 2);
  EXPECT_NE(no_files.output.find("files"), std::string::npos) << no_files.output;
  EXPECT_EQ(run_drape("frobnicate").status, 2);
}

TEST(CcdCommand, FloatFlagsMustBeFinite) {
  // CLI11's ranges let NaN through; every float flag rejects it, and infinities, by name.
  for (const char* flag : {"--thickness", "--contact-tolerance", "--root-tolerance", "--time-tolerance"}) {
    for (const char* value : {"nan", "NaN", "inf"}) {
      const Outcome run = run_drape(std::string("ccd --passes 1 ") + flag + " " + value + " " + data("unit-tests/edge-edge/data_0_1.csv"));
      EXPECT_EQ(run.status, 2) << flag << " " << value << ": " << run.output;
      EXPECT_NE(run.output.find(std::string(flag) + ": expected a finite number"), std::string::npos) << flag << " " << value << ": " << run.output;
    }
  }
  EXPECT_EQ(run_drape("ccd --passes 1 --thickness 0.001 " + data("unit-tests/edge-edge/data_0_1.csv")).status, 0);
}

TEST(CcdCommand, AFileOutsideAKindFolderNeedsKind) {
  // A copy of a good file in a folder whose path names no kind.
  const fs::path dir = drape::testing::fresh_temp_path("ccd_command", "no_kind");
  fs::create_directories(dir);
  const fs::path file = dir / "queries.csv";
  fs::copy_file(data("unit-tests/edge-edge/data_0_1.csv"), file);
  const Outcome no_kind = run_drape("ccd --passes 1 " + file.string());
  EXPECT_EQ(no_kind.status, 2);
  EXPECT_NE(no_kind.output.find(file.string() + ": cannot tell the query kind"), std::string::npos) << no_kind.output;
  EXPECT_EQ(run_drape("ccd --passes 1 --kind edge-edge " + file.string()).status, 0);
}

TEST(CcdCommand, AFolderWithoutQueryFilesIsBadInput) {
  const fs::path empty = drape::testing::fresh_temp_path("ccd_command", "empty");
  fs::create_directories(empty);
  const Outcome run = run_drape("ccd " + empty.string());
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.output.find(empty.string() + ": the folder holds no .csv query file"), std::string::npos) << run.output;
}

TEST(CcdCommand, AnUnreadableSubfolderIsReportedNotThrown) {
  if (::geteuid() == 0) GTEST_SKIP() << "root reads every folder";
  const fs::path top = drape::testing::fresh_temp_path("ccd_command", "unreadable");
  fs::create_directories(top / "locked");
  fs::copy_file(data("unit-tests/edge-edge/data_0_1.csv"), top / "edge-edge.csv");
  fs::permissions(top / "locked", fs::perms::none);
  const Outcome run = run_drape("ccd --kind edge-edge " + top.string());
  fs::permissions(top / "locked", fs::perms::owner_all);
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.output.find(top.string()), std::string::npos) << run.output;  // the folder, or the subfolder in it
  EXPECT_NE(run.output.find(": cannot list the folder: "), std::string::npos) << run.output;
}
