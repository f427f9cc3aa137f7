// The bending model (Model::hinges, material `bending_rigidity`): its calibration on a
// cylinder, on a mesh's triangles, a grid's in every direction and against its checkerboard,
// its indifference to rigid motions and in-plane affine maps, its Jacobians, the two solvers' agreement on it, and the cantilever test (Peirce; ASTM
// D1388) against the heavy elastica solved numerically (core/textile.h; checked in test_textile.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <set>
#include <sstream>

#include "drape/core/integrator.h"
#include "drape/core/textile.h"
#include "../temp_root.h"

using namespace drape;

namespace {

Model model_of(const std::string& json) { return build_model(parse_scene(json, "inline.json")); }

// A grid cloth of size x by y with n x m quads and bending rigidity B, lying in z = 0 with
// its corner at the origin.
Model strip(Scalar x, Scalar y, int n, int m, Scalar rigidity) {
  std::ostringstream json;
  json.precision(17);
  json << R"({"cloths": [{"grid": {"size": [)" << x << ", " << y << R"(], "resolution": [)" << n << ", " << m
       << R"(]}, "transform": {"translate": [)" << x / 2 << ", " << y / 2 << R"(, 0]},
       "material": {"bending_rigidity": )" << rigidity << "}}]}";
  return model_of(json.str());
}

// The bending energy at positions x of the stencils whose corners all rest within `inner` of
// `centre` along x and y (a window away from the border).
Scalar window_energy(const Model& model, const std::vector<Vec3>& x, const Vec3& centre, Scalar inner) {
  Scalar e = 0;
  for (const Hinge& hinge : model.hinges) {
    bool inside = true;
    for (int v : hinge.v)
      inside = inside && (model.initial_positions[std::size_t(v)] - centre).cwiseAbs().maxCoeff() < inner;
    if (inside) e += 0.5 * hinge_vector(hinge, x).squaredNorm();
  }
  return e;
}

Scalar bending_energy(const Model& model, const std::vector<Vec3>& x) {
  Scalar e = 0;
  for (const Hinge& hinge : model.hinges) e += 0.5 * hinge_vector(hinge, x).squaredNorm();
  return e;
}


// The cantilever test on a strip overhanging its clamp by `overhang` with bending length c
// ((B / w)^(1/3), w its weight per area): the mean tip drop after it settles, with `quads`
// quads along the overhang (NaN, with a failure, if a step fails). Its tensile stiffness is a
// fabric's, 5000 N/m, its shear a tenth of it: far stiffer in the plane, the linearised solve
// crept towards rest for seconds (rotations stretch stiff springs to first order), and the
// strip had not settled.
Scalar cantilever_drop(Scalar overhang, Scalar bending_length, int quads, const std::string& solver) {
  const Scalar density = 0.2, g = 9.81, width = overhang / 4;
  const Scalar rigidity = density * g * std::pow(bending_length, 3);
  const Scalar a = overhang / quads;  // the clamp holds one column of quads behind x = 0
  const Scalar tensile = 5000;         // N/m, and a tenth of it in shear
  std::ostringstream json;
  json.precision(17);
  json << R"({"frame_time": 0.05, "frame_steps": 10, "frames": 60,
    "cloths": [{"grid": {"size": [)" << overhang + a << ", " << width << R"(], "resolution": [)" << quads + 1 << ", "
       << std::max(2, quads / 4) << R"(]}, "transform": {"translate": [)" << (overhang - a) / 2 << R"(, 0, 0]},
       "material": {"density": )" << density << R"(, "tensile_stiffness": )" << tensile << R"(, "shear_stiffness": )" << tensile / 10
       << R"(, "bending_rigidity": )" << rigidity
       << R"(, "air_damping": 8}}],
    "handles": [{"box": {"min": [-1, -1, -1], "max": [)" << 1e-9 << R"(, 1, 1]}}],
    "gravity": [0, 0, )" << -g << R"(], "solver": )" << solver << "}";
  const Model model = model_of(json.str());
  State state = initial_state(model);
  Integrator integrator(model);
  const int steps = model.scene.frames * model.scene.frame_steps;
  for (int k = 0; k < steps; ++k)
    if (const StepReport r = integrator.step(state); !r.ok) {
      ADD_FAILURE() << "step " << k << ": " << r.failure;
      return std::nan("");
    }
  // The tip: the vertices of the last column.
  Scalar drop = 0;
  int count = 0;
  for (std::size_t v = 0; v < state.positions.size(); ++v)
    if (model.initial_positions[v].x() > overhang - 1e-9) drop -= state.positions[v].z(), ++count;
  return drop / count;
}

}  // namespace

