// The frame-statistics comparison behind drape check-stats and the golden regressions.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <map>

#include "drape/core/stats_compare.h"
#include "../temp_root.h"

using namespace drape;
namespace fs = std::filesystem;

namespace {

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = drape::testing::temp_root("stats");
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
  // The table gives the file its header, each row one cell per column written as before the
  // table existed (the literal header and printf format below are the earlier code's), and
  // the comparison its tolerances (the earlier list, literally).
  EXPECT_EQ(stats_header(),
            "frame,sim_time,wall_ms,solve_ms,solver_iterations,kinetic_energy,potential_energy,max_stretch,"
            "min_distance_obstacle,obstacle_contacts,solver_warnings,bvh_pairs,culled_triangles,vf_tests,ee_tests,culled,separated,root_solves,"
            "ccd_hits,impulse_iterations,impact_zones,proximity_impulses,held_self_contacts,rest_clamped_pairs,fail_safes,ccd_ms,broad_ms,narrow_ms,"
            "response_ms,penetrations,external_work,energy_excess,step_halvings,strain_limited,strain_ms,warnings");
  FrameStats s;
  s.frame = 7, s.sim_time = 0.1, s.wall_ms = 12.34567, s.solve_ms = 0.5, s.solver_iterations = 42;
  s.kinetic_energy = 1.0 / 3, s.potential_energy = -2.5e-7, s.max_stretch = 1.01, s.min_distance_obstacle = 0.25;
  s.obstacle_contacts = 3, s.solver_warnings = 1, s.external_work = 1e-20, s.energy_excess = -0.125, s.step_halvings = 2;
  s.strain_limited = 21, s.strain_ms = 5.0004;
  s.warnings = 1;
  CollisionCounters& c = s.collisions;
  c.bvh_pairs = 100, c.culled_triangles = 99, c.vf_tests = 11, c.ee_tests = 12, c.tests.culled = 13, c.tests.separated = 14, c.tests.root_solves = 15;
  c.ccd_hits = 16, c.impulse_iterations = 17, c.impact_zones = 18, c.proximity_impulses = 19, c.held_self_contacts = 23, c.rest_clamped_pairs = 20;
  c.fail_safes = 0, c.ccd_ms = 1.0005, c.broad_ms = 2, c.narrow_ms = 3, c.response_ms = 4;
  char expected[1024];
  std::snprintf(expected, sizeof expected,
                "%d,%.17g,%.3f,%.3f,%ld,%.17g,%.17g,%.17g,%.17g,%d,%d,%ld,%ld,%ld,%ld,%llu,%llu,%llu,%ld,%ld,%ld,%ld,%ld,%ld,%ld,%.3f,%.3f,%.3f,%.3f,,"
                "%.17g,%.17g,%d,%ld,%.3f,%d",
                s.frame, s.sim_time, s.wall_ms, s.solve_ms, s.solver_iterations, s.kinetic_energy, s.potential_energy,
                s.max_stretch, *s.min_distance_obstacle, s.obstacle_contacts, s.solver_warnings, c.bvh_pairs, c.culled_triangles, c.vf_tests,
                c.ee_tests, static_cast<unsigned long long>(c.tests.culled), static_cast<unsigned long long>(c.tests.separated),
                static_cast<unsigned long long>(c.tests.root_solves), c.ccd_hits, c.impulse_iterations, c.impact_zones,
                c.proximity_impulses, c.held_self_contacts, c.rest_clamped_pairs, c.fail_safes, c.ccd_ms, c.broad_ms, c.narrow_ms, c.response_ms,
                s.external_work, s.energy_excess, s.step_halvings, s.strain_limited, s.strain_ms, s.warnings);
  EXPECT_EQ(stats_row(s), expected);
  s.penetrations = 5;
  s.min_distance_obstacle.reset();
  const std::string row = stats_row(s);
  EXPECT_NE(row.find(",,3,1,100,"), std::string::npos) << "no distance: an empty cell; " << row;
  EXPECT_NE(row.find(",4.000,5,"), std::string::npos) << "penetrations counted: " << row;
  const std::map<std::string, std::pair<double, double>> earlier = {
      {"frame", {0, 0}},           {"sim_time", {1e-12, 1e-12}},          {"solver_iterations", {2, 0.05}},
      {"kinetic_energy", {1e-9, 1e-6}}, {"potential_energy", {1e-9, 1e-6}}, {"max_stretch", {1e-9, 1e-6}},
      {"min_distance_obstacle", {1e-7, 1e-6}}, {"obstacle_contacts", {2, 0.05}}, {"solver_warnings", {0, 0}},
      {"penetrations", {0, 0}},    {"fail_safes", {0, 0}},
      {"strain_limited", {2, 0.05}}};  // added with strain limiting: a count of work, like the iterations
  for (const StatsColumn& column : stats_columns()) {
    const std::string name = column.name;
    const auto listed = stats_tolerances().find(name);
    const ColumnTolerance used = listed != stats_tolerances().end() ? listed->second : default_tolerance();
    const bool timing = name.size() > 3 && name.substr(name.size() - 3) == "_ms";
    EXPECT_EQ(used.ignore, timing) << name;
    if (timing) continue;
    const auto before = earlier.find(name);
    const std::pair<double, double> expected_tolerance = before != earlier.end() ? before->second : std::pair{1e-9, 1e-6};
    EXPECT_EQ(used.absolute, expected_tolerance.first) << name;
    EXPECT_EQ(used.relative, expected_tolerance.second) << name;
  }
}
