// Contacts held in the linearised solve whose force pulls are released (solver.release_solves):
// between the cloth's layers and at a moving obstacle the step is solved again without them;
// a still obstacle's pull is released at the next step. A cloth lifted off another by its edge
// leaves the one under it lying on the ground; a cloth lifted off the ground leaves it; a
// plane falling away from a cloth does not drag it down.
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>

#include "drape/core/integrator.h"

using namespace drape;

namespace {

constexpr Scalar THICKNESS = 0.004;  // m
constexpr int CELLS = 10;            // quads along each side of a 0.2 m cloth
constexpr int ROW = CELLS + 1;       // vertices in a row along x

// A 0.2 m cloth lying on the ground (just over the thickness above it), its +y edge lifted at
// 0.5 m/s from the start; with on_cloth, it lies instead on a second such cloth, one thickness
// above it. 10 steps a frame.
std::string lifted(bool on_cloth, const std::string& solver = "") {
  std::ostringstream s;
  s.precision(17);
  const auto cloth = [&](Scalar z) {
    s << R"({"grid": {"size": [0.2, 0.2], "resolution": [)" << CELLS << ", " << CELLS
      << R"(]}, "transform": {"translate": [0, 0, )" << z
      << R"(]}, "material": {"density": 0.2, "stretch": 500, "shear": 50, "bend": 0.01}})";
  };
  s << R"({"frame_time": 0.02, "frame_steps": 10, "cloths": [)";
  cloth(1.01 * THICKNESS);
  if (on_cloth) {
    s << ", ";
    cloth(2.02 * THICKNESS);
  }
  s << R"(], "handles": [{"cloth": )" << (on_cloth ? 1 : 0)
    << R"(, "box": {"min": [-1, 0.099, -1], "max": [1, 1, 1]}, "motion": {"velocity": [0, 0, 0.5]}}],
    "obstacles": [{"plane": {}}], "collisions": {"self": )"
    << (on_cloth ? "true" : "false") << R"(, "thickness": )" << THICKNESS << R"(}, "solver": {"type": "cholmod")" << solver
    << "}}";
  return s.str();
}

struct Lift {
  Scalar lower_highest = 0;           // m: the highest vertex of the cloth underneath (on_cloth)
  std::vector<Scalar> lifted_rows;    // m: the lifted cloth's lowest vertex in each row along y
};

Lift run(const std::string& json, int steps) {
  const Model model = build_model(parse_scene(json, "contact_release.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  Lift lift;
  for (int s = 0; s < steps; ++s) {
    const StepReport r = integrator.step(state);
    EXPECT_TRUE(r.ok) << r.failure;
  }
  const std::size_t cloth = std::size_t(ROW * ROW), first = model.masses.size() - cloth;  // the lifted cloth comes last
  for (std::size_t v = 0; v < first; ++v) lift.lower_highest = std::max(lift.lower_highest, state.positions[v].z());
  lift.lifted_rows.assign(ROW, 1);
  for (std::size_t v = first; v < model.masses.size(); ++v)
    lift.lifted_rows[(v - first) / ROW] = std::min(lift.lifted_rows[(v - first) / ROW], state.positions[v].z());
  return lift;
}

}  // namespace

TEST(ContactRelease, AClothLiftedOffAnotherLeavesItOnTheGroundWhenSolvedAgainUntilNoPull) {
  // 0.16 s: the edge 8 cm up. Solved again up to 4 times, releasing the pulls and holding
  // again the released pairs that close, the cloth underneath stays where it lay. (With the
  // default single solve again it rises 4.7 cm, and rose 6.7 cm before session 23:
  // docs/collisions.md.)
  const Lift lift = run(lifted(true, R"(, "release_solves": 4)"), 80);
  EXPECT_LT(lift.lower_highest, 1.5 * THICKNESS);
  // (The response's proximity impulses over the run are not a measure of it: with the same
  // code they ranged from 17 to 913 by OpenBLAS's kernels alone (Zen, Haswell, Nehalem,
  // Sandybridge, Prescott: rounding parts the runs from the second frame), and one solve a
  // step, whose lower cloth rises 6.6 cm, gave 41 to 64.)
  // The lifted cloth has left it: its row next to the edge well above, its far rows on it.
  EXPECT_GT(lift.lifted_rows[CELLS - 1], 0.05);
  EXPECT_LT(lift.lifted_rows[0], 4 * THICKNESS);
}

TEST(ContactRelease, AClothLiftedOffTheGroundLeavesIt) {
  // The ground's pulls are released at the next step: the rows near the lifted edge leave it
  // (held while they pull, every row would stay at the thickness), the far rows lie on it.
  const Lift lift = run(lifted(false), 60);
  EXPECT_GT(lift.lifted_rows[CELLS - 1], 0.04);
  EXPECT_LT(lift.lifted_rows[0], 1.5 * THICKNESS);
}

TEST(ContactRelease, APlaneFallingAwayFromAClothDoesNotDragItDown) {
  // A cloth at rest on a plane that moves down at 2 m/s from the first step: held while it
  // pulls, the cloth would go down with the plane; released, it falls under gravity alone.
  const Model model = build_model(parse_scene(R"({"frame_time": 0.02, "frame_steps": 4,
    "cloths": [{"grid": {"size": [0.2, 0.2], "resolution": [10, 10]}, "transform": {"translate": [0, 0, 0.0041]}}],
    "obstacles": [{"plane": {}, "motion": {"velocity": [0, 0, -2]}}], "collisions": {"thickness": 0.004},
    "solver": {"type": "cholmod"}})",
                                              "falling_plane.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  for (int s = 0; s < 2; ++s) ASSERT_TRUE(integrator.step(state).ok);
  // Two steps of free fall: 9.81 * 0.01 s, about 0.1 m/s down; dragged, 2 m/s.
  for (const Vec3& v : state.velocities) EXPECT_GT(v.z(), -0.2);
}

TEST(ContactRelease, AReleasedContactIsHeldAgainWhenTheSolveMovesItsVertexIn) {
  // scenes/pile.json's ribbon standing on the ground (frames 6-8, after its landing): a vertex
  // released for a pull at the landing and resting on the ground afterwards fell in every
  // solve while its contact stayed released (its speed at each step's start, which the
  // response had stopped, never approached), and every step spread that stop through a second
  // factorisation: 60 in these 30 steps. Held again once a solve moves it in, a step
  // factorises about once.
  const Model model = build_model(load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/pile.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  for (int s = 0; s < 50; ++s) ASSERT_TRUE(integrator.step(state).ok);
  const int before = integrator.factorisations();
  for (int s = 0; s < 30; ++s) ASSERT_TRUE(integrator.step(state).ok);
  EXPECT_LE(integrator.factorisations() - before, 40);
}