TEST(Bending, ACylinderStoresHalfTheRigidityTimesItsCurvatureSquared) {
  // A 20 x 5 cm strip wrapped around a cylinder of radius R about either axis: B / (2 R^2) a
  // square metre, over the strip less the half quads at its two bent ends (which no hinge
  // spans), to 0.5 %.
  const Scalar B = 2e-5, R = 0.1;
  for (int n : {16, 32}) {
    const Model model = strip(0.2, 0.05, n, n / 4, B);
    std::vector<Vec3> along_x, along_y;
    for (const Vec3& p : model.initial_positions) {
      along_x.emplace_back(R * std::sin(p.x() / R), p.y(), R - R * std::cos(p.x() / R));
      along_y.emplace_back(p.x(), R * std::sin(p.y() / R), R - R * std::cos(p.y() / R));
    }
    const Scalar ax = 0.2 / n, ay = 0.05 / (n / 4);
    EXPECT_NEAR(bending_energy(model, along_x), B / (2 * R * R) * (0.2 - ax) * 0.05, 0.005 * B / (2 * R * R) * 0.01) << n;
    EXPECT_NEAR(bending_energy(model, along_y), B / (2 * R * R) * 0.2 * (0.05 - ay), 0.005 * B / (2 * R * R) * 0.01) << n;
  }
}

TEST(Bending, AMeshsHingesStoreHalfTheRigidityTimesTheCurvatureSquared) {
  // The Cusick scene's discs (rings 12.5, 6 and 3 mm apart, tools/make_meshes.py) wrapped
  // around a cylinder of radius R = 0.3 m along three directions: the hinges within 10 cm of
  // the centre store B / (2 R^2) times a third of their triangles' areas, to 3 % (the coarsest
  // disc's directions spread by 2.4 %). Without the hinges' calibration (model.cpp) they
  // stored 1.30-1.34 times it at 12.5 mm and 1.20 at 6 mm.
  const Scalar B = 1e-5, R = 0.3;
  for (const char* disc : {"disc_30cm_12mm.obj", "disc_30cm.obj", "disc_30cm_3mm.obj"}) {
    const std::string mesh = std::string(DRAPE_SOURCE_DIR) + "/scenes/meshes/" + disc;
    const Model model =
        model_of(R"({"cloths": [{"mesh": ")" + mesh + R"(", "material": {"bending_rigidity": )" + std::to_string(B) + "}}]}");
    ASSERT_FALSE(model.hinges.empty());
    const auto& x0 = model.initial_positions;
    for (const Scalar phi : {0.0, 1.0, 2.0}) {
      const Vec3 across(std::cos(phi), std::sin(phi), 0), along(-std::sin(phi), std::cos(phi), 0);
      std::vector<Vec3> x;
      for (const Vec3& p : x0) {
        const Scalar s = p.dot(across), t = p.dot(along);
        x.push_back(R * std::sin(s / R) * across + t * along + Vec3(0, 0, R - R * std::cos(s / R)));
      }
      Scalar energy = 0, area = 0;
      for (const Hinge& hinge : model.hinges) {
        bool inside = true;
        for (int v : hinge.v) inside = inside && x0[std::size_t(v)].norm() < 0.1;
        if (!inside) continue;
        const Vec3 &a = x0[std::size_t(hinge.v[0])], &b = x0[std::size_t(hinge.v[1])];
        const Vec3 &c = x0[std::size_t(hinge.v[2])], &d = x0[std::size_t(hinge.v[3])];
        area += ((b - a).cross(c - a).norm() + (b - a).cross(d - a).norm()) / 6;  // a third of each triangle
        energy += 0.5 * hinge_vector(hinge, x).squaredNorm();
      }
      EXPECT_NEAR(energy / (B / (2 * R * R) * area), 1, 0.03) << disc << ", direction " << phi;
    }
  }
}

