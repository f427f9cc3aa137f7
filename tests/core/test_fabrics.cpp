// The fabric presets (fabrics.h): the measured hinge constant's conversion to a bending
// rigidity, one fabric's conversion worked by hand, and the scene's `preset` key.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>

#include "drape/core/fabrics.h"
#include "drape/core/model.h"

using namespace drape;

namespace {

Model model_of(const std::string& json) { return build_model(parse_scene(json, "inline.json")); }

// A scene that building refuses, with the JSON path and the expectation in its message.
void expect_refused(const std::string& scene, const std::string& path, const std::string& expected) {
  try {
    model_of(scene);
    ADD_FAILURE() << "no error for " << scene;
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find(expected), std::string::npos) << what;
  }
}

// The simulator's hinge energy (fabrics.h: ke l^2 theta^2 / (8 (A0 + A1)), ke = 1) of a patch
// of equilateral triangles with edges of `edge` m bent onto a cylinder of radius `radius` across
// the direction at `angle` to the rows, per square metre of its interior edges' share of the
// sheet (two thirds of a triangle each).
Scalar hinge_energy_per_area(Scalar angle, Scalar edge, Scalar radius) {
  const int n = 30;
  const Scalar row = edge * std::sqrt(3.0) / 2;
  std::vector<Vec3> x;  // vertex (i, j) at i + n j, bent onto the cylinder
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Scalar px = i * edge + (j % 2) * edge / 2, py = j * row;
      const Scalar u = std::cos(angle) * px + std::sin(angle) * py, v = -std::sin(angle) * px + std::cos(angle) * py;
      x.emplace_back(radius * std::sin(u / radius), v, radius * (1 - std::cos(u / radius)));
    }
  const auto at = [&](int i, int j) { return i + n * j; };
  std::vector<Triangle> triangles;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i)
      if (j % 2 == 0) {
        triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      } else {
        triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      }
  // Interior edges: those two triangles share.
  std::map<std::pair<int, int>, std::vector<std::size_t>> edges;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles[t][std::size_t(k)], b = triangles[t][std::size_t((k + 1) % 3)];
      edges[{std::min(a, b), std::max(a, b)}].push_back(t);
    }
  Scalar energy = 0;
  int interior = 0;
  for (const auto& [ends, pair] : edges) {
    if (pair.size() != 2) continue;
    Vec3 normal[2];
    Scalar area = 0;
    for (int s = 0; s < 2; ++s) {
      const Triangle& t = triangles[pair[std::size_t(s)]];
      const Vec3 cross = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
      area += cross.norm() / 2, normal[s] = cross.normalized();
    }
    const Scalar theta = std::acos(std::clamp(normal[0].dot(normal[1]), Scalar(-1), Scalar(1)));
    const Scalar length = (x[std::size_t(ends.first)] - x[std::size_t(ends.second)]).norm();
    energy += length * length * theta * theta / (8 * area), ++interior;
  }
  return energy / (interior * std::sqrt(3.0) / 6 * edge * edge);
}

}  // namespace

TEST(Fabric, TheMeasuredHingeConstantIsFourTimesTheRigidity) {
  // Bent across every direction, the hinges store B kappa^2 / 2 with B = ke / 4, to the
  // patch's discretisation (1 cm edges on a 0.5 m cylinder).
  const Scalar radius = 0.5;
  for (const Scalar angle : {0.0, 0.3, M_PI / 6, M_PI / 4, M_PI / 2}) {
    const Scalar rigidity = 2 * hinge_energy_per_area(angle, 0.01, radius) * radius * radius;
    EXPECT_NEAR(rigidity / HINGE_CONSTANT_TO_RIGIDITY, 1, 0.02) << "angle " << angle;
  }
}

TEST(Fabric, TheDenimPresetIsItsMeasurementsConverted) {
  // Worked by hand from the data file's numbers: C11 = 2 x 205.352005, C12 = 2 x 10.234077,
  // C22 = 2 x 1013.88629; T_u = C11 - C12^2 / C22 = 410.4974, T_v = C22 - C12^2 / C11 = 2026.7525.
  const MeasuredFabric* denim = find_measured_fabric("11oz-black-denim");
  ASSERT_NE(denim, nullptr);
  const FabricPreset p = fabric_preset(*denim);
  EXPECT_NEAR(p.density, 0.324, 1e-12);
  EXPECT_NEAR(p.tensile_stiffness, (410.4974 + 2026.7525) / 2, 1e-3);
  EXPECT_NEAR(p.shear_stiffness, 53.387184, 1e-9);
  EXPECT_NEAR(p.bending_rigidity, (64.196457e-6 + 73.384567e-6 + 96.951576e-6) / 12, 1e-15);
  // A negative coupling is clamped to zero, as the simulator does: then T_u = C11 and T_v = C22.
  const FabricPreset knit = fabric_preset(*find_measured_fabric("navy-sparkle-sweat"));
  EXPECT_NEAR(knit.tensile_stiffness, (2 * 12.486332 + 2 * 3.272434) / 2, 1e-9);
  EXPECT_EQ(find_measured_fabric("silk"), nullptr);
  for (const MeasuredFabric& f : measured_fabrics()) {
    const FabricPreset q = fabric_preset(f);
    EXPECT_GT(q.tensile_stiffness, 0) << f.name;
    EXPECT_GT(q.shear_stiffness, 0) << f.name;
    EXPECT_GT(q.bending_rigidity, 0) << f.name;
  }
}

