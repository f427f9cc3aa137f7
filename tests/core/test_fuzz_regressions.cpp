// Every input in tests/data/fuzz-regressions (crashes the fuzzers found, once fixed, and
// hand-made extremes) goes through the parsers again: a clear error or a result, nothing else.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "drape/ccd_eval/query_file.h"
#include "drape/core/grid.h"
#include "drape/core/mesh.h"
#include "drape/core/mesh_io.h"
#include "drape/core/model.h"

namespace fs = std::filesystem;

TEST(FuzzRegressions, EveryKeptInputEndsInAResultOrAClearError) {
  std::size_t replayed = 0;
  for (const auto& entry : fs::directory_iterator(DRAPE_SOURCE_DIR "/tests/data/fuzz-regressions")) {
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string name = entry.path().filename().string();
    if (name.rfind("scene-", 0) == 0) {
      try {
        drape::build_model(drape::parse_scene(buffer.str(), entry.path()));
      } catch (const drape::SceneError& e) {
        EXPECT_NE(std::string(e.what()).find(entry.path().string()), std::string::npos) << e.what();
      }
      ++replayed;
    } else if (name.rfind("mesh-", 0) == 0) {
      // As the mesh fuzzer reads it: the first byte picks OBJ (even) or PLY (odd).
      const std::string bytes = buffer.str();
      if (bytes.empty()) continue;
      const std::string format = (static_cast<unsigned char>(bytes[0]) & 1) ? "ply" : "obj";
      try {
        (void)drape::mesh_problem(drape::parse_mesh(bytes.substr(1), format, entry.path().string()));
      } catch (const drape::MeshFileError& e) {
        EXPECT_NE(std::string(e.what()).find(entry.path().string()), std::string::npos) << e.what();
      }
      ++replayed;
    } else if (name.rfind("frame-", 0) == 0) {
      // As the frame fuzzer reads it: the first byte picks the grid.
      const std::string bytes = buffer.str();
      if (bytes.empty()) continue;
      drape::GridSpec spec;
      const auto b = static_cast<unsigned char>(bytes[0]);
      spec.resolution = {1 + b % 4, 1 + (b / 4) % 4};
      try {
        (void)drape::parse_frame_positions(bytes.substr(1), entry.path().string(), drape::make_grid(spec).mesh);
      } catch (const drape::MeshFileError& e) {
        EXPECT_NE(std::string(e.what()).find(entry.path().string()), std::string::npos) << e.what();
      }
      ++replayed;
    } else if (name.rfind("query_file-", 0) == 0) {
      try {
        drape::ccd::parse_query_text(buffer.str(), entry.path(), drape::ccd::QueryKind::EdgeEdge);
      } catch (const drape::ccd::QueryFileError& e) {
        EXPECT_NE(std::string(e.what()).find(entry.path().string()), std::string::npos) << e.what();
      }
      ++replayed;
    }
  }
  EXPECT_GE(replayed, 9u);
}
