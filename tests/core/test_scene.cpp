// Scene files: defaults, the ARCSim vocabulary, and an error naming the file and JSON path for
// every kind of bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "drape/core/model.h"
#include "drape/core/scene.h"
#include "../temp_root.h"

using namespace drape;
namespace fs = std::filesystem;

namespace {

const char* MINIMAL = R"({"cloths": [{"grid": {}}]})";

std::string error_of(const std::string& text) {
  try {
    build_model(parse_scene(text, "bad.json"));
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

fs::path temp_dir() {
  const fs::path dir = drape::testing::temp_root("scene_test");
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST(Scene, DefaultsAndDerivedValues) {
  const Scene s = parse_scene(MINIMAL, "scenes/minimal.json");
  EXPECT_EQ(s.frames, 60);
  EXPECT_EQ(s.frame_steps, 10);
  EXPECT_NEAR(s.timestep(), 1.0 / 300, 1e-15);
  EXPECT_EQ(s.output.folder, fs::path("out/minimal"));
  EXPECT_EQ(s.collisions.method, ccd::Method::Vincent);
  const Scene t = parse_scene(R"({"frame_time": 0.04, "timestep": 0.005, "end_time": 1.0, "cloths": [{"grid": {}}]})", "t.json");
  EXPECT_EQ(t.frame_steps, 8);
  EXPECT_EQ(t.frames, 25);
}

TEST(Scene, EveryShippedSceneIsValid) {
  for (const auto& entry : fs::directory_iterator(DRAPE_SOURCE_DIR "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    const Scene s = load_scene(entry.path());
    EXPECT_FALSE(s.comment.empty()) << entry.path() << " needs a comment saying what it shows";
    EXPECT_NO_THROW(build_model(s)) << entry.path();
  }
}

TEST(Scene, ZeroStiffnessCreatesNoSprings) {
  const Model all = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [4, 4]}}]})", "a.json"));
  const Model no_bend = build_model(
      parse_scene(R"({"cloths": [{"grid": {"resolution": [4, 4]}, "material": {"bend": 0, "shear": 0}}]})", "b.json"));
  // 4x4 quads, 5x5 vertices: 40 stretch, 32 shear, 30 bend springs.
  EXPECT_EQ(all.springs.size(), 102u);
  EXPECT_EQ(no_bend.springs.size(), 40u);
  for (const Spring& s : no_bend.springs) EXPECT_EQ(s.kind, SpringKind::Stretch);
}

TEST(Scene, HandlesByCornerNodeBoxAndBall) {
  const Model m = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [4, 4]}}],
    "handles": [{"corners": ["top-left", "top-right"]}, {"nodes": [12]}, {"box": {"min": [-1, -1, -1], "max": [-0.4, -0.4, 1]}}]})",
                                          "h.json"));
  EXPECT_EQ(m.pins.size(), 4u);  // two corners, the centre, the bottom-left corner
  EXPECT_GE(m.pin_of_vertex[12], 0);
  // A ball of 0.3 m around the centre of the 1 m grid of 0.25 m quads: the centre and its four
  // axis neighbours (0.25 m away), not the diagonal ones (0.35 m).
  const Model ball = build_model(parse_scene(R"({"cloths": [{"grid": {"resolution": [4, 4]}}],
    "handles": [{"ball": {"center": [0, 0, 0], "radius": 0.3}}]})", "b.json"));
  EXPECT_EQ(ball.pins.size(), 5u);
  for (const Pin& p : ball.pins) EXPECT_LE(ball.initial_positions[p.vertex].norm(), 0.3);
}