TEST(Fabric, APresetSetsTheFabricsKeysAndOthersOverrideIt) {
  const FabricPreset denim = fabric_preset(*find_measured_fabric("11oz-black-denim"));
  const Model grid = model_of(R"({"cloths": [{"grid": {}, "material": {"preset": "11oz-black-denim"}}]})");
  const Material& m = grid.scene.cloths[0].material;
  EXPECT_EQ(m.density, denim.density);
  EXPECT_EQ(m.tensile_stiffness, denim.tensile_stiffness);
  EXPECT_EQ(m.shear_stiffness, denim.shear_stiffness);
  EXPECT_EQ(m.bending_rigidity, denim.bending_rigidity);
  EXPECT_EQ(m.bend, 0);
  EXPECT_FALSE(grid.hinges.empty());
  const Model changed = model_of(
      R"({"cloths": [{"grid": {}, "material": {"preset": "11oz-black-denim", "mass_per_area": 300, "strain_limit": 1.1}}]})");
  EXPECT_NEAR(changed.scene.cloths[0].material.density, 0.3, 1e-12);
  EXPECT_EQ(changed.scene.cloths[0].material.strain_limit, 1.1);
  EXPECT_EQ(changed.scene.cloths[0].material.bending_rigidity, denim.bending_rigidity);
}

TEST(Fabric, AnUnknownPresetOrASpringKeyBesideOneIsRefused) {
  try {
    model_of(R"({"cloths": [{"grid": {}, "material": {"preset": "silk"}}]})");
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("inline.json"), std::string::npos) << what;
    EXPECT_NE(what.find("/cloths/0/material/preset"), std::string::npos) << what;
    EXPECT_NE(what.find("expected a fabric preset: one of 11oz-black-denim, royal-target"), std::string::npos) << what;
  }
  try {
    model_of(R"({"cloths": [{"grid": {}, "material": {"preset": "royal-target", "bend": 1}}]})");
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("expected no 'bend' beside a 'preset'"), std::string::npos) << e.what();
  }
}

// A shear locking angle limits a grid's diagonals to the length they reach at that angle with
// the cell's sides at the strain limit: a 2:1 cell at 30 degrees and 1.05,
// 1.05 sqrt(1 + 2 * 2 * 1 * 0.5 / 5) = 1.05 sqrt(1.4). The structural springs keep the strain
// limit; a mesh cloth (no shear springs), a missing strain limit and an angle out of range are
// refused where they are written.
TEST(Fabric, AShearLockingAngleLimitsAGridsDiagonals) {
  const Model model = model_of(R"({"cloths": [{"grid": {"size": [2, 1], "resolution": [4, 4]},
      "material": {"preset": "royal-target", "strain_limit": 1.05, "shear_locking_angle": 30}}]})");
  int diagonals = 0;
  for (const Spring& s : model.springs) {
    if (s.kind == SpringKind::Shear) {
      EXPECT_NEAR(s.limit, 1.05 * std::sqrt(1.4), 1e-12);
      ++diagonals;
    }
    if (s.kind == SpringKind::Stretch) {
      EXPECT_EQ(s.limit, 1.05);
    }
  }
  EXPECT_EQ(diagonals, 2 * 4 * 4);
  const auto refused = [](const std::string& cloth, const std::string& expected) {
    expect_refused(R"({"cloths": [)" + cloth + "]}", "/cloths/0/material/shear_locking_angle", expected);
  };
  refused(R"({"grid": {}, "material": {"strain_limit": 1.1, "shear_locking_angle": 90}})", "at most 89 degrees");
  refused(R"({"grid": {}, "material": {"shear_locking_angle": 30}})", "expected a 'strain_limit' beside it");
  refused(R"({"mesh": ")" + std::string(DRAPE_SOURCE_DIR) +
              R"(/scenes/meshes/disc_30cm_12mm.obj", "material": {"strain_limit": 1.1, "shear_locking_angle": 30}})",
          "a mesh cloth has no shear springs");
}

// A material's `compression` reaches every spring of its cloth (the bending springs too), and
// is refused out of [0, 1] or with the projective solver, whose springs are fixed-weight
// constraints, where it is written.
TEST(Fabric, ACompressionReachesEverySpringAndIsRefusedWhereItCannotHold) {
  const Model model = model_of(R"({"cloths": [{"grid": {"resolution": [4, 4]}, "material": {"compression": 0.1}},
                                             {"grid": {"resolution": [2, 2]}}]})");
  for (const Spring& s : model.springs)
    EXPECT_EQ(s.compression, s.i < model.cloths[1].first_vertex ? 0.1 : 1.0) << int(s.kind);
  const auto refused = [](const std::string& scene, const std::string& expected) {
    expect_refused(scene, "/cloths/0/material/compression", expected);
  };
  refused(R"({"cloths": [{"grid": {}, "material": {"compression": 1.5}}]})", "from 0 to 1");
  refused(R"({"cloths": [{"grid": {}, "material": {"compression": 0.1}}], "solver": {"type": "projective"}})",
          "expected the cholmod or cg solver");
}
