// Numerical stability at the extremes (issue: stiffness 1 to 1e9, masses 1e-6 to 1e3 per
// vertex, 1 to 100 steps per frame, triangles 1e-5 to 10 across, the scene translated by 1e6,
// cloth resting exactly on an obstacle, cloth meeting itself exactly coplanar). Each case here
// runs stably: no NaN, energy bounded, no penetration; docs/stability.md records the table.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "drape/core/integrator.h"
#include "drape/core/penetration.h"

using namespace drape;

namespace {

struct Outcome {
  bool ok = true;
  std::string failure;
  Scalar initial_energy = 0;
  Scalar max_energy = 0;
  Scalar final_energy = 0;
  std::size_t penetrations = 0;
  State state;
};

// A square cloth of `size` metres pinned at two corners (or free over obstacles), simulated for
// `seconds`.
Outcome simulate(const std::string& json, Scalar seconds) {
  const Model model = build_model(parse_scene(json, "extreme.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  Outcome out;
  out.initial_energy = out.max_energy = kinetic_energy(model, state) + potential_energy(model, state);
  const int steps = int(std::round(seconds / model.scene.timestep()));
  for (int s = 0; s < steps; ++s) {
    const StepReport r = integrator.step(state);
    if (!r.ok) {
      out.ok = false;
      out.failure = r.failure;
      break;
    }
    const Scalar e = kinetic_energy(model, state) + potential_energy(model, state);
    out.max_energy = std::max(out.max_energy, e);
    out.final_energy = e;
  }
  out.penetrations = find_penetrations(model, state.positions, state.time).size();
  out.state = state;
  return out;
}

std::string hanging(Scalar size, const std::string& material, const std::string& extra = "", int frame_steps = 4) {
  std::ostringstream s;
  s << R"({"frame_time": 0.04, "frame_steps": )" << frame_steps << R"(, "cloths": [{"grid": {"size": [)" << size << ", "
    << size << R"(], "resolution": [8, 8]}, "material": {)" << material << R"(}}],
      "handles": [{"corners": ["top-left", "top-right"]}])" << extra << "}";
  return s.str();
}

void expect_stable(const Outcome& o, const std::string& what) {
  EXPECT_TRUE(o.ok) << what << ": " << o.failure;
  EXPECT_EQ(o.penetrations, 0u) << what;
  for (const Vec3& x : o.state.positions) ASSERT_TRUE(x.allFinite()) << what;
}

}  // namespace

TEST(Extremes, StiffnessFromOneToOneBillion) {
  // Energy bound: the start plus all the energy gravity could release over the cloth's size
  // (total mass 0.15 kg, 1 m): 1.5 J.
  const Scalar gravity_work = 0.15 * 9.81 * 1.0;
  for (const char* stiffness : {"1", "1e3", "1e6", "1e9"}) {
    const Outcome o = simulate(hanging(1, std::string(R"("stretch": )") + stiffness + R"(, "shear": )" + stiffness), 2.0);
    expect_stable(o, std::string("stretch ") + stiffness);
    EXPECT_LE(o.final_energy, o.initial_energy + gravity_work) << stiffness;
    if (std::string(stiffness) != "1e9") {
      EXPECT_LE(o.max_energy, o.initial_energy + gravity_work) << stiffness;
    } else {
      // At 1e9 N (k = 8e9 N/m on 2 g particles, h = 0.01 s) the single linearised Newton step
      // of the first steps overshoots: a transient of about 12 J, gone within the first frame
      // (docs/stability.md). Bounded, not dissipative: recorded here so a change shows.
      EXPECT_LT(o.max_energy, 100 * gravity_work) << stiffness;
    }
  }
}

TEST(Extremes, MassesFromMicrogramsToTonnesPerVertex) {
  // 81 vertices on 1 m^2: a vertex carries about density / 64 kg.
  for (const char* density : {"6.4e-5", "6.4e4"}) {
    const Outcome o = simulate(hanging(1, std::string(R"("density": )") + density), 2.0);
    expect_stable(o, std::string("density ") + density);
  }
}