TEST(Bending, AGridBendsAlikeInEveryDirection) {
  // A 30 x 30 cm sheet of 30 x 30 quads wrapped around a cylinder (R = 0.2 m), bent along a
  // direction at an angle phi to the grid's x axis: the stencils away from the border (all
  // four corners 3 quads in) store what they store at phi = 0, to 1 %, at 22.5, 45 and 90
  // degrees. (The hinges of its right triangles, with a tenth of the rigidity on the
  // diagonals, stored 1 + 0.1 sin^2 2 phi times as much.)
  const Scalar R = 0.2, half = 0.15, inner = half - 3 * 0.01 - 1e-9;
  const Model model = strip(0.3, 0.3, 30, 30, 1e-5);
  const auto interior_energy = [&](Scalar phi) {
    const Vec3 centre(half, half, 0);
    const Vec3 across(std::cos(phi), std::sin(phi), 0), along(-std::sin(phi), std::cos(phi), 0);
    std::vector<Vec3> x;
    for (const Vec3& p : model.initial_positions) {
      const Scalar s = (p - centre).dot(across), t = (p - centre).dot(along);
      x.push_back(centre + R * std::sin(s / R) * across + t * along + Vec3(0, 0, R - R * std::cos(s / R)));
    }
    return window_energy(model, x, centre, inner);
  };
  const Scalar straight = interior_energy(0);
  ASSERT_GT(straight, 0);
  for (const Scalar degrees : {22.5, 45.0, 90.0})
    EXPECT_NEAR(interior_energy(degrees * M_PI / 180) / straight, 1, 0.01) << degrees << " degrees";
}

