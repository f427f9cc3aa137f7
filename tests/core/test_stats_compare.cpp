// The frame-statistics comparison behind drape check-stats and the golden regressions.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "drape/core/stats_compare.h"

using namespace drape;
namespace fs = std::filesystem;

namespace {

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / ("drape_stats_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

const char* HEADER = "frame,sim_time,wall_ms,kinetic_energy,min_distance_obstacle\n";

}  // namespace

TEST(StatsCompare, TimingsAreIgnoredAndSmallDifferencesTolerated) {
  const auto a = write("a.csv", std::string(HEADER) + "0,0,1.0,0.5,\n1,0.1,9.0,0.25,\n");
  const auto b = write("b.csv", std::string(HEADER) + "0,0,7.0,0.5,\n1,0.1,2.0,0.2500000001,\n");
  EXPECT_FALSE(compare_stats(a, b).has_value());
}

TEST(StatsCompare, ReportsTheFirstFrameAndColumnBeyondTolerance) {
  const auto a = write("c.csv", std::string(HEADER) + "0,0,1,0.5,0.1\n1,0.1,1,0.25,0.1\n2,0.2,1,0.3,0.1\n");
  const auto b = write("d.csv", std::string(HEADER) + "0,0,1,0.5,0.1\n1,0.1,1,0.26,0.1\n2,0.2,1,0.4,0.1\n");
  const auto d = compare_stats(a, b);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->frame, "1");
  EXPECT_EQ(d->column, "kinetic_energy");
  EXPECT_NE(d->message.find("frame 1, column kinetic_energy: run 0.25, golden 0.26"), std::string::npos) << d->message;
}

TEST(StatsCompare, EmptyAgainstAValueAndMissingRowsDiffer) {
  const auto a = write("e.csv", std::string(HEADER) + "0,0,1,0.5,\n");
  const auto b = write("f.csv", std::string(HEADER) + "0,0,1,0.5,0.3\n");
  ASSERT_TRUE(compare_stats(a, b).has_value());
  EXPECT_EQ(compare_stats(a, b)->column, "min_distance_obstacle");
  const auto shorter = write("g.csv", std::string(HEADER) + "0,0,1,0.5,0.3\n1,0.1,1,0.5,0.3\n");
  ASSERT_TRUE(compare_stats(b, shorter).has_value());
  EXPECT_NE(compare_stats(b, shorter)->message.find("1 frame rows, the golden file 2"), std::string::npos);
  const auto other_columns = write("h.csv", "frame,sim_time\n0,0\n");
  EXPECT_TRUE(compare_stats(a, other_columns).has_value());
  EXPECT_THROW(compare_stats(a, "/nonexistent.csv"), std::runtime_error);
}

TEST(StatsCompare, ARowWithAnotherCellCountIsAnErrorNamingTheLine) {
  const auto good = write("i.csv", std::string(HEADER) + "0,0,1,0.5,0.3\n1,0.1,1,0.5,0.3\n");
  const auto short_row = write("j.csv", std::string(HEADER) + "0,0,1,0.5,0.3\n1,0.1,1\n");
  const auto long_row = write("k.csv", std::string(HEADER) + "\n0,0,1,0.5,0.3,7\n");
  for (const auto& [path, expected] : {std::pair{short_row, ": line 3: expected 5 comma-separated cells as in the header, found 3"},
                                       std::pair{long_row, ": line 3: expected 5 comma-separated cells as in the header, found 6"}}) {
    for (const bool as_run : {true, false}) {
      try {
        if (as_run) compare_stats(path, good);
        else compare_stats(good, path);
        ADD_FAILURE() << path << " was accepted";
      } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path.string() + expected), std::string::npos) << e.what();
      }
    }
  }
}

TEST(StatsColumns, HeaderRowsAndTolerancesComeFromOneTable) {
  // One column table: the header names its columns in order, a row has one cell for each, and
  // the comparison's tolerances are the table's (timings ignored, the rest compared).
  const auto& columns = stats_columns();
  std::string expected;
  for (const StatsColumn& c : columns) expected += (expected.empty() ? std::string() : std::string(",")) + c.name;
  EXPECT_EQ(stats_header(), expected);
  FrameStats s;
  s.frame = 7;
  s.min_distance_obstacle = 0.25;
  const std::string row = stats_row(s);
  EXPECT_EQ(std::count(row.begin(), row.end(), ','), std::ptrdiff_t(columns.size()) - 1);
  EXPECT_EQ(row.substr(0, 2), "7,");
  for (const StatsColumn& c : columns) {
    const std::string name = c.name;
    const bool timing = name.size() > 3 && name.substr(name.size() - 3) == "_ms";
    EXPECT_EQ(c.tolerance.ignore, timing) << name;
    const auto listed = stats_tolerances().find(name);
    const ColumnTolerance used = listed != stats_tolerances().end() ? listed->second : default_tolerance();
    EXPECT_EQ(used.ignore, c.tolerance.ignore) << name;
    EXPECT_EQ(used.absolute, c.tolerance.absolute) << name;
    EXPECT_EQ(used.relative, c.tolerance.relative) << name;
  }
}