TEST(Extremes, OneToOneHundredStepsPerFrame) {
  for (int steps : {1, 100}) {
    const Outcome o = simulate(hanging(1, R"("stretch": 2000)", "", steps), 1.0);
    expect_stable(o, std::to_string(steps) + " steps a frame");
  }
}

TEST(Extremes, TrianglesFromTenMicronsToTenMetres) {
  // 8 quads a side: 1e-5 m triangles on an 8e-5 m cloth, 10 m triangles on an 80 m cloth.
  for (Scalar size : {8e-5, 80.0}) {
    const Outcome o = simulate(hanging(size, R"("stretch": 2000)", R"(, "collisions": {"thickness": 1e-7})"), 1.0);
    expect_stable(o, "size " + std::to_string(size));
  }
}

TEST(Extremes, TranslatedByAMillionMatchesTheOriginalRun) {
  // The same hanging cloth at the origin and 1e6 m away: after 1 s the shapes agree to 1e-6 m
  // (double precision holds about 1e-10 m at 1e6; the run amplifies that little).
  const std::string near = hanging(1, R"("stretch": 2000)");
  std::string far = near;
  far.replace(far.find(R"("material")"), 0, R"("transform": {"translate": [1e6, -1e6, 1e6]}, )");
  far.replace(far.find("\"handles\""), 0, R"("bounds": {"min": [999000, -1001000, 999000], "max": [1001000, -999000, 1001000]}, )");
  const Outcome a = simulate(near, 1.0), b = simulate(far, 1.0);
  expect_stable(a, "at the origin");
  expect_stable(b, "at 1e6");
  Scalar worst = 0;
  for (std::size_t v = 0; v < a.state.positions.size(); ++v)
    worst = std::max(worst, (b.state.positions[v] - Vec3(1e6, -1e6, 1e6) - a.state.positions[v]).norm());
  EXPECT_LT(worst, 1e-6);
}

TEST(Extremes, ClothRestingExactlyOnAnObstacle) {
  // Lying exactly at the thickness above the ground: it stays there, at rest, not inside.
  const Outcome o = simulate(R"({"frame_time": 0.04, "frame_steps": 4,
    "cloths": [{"grid": {"size": [1, 1], "resolution": [8, 8]}, "transform": {"translate": [0, 0, 0.005]}}],
    "obstacles": [{"plane": {}}], "collisions": {"thickness": 0.005}})", 1.0);
  expect_stable(o, "resting");
  for (const Vec3& x : o.state.positions) EXPECT_NEAR(x.z(), 0.005, 1e-9);
}

TEST(Extremes, ClothMeetingItselfExactlyCoplanar) {
  // Two cloths in the one plane slide into each other edge first: the motion is exactly
  // coplanar (every coplanarity cubic vanishes), so only the degenerate paths can see it.
  for (const char* method : {"vincent", "conservative"}) {
    const Outcome o = simulate(std::string(R"({"frame_time": 0.04, "frame_steps": 4, "gravity": [0, 0, 0],
      "cloths": [{"grid": {"size": [0.4, 0.4], "resolution": [4, 4]}, "transform": {"translate": [-0.25, 0, 0.5]}, "velocity": [0.5, 0, 0]},
                 {"grid": {"size": [0.4, 0.4], "resolution": [4, 4]}, "transform": {"translate": [0.25, 0, 0.5]}, "velocity": [-0.5, 0, 0]}],
      "collisions": {"self": true, "thickness": 0.005, "method": ")") + method + R"("}})", 0.5);
    expect_stable(o, method);
    // They met: the inner edges stopped short of each other.
    Scalar left_max = -1e9, right_min = 1e9;
    for (int v = 0; v < 25; ++v) left_max = std::max(left_max, o.state.positions[v].x());
    for (int v = 25; v < 50; ++v) right_min = std::min(right_min, o.state.positions[v].x());
    EXPECT_LT(left_max, right_min) << method;
  }
}