// A mesh cloth laid out on a grid's lattice (every triangle half of a cell: a grid exported
// as a mesh, the Cusick discs of half cells) bends as the grid does (lattice_bending.h), where
// its hinges bent half as stiffly along the cells' sides as along their diagonals: the
// half-cell discs wrapped around a cylinder (R = 0.3 m) stored 0.67, 1.22 and 1.05 times the
// fabric's energy bent at 0, 1 and 2 radians to the warp.
TEST(Bending, AMeshOnAGridsLatticeBendsAsTheGrid) {
  // A 0.3 x 0.2 m grid of 12 x 8 quads written as a mesh, its vertices in the grid's order:
  // the same stencils' energy as the grid cloth's at random positions, to rounding.
  const std::filesystem::path dir = drape::testing::temp_root("lattice_bending_test");
  std::filesystem::create_directories(dir);
  const int n = 12, m = 8;
  const Model grid = strip(0.3, 0.2, n, m, 1e-5);
  ASSERT_EQ(grid.triangles.size(), std::size_t(2 * n * m));
  {
    std::ofstream obj(dir / "grid.obj");
    obj.precision(17);
    for (const Vec3& p : grid.initial_positions) obj << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const Triangle& t : grid.triangles) obj << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  }
  const Model mesh = model_of(R"({"cloths": [{"mesh": ")" + (dir / "grid.obj").string() + R"(", "material": {"bending_rigidity": 1e-5}}]})");
  ASSERT_EQ(mesh.vertex_count(), grid.vertex_count());
  EXPECT_EQ(mesh.hinges.size(), grid.hinges.size());
  std::mt19937 random(7);
  std::uniform_real_distribution<Scalar> jitter(-0.01, 0.01);
  std::vector<Vec3> x, mesh_x(mesh.vertex_count());
  for (const Vec3& p : grid.initial_positions) x.push_back(p + Vec3(jitter(random), jitter(random), jitter(random)));
  // The reader may renumber the vertices: each mesh vertex takes the grid vertex at its place.
  for (std::size_t v = 0; v < mesh_x.size(); ++v) {
    std::size_t nearest = 0;
    for (std::size_t g = 1; g < x.size(); ++g)
      if ((grid.initial_positions[g] - mesh.initial_positions[v]).norm() <
          (grid.initial_positions[nearest] - mesh.initial_positions[v]).norm())
        nearest = g;
    ASSERT_LT((grid.initial_positions[nearest] - mesh.initial_positions[v]).norm(), 1e-6);
    mesh_x[v] = x[nearest];
  }
  EXPECT_NEAR(bending_energy(mesh, mesh_x) / bending_energy(grid, x), 1, 1e-6);
  // The same at 3.9 mm cells written with six decimals, as Blender writes OBJ files (each
  // coordinate off by up to 5e-7 m; with the first tolerances, 1e-4 of a cell, it got hinges):
  // still the grid's stencils, as many as the grid's.
  {
    const Model fine = strip(0.24, 0.16, 61, 41, 1e-5);
    std::ofstream obj(dir / "six_decimals.obj");
    obj << std::fixed << std::setprecision(6);
    for (const Vec3& p : fine.initial_positions) obj << "v " << p.x() + 0.1234567 << " " << p.y() - 0.7654321 << " " << p.z() << "\n";
    for (const Triangle& t : fine.triangles) obj << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    obj.close();
    const Model read = model_of(R"({"cloths": [{"mesh": ")" + (dir / "six_decimals.obj").string() +
                                R"(", "material": {"bending_rigidity": 1e-5}}]})");
    const auto stencils = [](const Model& m) {
      return std::count_if(m.hinges.begin(), m.hinges.end(), [](const Hinge& h) { return h.v[1] == h.v[3]; });
    };
    EXPECT_GT(stencils(fine), 0);
    EXPECT_EQ(stencils(read), stencils(fine));
    EXPECT_EQ(read.hinges.size(), fine.hinges.size());
  }

  // The Cusick discs of half cells at three resolutions, and one turned 30 degrees against
  // its axes, wrapped around a cylinder along three directions: the stencils within 10 cm of
  // the centre store the same energy in each direction, to 1 %.
  const Scalar B = 1e-5, R = 0.3;
  for (const char* disc : {"disc_30cm_cells_12mm.obj", "disc_30cm_cells.obj", "disc_30cm_cells_3mm.obj",
                           "disc_30cm_cells_turned30.obj"}) {
    const std::string path = std::string(DRAPE_SOURCE_DIR) + "/scenes/meshes/" + disc;
    const Model model = model_of(R"({"cloths": [{"mesh": ")" + path + R"(", "material": {"bending_rigidity": )" +
                                 std::to_string(B) + "}}]}");
    const auto wrapped_energy = [&](Scalar phi) {
      const Vec3 across(std::cos(phi), std::sin(phi), 0), along(-std::sin(phi), std::cos(phi), 0);
      std::vector<Vec3> wrapped;
      for (const Vec3& p : model.initial_positions) {
        const Scalar s = p.dot(across), t = p.dot(along);
        wrapped.push_back(R * std::sin(s / R) * across + t * along + Vec3(0, 0, R - R * std::cos(s / R)));
      }
      Scalar e = 0;
      for (const Hinge& hinge : model.hinges) {
        bool inside = true;
        for (int v : hinge.v) inside = inside && model.initial_positions[std::size_t(v)].norm() < 0.1;
        if (inside) e += 0.5 * hinge_vector(hinge, wrapped).squaredNorm();
      }
      return e;
    };
    const Scalar straight = wrapped_energy(0);
    ASSERT_GT(straight, 0) << disc;
    for (const Scalar phi : {0.5, 1.0, 2.0}) EXPECT_NEAR(wrapped_energy(phi) / straight, 1, 0.01) << disc << ", " << phi;
  }
}