TEST(Scene, BadInputNamesTheFileThePathAndWhatWasExpected) {
  struct Case {
    std::string text;
    const char* expected;
  };
  const Case cases[] = {
      {R"({"cloths": [{"grid": {}}], "colisions": {}})", "bad.json: /colisions: unknown key"},
      {R"({"cloths": [{"grid": {}}], "frames": "ten"})", "/frames: expected an integer, found \"ten\""},
      {R"({"cloths": [{"grid": {}}], "frames": 0})", "/frames: expected an integer from 1"},
      {R"({"cloths": [{"grid": {}, "material": {"density": -1}}]})", "/cloths/0/material/density: expected a number > 0"},
      {R"({"cloths": [{"grid": {}, "material": {"strain_limit": 1}}]})", "/cloths/0/material/strain_limit: expected a number from 1.001 to 10"},
      // Material and air values past what any cloth means (each passed validation before, and
      // density or stretch at 1e308 wrote non-finite energies from frame 0).
      {R"({"cloths": [{"grid": {}, "material": {"density": 1e308}}]})",
       "/cloths/0/material/density: expected a number > 0 and at most 1e+06 kg/m^2, found 1e+308"},
      {R"({"cloths": [{"grid": {}, "material": {"mass_per_area": 2e9}}]})",
       "/cloths/0/material/mass_per_area: expected a number > 0 and at most 1e+09 g/m^2"},
      {R"({"cloths": [{"grid": {}, "material": {"stretch": 1e308}}]})",
       "/cloths/0/material/stretch: expected a number >= 0 and at most 1e+09 N"},
      {R"({"cloths": [{"grid": {}, "material": {"tensile_stiffness": 1e10, "shear_stiffness": 1}}]})",
       "/cloths/0/material/tensile_stiffness: expected a number > 0 and at most 1e+09 N/m"},
      {R"({"cloths": [{"grid": {}, "material": {"bending_rigidity": 1e4}}]})",
       "/cloths/0/material/bending_rigidity: expected a number > 0 and at most 1000 N m"},
      {R"({"cloths": [{"grid": {}, "material": {"air_damping": 1e7}}]})",
       "/cloths/0/material/air_damping: expected a number >= 0 and at most 1e+06 1/s"},
      {R"({"cloths": [{"grid": {}}], "friction": 1e300})", "/friction: expected a number >= 0 and at most 100, found"},
      {R"({"cloths": [{"grid": {}}], "wind": {"density": 1e300}})", "/wind/density: expected a number >= 0 and at most 10000 kg/m^3"},
      {R"({"cloths": [{"grid": {}}], "wind": {"drag": -1}})", "/wind/drag: expected a number >= 0 and at most 100"},

      {R"({"cloths": [{"grid": {}, "material": {"density": 0.2, "mass_per_area": 200}}]})",
       "/cloths/0/material/mass_per_area: expected 'density' (kg/m^2) or 'mass_per_area' (g/m^2), not both"},
      {R"({"cloths": [{"grid": {}, "material": {"stretch": 9, "tensile_stiffness": 9, "shear_stiffness": 1}}]})",
       "/cloths/0/material/stretch: expected no 'stretch' beside 'tensile_stiffness' and 'shear_stiffness'"},
      {R"({"cloths": [{"grid": {}, "material": {"bend": 1, "tensile_stiffness": 9, "shear_stiffness": 1}}]})",
       "/cloths/0/material/bend: expected no 'bend' beside"},
      {R"({"cloths": [{"grid": {}, "material": {"tensile_stiffness": 9}}]})",
       "/cloths/0/material/tensile_stiffness: expected 'tensile_stiffness' and 'shear_stiffness' together"},
      {R"({"cloths": [{"grid": {}, "material": {"shear_stiffness": 9}}]})",
       "/cloths/0/material/shear_stiffness: expected 'tensile_stiffness' and 'shear_stiffness' together"},
      {R"({"cloths": [{"grid": {"size": [1, 1], "resolution": [2, 20]}, "material": {"tensile_stiffness": 100, "shear_stiffness": 90}}]})",
       "/cloths/0/material/shear_stiffness: the grid's quads (0.5 x 0.05 m) are too elongated"},
      {R"({"cloths": [{"grid": {}, "material": {"bend": 1, "bending_rigidity": 1e-5}}]})",
       "/cloths/0/material/bending_rigidity: expected one bending model"},
      {R"({"cloths": [{"grid": {}, "material": {"bending_rigidity": 0}}]})", "/cloths/0/material/bending_rigidity: expected a number > 0"},
      {R"({"cloths": [{"grid": {"resolution": [0, 4]}}]})", "/cloths/0/grid/resolution/0: expected an integer from 1"},
      {R"({"cloths": [{"grid": {"size": [1, -2]}}]})", "/cloths/0/grid/size: expected two sizes > 0"},
      {R"({"cloths": []})", "/cloths: expected at least 1 entries"},
      {R"({"frames": 3})", "/: missing the required key 'cloths'"},
      {R"({"cloths": [{"grid": {}, "mesh": "a.obj"}]})", "/cloths/0: expected exactly one of 'grid'"},
      {R"({"cloths": [{"grid": {}}], "gravity": [0, 0]})", "/gravity: expected an array of 3 numbers"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "lu"}})", "/solver/type: expected one of 'cholmod', 'cg', 'projective'"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "iterations": 0}})", "/solver/iterations"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "chebyshev": 1}})", "/solver/chebyshev"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "history": 101}})", "/solver/history: expected"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "tolerance": -1}})", "/solver/tolerance: expected a number from 0 to 1"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "cg", "tolerance": 0}})", "/solver/tolerance: expected a number from 1e-16 to 1"},
      {R"({"cloths": [{"grid": {}}], "solver": {"factor_reuse": -1}})", "/solver/factor_reuse: expected"},
      // A key of another solver type: refused, not ignored.
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "cholmod", "history": 3}})",
       "/solver/history: applies to the projective solver only, and this scene's 'type' is cholmod"},
      {R"({"cloths": [{"grid": {}}], "solver": {"tolerance": 0.5}})", "/solver/tolerance: applies to the cg or projective solver only"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "cg", "factor_reuse": 5}})", "/solver/factor_reuse: applies to the cholmod solver only"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "cg", "iterations": 5}})", "/solver/iterations: applies to the projective solver only"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "max_iterations": 5}})", "/solver/max_iterations: applies to the cg solver only"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "release_solves": 2}})", "/solver/release_solves: applies to the cholmod solver only"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "history": 0, "tolerance": 0.1}})",
       "/solver/tolerance: applies to L-BFGS (a 'history' above 0) only"},
      {R"({"cloths": [{"grid": {}}], "solver": {"type": "projective", "chebyshev": 0.5}})",
       "/solver/chebyshev: applies to local-global iterations ('history': 0) only"},
      {R"({"cloths": [{"grid": {}}], "end_time": 0.05})", "/end_time: expected a whole number of frames of 0.03333333333 s (frame_time); 0.05 s is 1.5 frames"},
      {R"({"cloths": [{"grid": {}}], "output": {"folder": ""}})", "/output/folder: expected a folder's path, not an empty string"},
      {R"({"cloths": [{"mesh": "a.obj", "material": {"shear": 200}}]})", "/cloths/0/material/shear: a mesh cloth's springs are its edges"},
      {R"({"cloths": [{"grid": {}}], "collisions": {"method": "quartic"}})", "/collisions/method: expected one of"},
      {R"({"cloths": [{"grid": {}}], "timestep": 0.007})", "/timestep: expected a timestep that divides frame_time"},
      {R"({"cloths": [{"grid": {}}], "timestep": 1e-300})", "/timestep: expected at most 100000 steps per frame"},
      {R"({"cloths": [{"grid": {}}], "end_time": 1e300})", "/end_time: expected at most 10000000 frames"},
      {R"({"cloths": [{"grid": {}}], "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0}}]})",
       "/obstacles/0/sphere/radius: expected a number from 1e-6 to 1e4 (m), found 0"},
      {R"({"cloths": [{"grid": {}}], "obstacles": [{"plane": {"normal": [0, 0, 0]}}]})", "/obstacles/0/plane/normal: the normal must not be zero"},
      {R"({"cloths": [{"grid": {}}], "handles": [{"nodes": [100000]}]})", "/handles/0/nodes/0: vertex 100000 does not exist"},
      {R"({"cloths": [{"grid": {}}], "handles": [{"cloth": 1, "nodes": [0]}]})", "/handles/0/cloth: expected an integer from 0 to 0"},
      {R"({"cloths": [{"grid": {}}], "handles": [{"box": {"min": [5, 5, 5], "max": [6, 6, 6]}}]})", "/handles/0/box: the box holds no vertex"},
      {R"({"cloths": [{"grid": {}}], "handles": [{}]})", "/handles/0: expected 'nodes', 'corners', 'box' or 'ball'"},
      {R"({"cloths": [{"grid": {}}], "handles": [{"ball": {"center": [5, 5, 5], "radius": 1}}]})", "/handles/0/ball: the ball holds no vertex"},
      {R"({"cloths": [{"grid": {}}], "handles": [{"ball": {"center": [0, 0, 0], "radius": -1}}]})",
       "/handles/0/ball/radius: expected a number from 1e-6 to 1e4 (m), found -1"},
      {R"({"cloths": [{"grid": {}}], "handles": [{"corners": ["middle"]}]})", "/handles/0/corners/0: expected one of 'bottom-left'"},
      {R"({"cloths": [{"mesh": "nowhere.obj"}]})", "/cloths/0/mesh: nowhere.obj: no such mesh file"},
      {R"({"cloths": [{"grid": {}}], "output": {"mesh_format": "xyz"}})", "/output/mesh_format: expected one of"},
      {R"({"cloths": [{"grid": {}}], "frames": 1e999})", "bad.json: line 1, column 38: the number 1e999 is beyond a double's range"},
      {R"({"cloths": [{"grid": 5}]})", "bad.json: /cloths/0/grid: expected an object, found 5"},
      {R"({"cloths": {}})", "bad.json: /cloths: expected an array, found {}"},
      {R"({"cloths": [{"grid": {}}], "friction": -1})", "bad.json: /friction: expected a number >= 0 and at most 100, found -1"},
      {R"({"cloths": [{"grid": {}}], "collisions": {"self": "yes"}})",
       "bad.json: /collisions/self: expected true or false, found \"yes\""},
      {R"({"cloths": [{"grid": {}}], "output": {"folder": 3}})", "bad.json: /output/folder: expected a string, found 3"},
      {R"({"cloths": [{"grid": {"size": [1]}}]})", "bad.json: /cloths/0/grid/size: expected an array of 2 numbers, found [1]"},
      {R"({"cloths": [{"grid": {"resolution": [4]}}]})",
       "bad.json: /cloths/0/grid/resolution: expected [quads along x, quads along y]"},
      {R"({"cloths": [{"grid": {}, "transform": {"rotate": [90, 0, 0, 0]}}]})",
       "bad.json: /cloths/0/transform/rotate: the rotation axis must not be zero"},
      {R"({"cloths": [{"grid": {}, "transform": {"rotate": [90, 1e200, 0, 0]}}]})",
       "bad.json: /cloths/0/transform/rotate: expected a rotation axis of finite length"},
      {R"({"cloths": [{"grid": {}}], "handles": [{"nodes": [0], "motion": {"start": 2, "end": 1}}]})",
       "bad.json: /handles/0/motion: 'end' must be later than 'start'"},
      {R"({"cloths": [{"grid": {}}], "bounds": {"min": [-1, -1, 1], "max": [1, 1, -1]}})",
       "bad.json: /bounds: expected min <= max in every coordinate"},
      {R"({"cloths": [{"grid": {}, "transform": {"translate": [0, 0, 1]}}], "bounds": {"min": [-1, -1, -1], "max": [1, 1, 0.5]}})",
       "bad.json: /bounds: expected a box holding every cloth's initial position; cloth 0 has a vertex at (-0.5, -0.5, 1)"},
      {R"({"cloths": [{"grid": {}}], "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 1}, "plane": {}}]})",
       "bad.json: /obstacles/0: expected exactly one of 'sphere', 'plane' or 'mesh'"},
      {R"({"cloths": [{"grid": {}}], "obstacles": [{"plane": {}, "transform": {"scale": 2}}]})",
       "bad.json: /obstacles/0/transform: only a mesh obstacle takes a transform"},
      {R"({"cloths": [{"grid": {}}], "obstacles": [{"plane": {"normal": [1e200, 0, 0]}}]})",
       "bad.json: /obstacles/0/plane/normal: expected a normal of finite length"},
      {R"({"cloths": [{"grid": {}}], "frame_steps": 10, "timestep": 0.001})",
       "bad.json: /: give 'frame_steps' or 'timestep', not both"},
      {R"({"cloths": [{"grid": {}}], "render": 3})", "bad.json: /render: expected an object"},
      // Hostile input: numbers that validate one by one but make a run meaningless or
      // non-finite, duplicate keys, nesting that would overflow a recursive reader.
      {R"({"cloths": [{"grid": {"size": [1e308, 1e308]}}]})",
       "bad.json: /cloths/0/grid/size: expected two sizes > 0 and at most 10000 m"},
      {R"({"cloths": [{"grid": {}, "transform": {"translate": [1e308, 0, 0]}}]})",
       "bad.json: /cloths/0/transform/translate: expected coordinates within +-1e+07 m"},
      {R"({"cloths": [{"grid": {"size": [1000, 1000]}, "transform": {"translate": [9.9e6, 0, 0], "scale": 1e6}}]})",
       "bad.json: /cloths/0: vertex 0 lands at ("},
      {R"({"cloths": [{"grid": {}, "transform": {"scale": 1e300}}]})",
       "bad.json: /cloths/0/transform/scale: expected a number from 1e-6 to 1e6"},
      {R"({"cloths": [{"grid": {}, "velocity": [0, 0, -1e300]}]})",
       "bad.json: /cloths/0/velocity: expected coordinates within +-100000 m/s"},
      {R"({"cloths": [{"grid": {}}], "gravity": [0, 0, -1e300]})", "bad.json: /gravity: expected coordinates within +-10000 m/s^2"},
      {R"({"cloths": [{"grid": {}}], "collisions": {"thickness": 10}})",
       "bad.json: /collisions/thickness: expected a number from 0 to 1 (m), found 10"},
      {R"({"cloths": [{"grid": {"size": [0.1, 0.1]}}], "collisions": {"thickness": 0.5}})",
       "bad.json: /collisions/thickness: the thickness (0.5 m) is more than a quarter of cloth 0's diagonal"},
      {R"({"cloths": [{"grid": {}}], "frame_time": 1e300})", "bad.json: /frame_time: expected a number from 1e-6 to 60 (s)"},
      {R"({"frames": 3, "cloths": [{"grid": {}}], "frames": 4})",
       "bad.json: line 1, column 41: the key 'frames' appears twice in the same object"},
      {R"({"cloths": [{"grid": {"size": [1, 1], "s\u0069ze": [2, 2]}}]})",
       "bad.json: line 1, column 39: the key 'size' appears twice in the same object"},
      {"{\"cloths\": " + std::string(100000, '[') + std::string(100000, ']') + "}",
       "bad.json: line 1, column 75: expected at most 64 levels of nested arrays and objects"},
  };
  for (const Case& c : cases) {
    const std::string message = error_of(c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "scene: " << c.text.substr(0, 200) << "\nmessage: " << message;
  }
}

