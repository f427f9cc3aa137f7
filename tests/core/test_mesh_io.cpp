// Mesh files through assimp: round trips, welding, atomic writes, errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "drape/core/grid.h"
#include "drape/core/mesh_io.h"
#include "drape/core/model.h"
#include "drape/core/run.h"
#include "drape/core/scene.h"
#include "../temp_root.h"

using namespace drape;
namespace fs = std::filesystem;

TEST(MeshIo, RoundTripsObjAndPly) {
  const fs::path dir = drape::testing::temp_root("mesh_io");
  fs::create_directories(dir);
  const GridMesh grid = make_grid({Vec2(2, 1), {6, 3}, GridDiagonals::Alternate});
  for (const std::string format : {"obj", "ply", "stl"}) {
    const fs::path path = dir / ("grid" + mesh_extension(format));
    save_mesh(path, grid.mesh, format);
    EXPECT_FALSE(fs::exists(path.string() + ".partial"));
    const TriangleMesh back = load_mesh(path);
    EXPECT_EQ(back.vertices.size(), grid.mesh.vertices.size()) << format;  // STL repeats vertices: welded
    EXPECT_EQ(back.triangles.size(), grid.mesh.triangles.size()) << format;
    EXPECT_NEAR(surface_area(back), 2.0, 1e-5) << format;
    EXPECT_EQ(mesh_problem(back), "") << format;
  }
  EXPECT_FALSE(fs::exists(dir / "grid.mtl"));  // OBJ without a material file
}

