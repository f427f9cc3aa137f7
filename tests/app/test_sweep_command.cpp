// drape sweep end to end: the table, the plot, and bad flags.
#include <gtest/gtest.h>

#include <fstream>

#include "drape_process.h"

using namespace drape::testing;
namespace fs = std::filesystem;

TEST(SweepCommand, WritesTheTableAndThePlot) {
  const fs::path out = fresh_temp_path("sweep", "small");
  const Outcome run = run_drape("sweep " DRAPE_SOURCE_DIR "/scenes/hanging.json --frames 2 --steps 1,2 --solvers cholmod,cg:1e-4 "
                                "--methods vincent --out " + out.string());
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("Pareto front"), std::string::npos) << run.output;
  EXPECT_EQ(lines(out / "sweep.csv").size(), 1u + 1 + 4);  // header, reference, 2 x 2 settings
  ASSERT_TRUE(fs::exists(out / "sweep.png"));
  std::ifstream png(out / "sweep.png", std::ios::binary);
  char magic[4] = {};
  png.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  // Started again: every run is kept, none runs, the table is the same but for times.
  const Outcome again = run_drape("sweep " DRAPE_SOURCE_DIR "/scenes/hanging.json --frames 2 --steps 1,2 --solvers cholmod,cg:1e-4 "
                                  "--methods vincent --no-plot --out " + out.string());
  EXPECT_EQ(again.status, 0) << again.output;
  EXPECT_NE(again.output.find("5 runs kept already, 0 to run"), std::string::npos) << again.output;
  // More frames: a different sweep, all run again.
  const Outcome longer = run_drape("sweep " DRAPE_SOURCE_DIR "/scenes/hanging.json --frames 3 --steps 1,2 --solvers cholmod,cg:1e-4 "
                                   "--methods vincent --no-plot --out " + out.string());
  EXPECT_NE(longer.output.find("0 runs kept already, 5 to run"), std::string::npos) << longer.output;
}

TEST(SweepCommand, BadFlagsNameTheFlag) {
  const std::string scene = DRAPE_SOURCE_DIR "/scenes/hanging.json";
  const Outcome solver = run_drape("sweep " + scene + " --solvers lu --no-plot --out " + fresh_temp_path("sweep", "a").string());
  EXPECT_EQ(solver.status, 2);
  EXPECT_NE(solver.output.find("--solvers 'lu': expected cholmod, cholmod:release_solves=N, cg, cg:TOLERANCE, projective or projective:NAME=VALUE[:NAME=VALUE...]"), std::string::npos) << solver.output;
  const Outcome method = run_drape("sweep " + scene + " --methods quartic");
  EXPECT_EQ(method.status, 2);
  EXPECT_NE(method.output.find("--methods"), std::string::npos) << method.output;
  const Outcome steps = run_drape("sweep " + scene + " --steps 0");
  EXPECT_EQ(steps.status, 2);
  EXPECT_NE(steps.output.find("--steps"), std::string::npos) << steps.output;
  const Outcome thickness = run_drape("sweep " + scene + " --thickness nan");
  EXPECT_EQ(thickness.status, 2);
  EXPECT_NE(thickness.output.find("--thickness"), std::string::npos) << thickness.output;
  const Outcome held = run_drape("sweep " + scene + " --self-in-solve maybe");
  EXPECT_EQ(held.status, 2);
  EXPECT_NE(held.output.find("--self-in-solve"), std::string::npos) << held.output;
}

TEST(SweepCommand, SelfContactsInTheSolveAreAKnob) {
  const fs::path out = fresh_temp_path("sweep", "held");
  const Outcome run = run_drape("sweep " DRAPE_SOURCE_DIR "/scenes/cloth_fold.json --frames 2 --steps 5 --solvers cholmod "
                                "--methods vincent --self-in-solve on,off --no-plot --out " + out.string());
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("self_in_solve=on"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("self_in_solve=off"), std::string::npos) << run.output;
  const std::vector<std::string> table = lines(out / "sweep.csv");
  ASSERT_EQ(table.size(), 1u + 1 + 2);  // header, reference, on and off
  EXPECT_NE(table[0].find(",max_zone_iterations,self_in_solve,frames_done,"), std::string::npos) << table[0];
}
