// `drape ccd` end to end: the table, the JSON document, and the errors on bad input.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "drape_process.h"

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
  const fs::path dir = fs::temp_directory_path() / ("drape_ccd_cmd_" + std::to_string(::getpid())) / "edge-edge";
  fs::create_directories(dir);
  std::ofstream(dir / "bad.csv") << "0,1,0,1,0,1,0\n0,1,0,1,0,1\n";
  const Outcome bad = run_drape("ccd " + (dir / "bad.csv").string());
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.output.find((dir / "bad.csv").string() + ":2:"), std::string::npos) << bad.output;

  EXPECT_EQ(run_drape("ccd /nonexistent.csv").status, 2);
  EXPECT_EQ(run_drape("ccd --method quartic " + data("unit-tests")).status, 2);
  EXPECT_EQ(run_drape("ccd --passes 0 " + data("unit-tests")).status, 2);
  EXPECT_EQ(run_drape("ccd").status, 2);
  EXPECT_EQ(run_drape("frobnicate").status, 2);
  const Outcome no_kind = run_drape("ccd " + fs::temp_directory_path().string() + "/../" + (dir / "bad.csv").string());
  EXPECT_EQ(no_kind.status, 2);
}