// The lattice's stencils join only what the mesh joins: around a hole of two missing cells no
// second difference crosses the hole and no twist covers a missing cell; a vertex moved off
// its lattice point by a hundredth of a cell makes the mesh a general one (hinges), while a
// millionth is rounding.
TEST(Bending, ALatticesStencilsFollowTheMeshAndAVertexOffItGivesHinges) {
  const std::filesystem::path dir = drape::testing::temp_root("lattice_hole_test");
  std::filesystem::create_directories(dir);
  const int n = 6;
  const Scalar a = 0.01;
  const auto write = [&](const std::string& name, Scalar moved) {
    std::ofstream obj(dir / name);
    obj.precision(17);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) obj << "v " << a * i + (i == 4 && j == 4 ? moved : 0) << " " << a * j << " 0\n";
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (j == 2 && (i == 2 || i == 3)) continue;  // the hole: cells (2, 2) and (3, 2)
        const int v00 = j * (n + 1) + i + 1, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
        obj << "f " << v00 << " " << v10 << " " << v11 << "\nf " << v00 << " " << v11 << " " << v01 << "\n";
      }
    obj.close();
    return model_of(R"({"cloths": [{"mesh": ")" + (dir / name).string() + R"(", "material": {"bending_rigidity": 1e-5}}]})");
  };
  const auto is_second_difference = [](const Hinge& h) { return h.v[1] == h.v[3]; };
  const Model holed = write("hole.obj", 0);
  std::set<std::pair<int, int>> edges;
  for (const Triangle& t : holed.triangles)
    for (int k = 0; k < 3; ++k) edges.insert(std::minmax(t[std::size_t(k)], t[std::size_t((k + 1) % 3)]));
  int second_differences = 0, twists = 0;
  for (const Hinge& h : holed.hinges) {
    if (is_second_difference(h)) {
      ++second_differences;
      EXPECT_TRUE(edges.count(std::minmax(h.v[0], h.v[1])) && edges.count(std::minmax(h.v[1], h.v[2])));
    } else {
      ++twists;
      for (int k = 0; k < 4; ++k)
        for (int l = k + 1; l < 4; ++l)
          if ((k == 0 && l == 3) || (k == 1 && l == 2)) continue;  // the cell's diagonals
          else EXPECT_TRUE(edges.count(std::minmax(h.v[std::size_t(k)], h.v[std::size_t(l)]))) << k << l;
    }
  }
  // 7 rows and 7 columns of 5 interior points each; the hole takes one edge, the one between
  // its two cells ((3, 2) to (3, 3): the others border cells that are there), and with it the
  // second differences about its two ends along column 3. Twists: 36 - 2 cells.
  EXPECT_EQ(second_differences, 2 * 7 * 5 - 2);
  EXPECT_EQ(twists, 34);
  const Model rounded = write("rounded.obj", 1e-6 * a);
  EXPECT_TRUE(std::any_of(rounded.hinges.begin(), rounded.hinges.end(), is_second_difference));
  const Model off = write("off.obj", 0.01 * a);
  EXPECT_FALSE(off.hinges.empty());
  EXPECT_FALSE(std::any_of(off.hinges.begin(), off.hinges.end(), is_second_difference));
}

TEST(Bending, AGridResistsTheCheckerboardFourTimesAsMuchAsStripes) {
  // Vertices of a 20 x 20 grid moved up and down by w: the checkerboard z = w (-1)^(i+j)
  // against stripes z = w (-1)^i along either axis. The continuum's bending energy grows with
  // the wavenumber to the fourth: the checkerboard's is sqrt(2) times the stripes', so four
  // times their energy. Counted over the stencils away from the border, to 1 %. (The hinges
  // of both of a grid's triangulations gave the checkerboard 0.43 times the stripes' energy:
  // none from the axis edges, a tenth of the rigidity on the diagonals.)
  const Scalar w = 1e-3, half = 0.1, inner = half - 2 * 0.01 - 1e-9;
  const Model model = strip(0.2, 0.2, 20, 20, 1e-5);
  const Vec3 centre(half, half, 0);
  const auto interior_energy = [&](auto height) {
    std::vector<Vec3> x;
    for (const Vec3& p : model.initial_positions) {
      const int i = int(std::lround(p.x() / 0.01)), j = int(std::lround(p.y() / 0.01));
      x.push_back(p + Vec3(0, 0, height(i, j)));
    }
    return window_energy(model, x, centre, inner);
  };
  const auto sign = [](int k) { return k % 2 == 0 ? 1.0 : -1.0; };
  const Scalar checkerboard = interior_energy([&](int i, int j) { return w * sign(i + j); });
  const Scalar rows = interior_energy([&](int i, int) { return w * sign(i); });
  const Scalar columns = interior_energy([&](int, int j) { return w * sign(j); });
  ASSERT_GT(rows, 0);
  EXPECT_NEAR(columns / rows, 1, 0.05);
  EXPECT_NEAR(checkerboard / rows, 4, 0.04);
}