// An OBJ cloth keeps the file's vertex order (assimp's reader numbers vertices as the faces
// first use them): its frames list the vertices as the file does, a handle's nodes name the
// file's vertices, and a vertex no triangle uses is left out and refused as a node.
TEST(MeshIo, AnObjClothKeepsTheFilesVertexOrder) {
  const fs::path dir = drape::testing::temp_root("mesh_order");
  fs::create_directories(dir);
  {
    // Vertex 0 unused; the faces use 4 and 3 before 1 and 2; vertex 3 homogeneous (w = 2,
    // read as (1, 1, 0)); vertex 5 repeats vertex 1's position; vertex 6, not a number, unused.
    std::ofstream obj(dir / "square.obj");
    obj << "v 5 5 5\nv 0 0 0\nv 1 0 0\nv 2 2 0 2\nv 0 1 0\nv 0 0 0\nv nan nan nan\nf 5 4 2\nf 4 3 6\n";
  }
  TriangleMesh mesh = load_mesh(dir / "square.obj");
  ASSERT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.vertices[0], Vec3(0, 1, 0));  // as the faces first use them
  EXPECT_TRUE(number_as_in_file(mesh, dir / "square.obj"));
  ASSERT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.vertices[0], Vec3(0, 0, 0));
  EXPECT_EQ(mesh.vertices[1], Vec3(1, 0, 0));
  EXPECT_EQ(mesh.vertices[2], Vec3(1, 1, 0));
  EXPECT_EQ(mesh.vertices[3], Vec3(0, 1, 0));
  EXPECT_EQ(mesh.from_file, (std::vector<int>{-1, 0, 1, 2, 3, 0, -1}));
  EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{3, 2, 0}, {2, 1, 0}}));
  EXPECT_EQ(mesh_problem(mesh), "");

  const auto scene = [&](int node) {
    return parse_scene(R"({"cloths": [{"mesh": ")" + (dir / "square.obj").string() + R"("}], "handles": [{"nodes": [)" +
                           std::to_string(node) + "]}]}",
                       "inline.json");
  };
  const Model model = build_model(scene(3));
  ASSERT_EQ(model.pins.size(), 1u);
  EXPECT_EQ(model.initial_positions[std::size_t(model.pins[0].vertex)], Vec3(1, 1, 0));  // the file's vertex 3
  try {
    build_model(scene(0));
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("/handles/0/nodes/0: vertex 0 of cloth 0's mesh file is used by no triangle"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(build_model(scene(6)), SceneError);  // unused
  EXPECT_THROW(build_model(scene(7)), SceneError);  // the file has 7 vertices

  // A vertex no "v" line gives (here one moved after reading): the numbering is not the
  // file's, and the mesh is left as it was.
  TriangleMesh moved = load_mesh(dir / "square.obj");
  moved.vertices[1] += Vec3(0.1, 0, 0);
  const TriangleMesh before = moved;
  EXPECT_FALSE(number_as_in_file(moved, dir / "square.obj"));
  EXPECT_EQ(moved.vertices, before.vertices);
  EXPECT_TRUE(moved.from_file.empty());
}

TEST(MeshIo, ErrorsNameTheFile) {
  try {
    load_mesh("/nonexistent/cloth.obj");
    FAIL();
  } catch (const MeshFileError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/cloth.obj: no such mesh file"), std::string::npos);
  }
  EXPECT_THROW(save_mesh("/nonexistent/folder/x.obj", make_grid({}).mesh, "obj"), MeshFileError);
  // An OBJ face naming a vertex the file lacks: the line and the corner (assimp's message
  // named neither).
  const fs::path dir = drape::testing::temp_root("mesh_faces");
  fs::create_directories(dir);
  for (const auto& [face, expected] : {std::pair{"f 1 2 9", "bad.obj:5: face corner '9': vertex 9 is out of range: the file gives 4 vertices"},
                                       std::pair{"f 0 1 2", "bad.obj:5: face corner '0': expected a vertex index from 1 to 4"},
                                       std::pair{"f -1 -2 -5", "bad.obj:5: face corner '-5': vertex -5 is out of range"}}) {
    std::ofstream(dir / "bad.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n" << face << "\n";
    try {
      load_mesh(dir / "bad.obj");
      FAIL() << face;
    } catch (const MeshFileError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

TEST(Mesh, TopologyOfAGrid) {
  const GridMesh grid = make_grid({Vec2(1, 1), {3, 2}, GridDiagonals::Forward});
  EXPECT_EQ(grid.mesh.vertices.size(), 12u);
  EXPECT_EQ(grid.mesh.triangles.size(), 12u);
  EXPECT_EQ(mesh_edges(grid.mesh).size(), 3u * 3 + 4 * 2 + 6);  // horizontal, vertical, diagonal
  EXPECT_EQ(bending_pairs(grid.mesh).size(), mesh_edges(grid.mesh).size() - 10);  // interior edges
  EXPECT_EQ(*grid_corner(grid, "top-right"), 11);
  const GridSprings springs = grid_springs(grid);
  EXPECT_EQ(springs.stretch.size(), 17u);
  EXPECT_EQ(springs.shear.size(), 12u);
  EXPECT_EQ(springs.bend.size(), 2u * 3 + 4);  // along x: 2 in each of 3 rows; along y: 1 in each of 4 columns
}

TEST(MeshIo, FramesMustMatchTheMeshAndBeFinite) {
  const fs::path dir = drape::testing::temp_root("mesh_io");
  fs::create_directories(dir);
  const GridMesh grid = make_grid({Vec2(1, 1), {2, 2}, GridDiagonals::Alternate});
  const fs::path good = dir / "frame_good.obj";
  save_mesh(good, grid.mesh, "obj");
  EXPECT_EQ(load_frame_positions(good, grid.mesh).size(), grid.mesh.vertices.size());
  const auto error_of = [&](const fs::path& path) {
    try {
      load_frame_positions(path, grid.mesh);
    } catch (const MeshFileError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // One triangle more than the mesh: every triangle of the file is counted.
  const fs::path extra = dir / "frame_extra.obj";
  fs::copy_file(good, extra, fs::copy_options::overwrite_existing);
  std::ofstream(extra, std::ios::app) << "\nf 1 2 3\n";
  EXPECT_NE(error_of(extra).find(extra.string() + ": expected 8 triangles, found 9"), std::string::npos) << error_of(extra);
  // A NaN coordinate.
  std::ifstream in(good);
  std::string text, line;
  bool replaced = false;
  while (std::getline(in, line)) {
    if (!replaced && line.rfind("v ", 0) == 0) {
      line = "v nan 0 0";
      replaced = true;
    }
    text += line + "\n";
  }
  ASSERT_TRUE(replaced);
  const fs::path non_finite = dir / "frame_nan.obj";
  std::ofstream(non_finite) << text;
  EXPECT_NE(error_of(non_finite).find(non_finite.string() + ": vertex "), std::string::npos) << error_of(non_finite);
  EXPECT_NE(error_of(non_finite).find("has a non-finite coordinate"), std::string::npos) << error_of(non_finite);
}

TEST(MeshIo, NonFiniteVerticesAreNotWelded) {
  const fs::path dir = drape::testing::temp_root("mesh_io");
  fs::create_directories(dir);
  const fs::path path = dir / "nan.obj";
  std::ofstream(path) << "v 0 0 0\nv 1 0 0\nv nan 0 0\nf 1 2 3\n";
  const TriangleMesh mesh = load_mesh(path);
  ASSERT_EQ(mesh.vertices.size(), 3u);
  EXPECT_FALSE(mesh.vertices[2].allFinite());
  EXPECT_EQ(mesh_problem(mesh), "vertex 2 has a non-finite coordinate");
}

// Frames keep double precision: a cloth a thousand kilometres from the origin, where single
// precision rounds to 6 cm, reads back bit for bit from the frame a run wrote.
TEST(MeshIo, AFrameFarFromTheOriginReadsBackBitForBit) {
  const fs::path dir = drape::testing::temp_root("mesh_io_far");
  fs::remove_all(dir);
  const Model model = build_model(parse_scene(
      R"({"frames": 1, "cloths": [{"grid": {"size": [1, 1], "resolution": [7, 5]},
          "transform": {"translate": [1000000.123456789, -999999.987654321, 1000000.5], "rotate": [17, 1, 2, 3]}}]})",
      dir / "far.json"));
  RunSettings settings;
  settings.out = dir / "out";
  settings.frames = 1;
  const std::atomic<bool> interrupt{false};
  const RunOutcome outcome = run_simulation(model, settings, interrupt, nullptr);
  ASSERT_EQ(outcome.end, RunEnd::Completed) << outcome.message;
  const TriangleMesh topology = model.cloth_mesh(model.initial_positions);
  const std::vector<Vec3> frame0 = load_frame_positions(mesh_path(settings.out, 0, "obj"), topology);
  ASSERT_EQ(frame0.size(), model.initial_positions.size());
  for (std::size_t v = 0; v < frame0.size(); ++v)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(frame0[v][k], model.initial_positions[v][k]) << "vertex " << v;
  // Frame 1 moved under gravity by far less than single precision's step there.
  const std::vector<Vec3> frame1 = load_frame_positions(mesh_path(settings.out, 1, "obj"), topology);
  const Scalar fall = model.initial_positions[0].z() - frame1[0].z();
  EXPECT_GT(fall, 0.001);  // about 5 mm: g (1/30 s)^2 / 2
  EXPECT_LT(fall, 0.0625);
  fs::remove_all(dir);
}
