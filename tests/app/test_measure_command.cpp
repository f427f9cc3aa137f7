// drape measure end to end: the Cusick measurements of a run's frame, and bad input.
#include <gtest/gtest.h>

#include <fstream>

#include "drape_process.h"

using namespace drape::testing;
namespace fs = std::filesystem;

// The 30 cm disc at frame 0, flat: coefficient 1 (to the mesh's polygonal rim), no nodes.
TEST(MeasureCommand, TheCusickCoefficientOfAFlatDiscIsOne) {
  const fs::path dir = fresh_temp_path("measure", "disc");
  fs::create_directories(dir);
  std::ofstream(dir / "disc.json") << R"({"frames": 1, "cloths": [{"mesh": ")" DRAPE_SOURCE_DIR R"(/scenes/meshes/disc_30cm.obj"}]})";
  ASSERT_EQ(run_drape("run " + (dir / "disc.json").string() + " --quiet --out " + (dir / "out").string()).status, 0);
  const Outcome flat = run_drape("measure cusick " + (dir / "out").string() + " --frame 0 --json");
  ASSERT_EQ(flat.status, 0) << flat.output;
  const auto at = flat.output.find("\"drape_coefficient\": ");
  ASSERT_NE(at, std::string::npos) << flat.output;
  EXPECT_NEAR(std::stod(flat.output.substr(at + 21)), 1.0, 0.01) << flat.output;
  EXPECT_NE(flat.output.find("\"nodes\": 0"), std::string::npos) << flat.output;
  EXPECT_NE(flat.output.find("\"fabric_radius_m\": 0.15"), std::string::npos) << flat.output;
  // The last frame by default, in words.
  const Outcome last = run_drape("measure cusick " + (dir / "out").string());
  EXPECT_EQ(last.status, 0) << last.output;
  EXPECT_NE(last.output.find("frame 1: Cusick drape coefficient"), std::string::npos) << last.output;
  // Bad input.
  const Outcome missing = run_drape("measure cusick " + (dir / "out").string() + " --frame 7");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.output.find("has no frame 7; its frames run from 0 to 1"), std::string::npos) << missing.output;
  const Outcome inverted = run_drape("measure cusick " + (dir / "out").string() + " --support-radius 0.2");
  EXPECT_EQ(inverted.status, 2);
  EXPECT_NE(inverted.output.find("expected radii with 0 < support radius < fabric radius"), std::string::npos) << inverted.output;
  EXPECT_EQ(run_drape("measure drop " + (dir / "out").string()).status, 2);
  EXPECT_EQ(run_drape("measure cusick " + (dir / "nothing").string()).status, 2);
}