TEST(Bending, RigidMotionsAndInPlaneAffineMapsStoreNothing) {
  // Compressed to 70 % along x, stretched 10 % along y, sheared, then turned and moved: no
  // bending energy (against a gentle bend's, R = 1 m, for scale).
  const Model model = strip(0.2, 0.2, 12, 12, 1e-5);
  ASSERT_FALSE(model.hinges.empty());
  const Eigen::AngleAxis<Scalar> turn(0.7, Vec3(1, 2, 3).normalized());
  std::vector<Vec3> mapped, bent;
  for (const Vec3& p : model.initial_positions) {
    mapped.push_back(turn * Vec3(0.7 * p.x() + 0.2 * p.y(), 1.1 * p.y(), 0) + Vec3(0.3, -2, 5));
    bent.emplace_back(std::sin(p.x()), p.y(), 1 - std::cos(p.x()));
  }
  EXPECT_LT(bending_energy(model, mapped), 1e-12 * bending_energy(model, bent));
  // The bending springs are gone: the hinges are the cloth's only bending model.
  for (const Spring& s : model.springs) EXPECT_NE(s.kind, SpringKind::Bend);
}

TEST(Bending, BothBendingModelsInOneMaterialAreRefused) {
  EXPECT_THROW(model_of(R"({"cloths": [{"grid": {}, "material": {"bend": 1, "bending_rigidity": 1e-5}}]})"),
               std::runtime_error);
}

TEST(Bending, ACantileverDropsAsTheHeavyElastica) {
  // The cantilever test: a strip overhanging its clamp by 6 cm, bending lengths c of 1, 3 and
  // 6 cm (hanging nearly straight down; about where the standard's 41.5-degree line meets the
  // tip; a gentle bend): the settled tip's drop within 3 % of the elastica's at three
  // resolutions, with the reference solver. The row stencil centred on the last pinned column
  // bends over its vertex's whole cell, half of which lies behind that column: the strip is
  // clamped half a quad behind it, and the elastica is solved for that length (without it, at 2c, the drop
  // is 14 % too large at 8 quads and 3.6 % at 32, halving with the quad).
  for (const Scalar c : {0.01, 0.03, 0.06}) {
    const Scalar overhang = 0.06;
    for (int quads : {8, 16, 32}) {
      const Scalar expected = heavy_elastica_drop(overhang + 0.5 * overhang / quads, 1 / std::pow(c, 3));
      const Scalar drop = cantilever_drop(overhang, c, quads, R"({"type": "cholmod"})");
      EXPECT_NEAR(drop / expected, 1, 0.03) << "c " << c << ", " << quads << " quads: " << drop << " m, elastica " << expected;
    }
  }
}