// A grid the schema accepts but no ordinary machine can run: refused with the estimate,
// before anything of its size is allocated.
TEST(Scene, AGridBeyondTheMachinesMemoryIsRefusedWithTheEstimate) {
  const std::string message = error_of(R"({"cloths": [{"grid": {"resolution": [4096, 4096]}}]})");
  if (message.empty()) GTEST_SKIP() << "this machine has the memory of a 4096 x 4096 run (about 256 GiB)";
  EXPECT_NE(message.find("bad.json: /cloths: the cloths have 16785409 vertices; a run needs about 256 GiB of memory"),
            std::string::npos)
      << message;
}

TEST(Scene, JsonSyntaxErrorsGiveLineAndColumn) {
  const std::string message = error_of("{\n  \"cloths\": [\n    {\"grid\": {}},\n  ]\n}");
  EXPECT_NE(message.find("bad.json: line 4, column 3: invalid JSON"), std::string::npos) << message;
}

TEST(Scene, BadMeshesAreRejectedWithTheirProblem) {
  const fs::path dir = temp_dir();
  std::ofstream(dir / "nonmanifold.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 2 5\n";
  std::ofstream(dir / "degenerate.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n";
  std::ofstream(dir / "garbage.obj") << "this is not a mesh\n";
  std::ofstream(dir / "good.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
  const auto scene_with = [&](const std::string& mesh) {
    return R"({"cloths": [{"mesh": ")" + (dir / mesh).string() + R"("}]})";
  };
  EXPECT_NE(error_of(scene_with("nonmanifold.obj")).find("/cloths/0/mesh: " + (dir / "nonmanifold.obj").string() + ": edge (0, 1) is shared by more than two triangles"), std::string::npos)
      << error_of(scene_with("nonmanifold.obj"));
  EXPECT_NE(error_of(scene_with("degenerate.obj")).find("zero area"), std::string::npos) << error_of(scene_with("degenerate.obj"));
  EXPECT_NE(error_of(scene_with("garbage.obj")).find("/cloths/0/mesh:"), std::string::npos) << error_of(scene_with("garbage.obj"));
  // A mesh's springs are fitted to the tensile and shear stiffness together: a shear stiffness
  // alone is refused, both are taken.
  const std::string shear = R"({"cloths": [{"mesh": ")" + (dir / "good.obj").string() + R"(", "material": {)";
  EXPECT_NE(error_of(shear + R"("shear_stiffness": 30}}]})").find("/cloths/0/material/shear_stiffness: expected 'tensile_stiffness'"),
            std::string::npos)
      << error_of(shear + R"("shear_stiffness": 30}}]})");
  EXPECT_EQ(error_of(shear + R"("tensile_stiffness": 300, "shear_stiffness": 30}}]})"), "");
  EXPECT_EQ(error_of(scene_with("good.obj")), "");
  // A NaN is never welded into a finite vertex: the mesh check sees it.
  std::ofstream(dir / "nan.obj") << "v nan 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
  const std::string non_finite = error_of(scene_with("nan.obj"));
  EXPECT_NE(non_finite.find("/cloths/0/mesh: " + (dir / "nan.obj").string() + ": vertex "), std::string::npos) << non_finite;
  EXPECT_NE(non_finite.find("non-finite"), std::string::npos) << non_finite;
  std::ofstream(dir / "repeated.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 1 2 1\n";
  const std::string repeated = error_of(scene_with("repeated.obj"));
  EXPECT_NE(repeated.find("/cloths/0/mesh: " + (dir / "repeated.obj").string() + ": triangle 1 repeats a vertex"), std::string::npos)
      << repeated;
  // Obstacle meshes are checked alike.
  const std::string obstacle =
      error_of(R"({"cloths": [{"grid": {}}], "obstacles": [{"mesh": ")" + (dir / "nonmanifold.obj").string() + R"("}]})");
  EXPECT_NE(obstacle.find("/obstacles/0/mesh: " + (dir / "nonmanifold.obj").string() + ": edge (0, 1)"), std::string::npos)
      << obstacle;
  // Scene bounds must hold a mesh cloth's initial vertices too.
  const std::string outside = error_of(R"({"cloths": [{"mesh": ")" + (dir / "good.obj").string() +
                                       R"("}], "bounds": {"min": [-1, -1, -1], "max": [0.5, 0.5, 1]}})");
  EXPECT_NE(outside.find("bad.json: /bounds: expected a box holding every cloth's initial position; cloth 0 has a vertex at (1, 0, 0)"),
            std::string::npos)
      << outside;
  EXPECT_EQ(error_of(R"({"cloths": [{"mesh": ")" + (dir / "good.obj").string() +
                     R"("}], "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}})"),
            "");
  // Corners need a grid.
  EXPECT_NE(error_of(R"({"cloths": [{"mesh": ")" + (dir / "good.obj").string() + R"("}], "handles": [{"corners": ["top-left"]}]})")
                .find("/handles/0/corners: corner names need a grid cloth"),
            std::string::npos);
}