TEST(Bending, HingeJacobiansMatchFiniteDifferences) {
  // Each hinge force's Jacobians are -k_i k_j I and -damping k_i k_j I, by central
  // differences at a perturbed state (its forces against potential_energy's gradient:
  // ModelForces in test_forces.cpp): a grid's first stencil (a row's second difference) and
  // last (a cell's twist), and a mesh's last hinge.
  const Model model = model_of(R"({"cloths": [{"grid": {"size": [1, 1], "resolution": [4, 3]},
    "material": {"bending_rigidity": 0.01, "damping": 0.003}}, {"mesh": ")" + std::string(DRAPE_SOURCE_DIR) +
                               R"(/scenes/meshes/disc_30cm_12mm.obj", "transform": {"translate": [0, 0, 2]},
    "material": {"bending_rigidity": 0.01, "damping": 0.003}}], "gravity": [0, 0, 0]})");
  const int grid_vertices = 5 * 4;
  const auto last_of_grid = std::find_if(model.hinges.rbegin(), model.hinges.rend(),
                                         [&](const Hinge& h) { return h.v[0] < grid_vertices; });
  ASSERT_NE(last_of_grid, model.hinges.rend());
  ASSERT_GE(model.hinges.back().v[0], grid_vertices);
  const Scalar step = 1e-6;
  State state = initial_state(model);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<Scalar> u(-0.05, 0.05);
  for (Vec3& x : state.positions) x += Vec3(u(rng), u(rng), u(rng));
  for (Vec3& v : state.velocities) v = Vec3(u(rng), u(rng), u(rng));
  for (const Hinge& hinge : {model.hinges.front(), *last_of_grid, model.hinges.back()})
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = 0; j < 4; ++j)
        for (int c = 0; c < 3; ++c) {
          std::vector<Vec3> x_plus = state.positions, x_minus = state.positions, v_plus = state.velocities,
                            v_minus = state.velocities;
          x_plus[std::size_t(hinge.v[j])][c] += step;
          x_minus[std::size_t(hinge.v[j])][c] -= step;
          v_plus[std::size_t(hinge.v[j])][c] += step;
          v_minus[std::size_t(hinge.v[j])][c] -= step;
          const Vec3 by_x = (hinge_force(hinge, i, x_plus, state.velocities) - hinge_force(hinge, i, x_minus, state.velocities)) / (2 * step);
          const Vec3 by_v = (hinge_force(hinge, i, state.positions, v_plus) - hinge_force(hinge, i, state.positions, v_minus)) / (2 * step);
          Scalar k_j = 0;  // every corner at vertex v[j] (a grid's three-point stencils repeat one, weight 0)
          for (std::size_t l = 0; l < 4; ++l)
            if (hinge.v[l] == hinge.v[j]) k_j += hinge.k[l];
          const Vec3 expected = -hinge.k[i] * k_j * Vec3::Unit(c);
          EXPECT_LT((by_x - expected).norm(), 1e-6 * (1 + expected.norm()));
          EXPECT_LT((by_v - hinge.damping * expected).norm(), 1e-6 * (1 + expected.norm()));
        }
}

TEST(Bending, BothSolversTakeTheSameStepWithHingesAlone) {
  // A cloth held only by its hinges (no springs), its top corners scripted to move: its
  // forces are linear, so the reference's linearised backward Euler step is backward Euler
  // itself, and the projective solver's objective is the quadratic its factorised matrix
  // holds exactly. Two implementations of the hinges (the reference's blocks, forces,
  // stiffness times v and coupling to the moving corners; the projective one's matrix,
  // gradient and right-hand side) must take the same steps: to 1e-9 of the motion.
  const std::string scene = R"({"frame_time": 0.04, "frame_steps": 4,
    "cloths": [{"grid": {"size": [0.4, 0.4], "resolution": [8, 8]}, "velocity": [0.3, -0.2, 0.5],
      "material": {"stretch": 0, "shear": 0, "bending_rigidity": 0.001, "damping": 0.01}}],
    "handles": [{"corners": ["top-left", "top-right"], "motion": {"velocity": [0.1, 0, 0.2], "angular_velocity": [1, 0, 2]}}],
    "solver": )";
  std::vector<State> ends;
  for (const char* solver : {R"({"type": "cholmod"})", R"({"type": "projective", "iterations": 5})",
                             R"({"type": "projective", "iterations": 200, "history": 0})"}) {
    const Model model = model_of(scene + solver + "}");
    State state = initial_state(model);
    Integrator integrator(model);
    for (int k = 0; k < 6; ++k) ASSERT_TRUE(integrator.step(state).ok) << solver;
    ends.push_back(state);
  }
  const Model model = model_of(scene + R"({"type": "cholmod"})" + "}");
  Scalar moved = 0;
  for (std::size_t v = 0; v < model.vertex_count(); ++v) moved = std::max(moved, (ends[0].positions[v] - model.initial_positions[v]).norm());
  for (std::size_t k = 1; k < ends.size(); ++k)
    for (std::size_t v = 0; v < model.vertex_count(); ++v)
      EXPECT_LT((ends[k].positions[v] - ends[0].positions[v]).norm(), 1e-9 * moved) << "solver " << k << ", vertex " << v;
}
