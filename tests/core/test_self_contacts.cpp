// The cloth's contacts with itself held in the implicit solve (collisions.self_in_solve, the
// linearised solver): two layers closer than the thickness, driven together, are stopped by
// the solve itself, which keeps the momentum (the two sides' pushes are equal and opposite)
// and makes no energy; the response's proximity impulses have next to nothing left to do. A
// cloth with no contact with itself runs bit for bit as without the option.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>

#include "drape/core/collision.h"
#include "drape/core/integrator.h"
#include "drape/core/penetration.h"
#include "integrator_workspace.h"

using namespace drape;

namespace {

constexpr Scalar THICKNESS = 0.005;  // m

// Two square layers of 10 x 10 quads (2 cm), gap apart, the upper shifted by upper_shift (a third of a quad)
// so that its vertices lie over the lower's faces: the lower of density 0.2 kg/m^2 moving up at
// 0.2 m/s, the upper of 0.1 kg/m^2 down at 0.8 m/s (a momentum of their own, which the contacts
// must keep: no air to take it), or with falling, both dropping together at 0.5 m/s under
// gravity.
std::string layers(bool in_solve, Scalar gap, bool falling = false, Scalar upper_shift = 0.2 / 30) {
  std::ostringstream s;
  s.precision(17);
  const auto cloth = [&](Scalar shift, Scalar z, Scalar vz, Scalar density) {
    s << R"({"grid": {"size": [0.2, 0.2], "resolution": [10, 10]}, "transform": {"translate": [)" << shift << ", " << shift
      << ", " << z << R"(]}, "velocity": [0, 0, )" << vz << R"(], "material": {"density": )" << density
      << R"(, "stretch": 500, "shear": 50, "bend": 0.01, "air_damping": 0}})";
  };
  s << R"({"frame_time": 0.02, "frame_steps": 4, "gravity": [0, 0, )" << (falling ? -9.81 : 0) << R"(], "cloths": [)";
  cloth(0, 0.5, falling ? -0.5 : 0.2, 0.2);
  s << ", ";
  cloth(upper_shift, 0.5 + gap, falling ? -0.5 : -0.8, 0.1);
  s << R"(], "collisions": {"self": true, "thickness": )" << THICKNESS << R"(, "self_in_solve": )" << (in_solve ? "true" : "false")
    << R"(}, "solver": {"type": "cholmod"}})";
  return s.str();
}

struct Layers {
  long held = 0, proximity = 0, first_step_proximity = 0;
  Scalar largest_momentum = 0;  // |change of sum m v| over sum m |v| at the start, largest over the steps
  Scalar energy_start = 0, energy_max = 0, energy_first_step = 0;
  Scalar closest_layers = 1;  // m: the least distance between the layers' mean heights
  std::size_t penetrations = 0;
};

Layers simulate(const std::string& json, int steps) {
  const Model model = build_model(parse_scene(json, "self_contacts.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  Layers run;
  Scalar scale = 0;
  Vec3 momentum_start = Vec3::Zero();
  for (std::size_t v = 0; v < model.masses.size(); ++v) {
    scale += model.masses[v] * state.velocities[v].norm();
    momentum_start += model.masses[v] * state.velocities[v];
  }
  run.energy_start = run.energy_max = kinetic_energy(model, state) + potential_energy(model, state);
  const std::size_t half = model.masses.size() / 2;  // the first cloth's vertices come first
  for (int s = 0; s < steps; ++s) {
    const StepReport r = integrator.step(state);
    EXPECT_TRUE(r.ok) << r.failure;
    run.held += r.collisions.held_self_contacts;
    run.proximity += r.collisions.proximity_impulses;
    if (s == 0) run.first_step_proximity = r.collisions.proximity_impulses;
    Vec3 momentum = Vec3::Zero();
    for (std::size_t v = 0; v < model.masses.size(); ++v) momentum += model.masses[v] * state.velocities[v];
    run.largest_momentum = std::max(run.largest_momentum, (momentum - momentum_start).norm() / scale);
    run.energy_max = std::max(run.energy_max, kinetic_energy(model, state) + potential_energy(model, state));
    if (s == 0) run.energy_first_step = kinetic_energy(model, state) + potential_energy(model, state);
    Scalar bottom = 0, top = 0;
    for (std::size_t v = 0; v < model.masses.size(); ++v) (v < half ? bottom : top) += state.positions[v].z();
    run.closest_layers = std::min(run.closest_layers, (top - bottom) / Scalar(half));
    run.penetrations += find_penetrations(model, state.positions, state.time).size();
  }
  return run;
}

TEST(SelfContactsInTheSolve, TwoLayersDrivenTogetherAreStoppedByTheSolveWithTheirMomentumAndNoEnergyMade) {
  const Layers on = simulate(layers(true, 0.8 * THICKNESS), 8);
  const Layers off = simulate(layers(false, 0.8 * THICKNESS), 8);
  EXPECT_GT(on.held, 0);
  EXPECT_EQ(off.held, 0);
  // The two sides are pushed apart equally and oppositely: the momentum is kept, to the solve's
  // rounding, which grows with the penalty (SELF_CONTACT_HOLD). Each side held against the
  // other's velocity at the step's start, as a one-sided contact, pushes the light layer as
  // hard as the heavy one: the momentum changes by a large part of itself.
  // (Without them, the response stops the layers, and its spread through the solve, which
  // holds the stopped vertices by a penalty of 1e8, changed the momentum by 0.2 %.)
  EXPECT_LT(on.largest_momentum, 1e-5);
  // An inelastic stop: the approach's kinetic energy is lost, none is made.
  EXPECT_LE(on.energy_max, on.energy_start * (1 + 1e-9));
  EXPECT_LT(on.energy_first_step, 0.5 * on.energy_start) << "the approach was not stopped in the first step";
  // The solve stopped the approach: the response had next to nothing to do, where without it
  // every vertex over a face needs its impulse.
  EXPECT_GT(off.first_step_proximity, 50);
  EXPECT_LT(on.first_step_proximity, off.first_step_proximity / 10) << on.first_step_proximity << " against " << off.first_step_proximity;
  // Held apart, never through each other.
  EXPECT_GT(on.closest_layers, 0.7 * THICKNESS);
  EXPECT_EQ(on.penetrations, 0u);
  EXPECT_EQ(off.penetrations, 0u);
}

TEST(SelfContactsInTheSolve, ClothWithNoContactWithItselfRunsBitForBitAsWithoutThem) {
  // The two layers 5 cm apart, falling together: no self contact, so nothing held, and the
  // same bits (the pattern, the solve and the response are untouched).
  const std::string far = layers(true, 0.05, true), far_off = layers(false, 0.05, true);
  const Model model = build_model(parse_scene(far, "far.json"));
  const Model model_off = build_model(parse_scene(far_off, "far_off.json"));
  State a = initial_state(model), b = initial_state(model_off);
  Integrator on(model), off(model_off);
  long held = 0;
  for (int s = 0; s < 12; ++s) {
    const StepReport r = on.step(a);
    ASSERT_TRUE(r.ok) << r.failure;
    ASSERT_TRUE(off.step(b).ok);
    held += r.collisions.held_self_contacts;
  }
  EXPECT_EQ(held, 0);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.velocities, b.velocities);
}

// A 20 cm cloth lying on a 60 cm one (at the thickness) that lies on the ground, thrown along
// it at 1 m/s: Coulomb friction between the layers (friction 0.5) stops it within
// v^2 / (2 mu g) = 10.2 cm; without friction it slides on. The contacts between the layers are
// held in the solve, so the friction is the solve's too (the response, with nothing left to
// stop, gives none).
Scalar slid(Scalar friction) {
  std::ostringstream s;
  s.precision(17);
  s << R"({"frame_time": 0.02, "frame_steps": 5, "friction": )" << friction << R"(, "cloths": [
      {"grid": {"size": [0.6, 0.6], "resolution": [10, 10]}, "transform": {"translate": [0, 0, 0.005]}},
      {"grid": {"size": [0.2, 0.2], "resolution": [10, 10]}, "transform": {"translate": [0, 0, 0.0101]}, "velocity": [1, 0, 0]}],
    "obstacles": [{"plane": {}}], "collisions": {"self": true, "thickness": 0.005}, "solver": {"type": "cholmod"}})";
  const Model model = build_model(parse_scene(s.str(), "slide.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  long held = 0;
  for (int step = 0; step < 75; ++step) {  // 0.3 s
    const StepReport r = integrator.step(state);
    EXPECT_TRUE(r.ok) << r.failure;
    held += r.collisions.held_self_contacts;
  }
  EXPECT_GT(held, 0);
  EXPECT_EQ(find_penetrations(model, state.positions, state.time).size(), 0u);
  const std::size_t first = 121;  // the upper cloth's vertices follow the lower's 11 x 11
  Scalar x = 0;
  for (std::size_t v = first; v < model.masses.size(); ++v) x += state.positions[v].x();
  return x / Scalar(model.masses.size() - first);
}

TEST(SelfContactsInTheSolve, AClothSlidingOnAnotherStopsWhereCoulombFrictionSays) {
  const Scalar expected = 1.0 / (2 * 0.5 * 9.81);
  EXPECT_NEAR(slid(0.5), expected, 0.15 * expected);
  EXPECT_GT(slid(0), 0.25);  // 0.3 s at about 1 m/s, less the air's drag
}

}  // namespace

TEST(SelfContactsInTheSolve, AVertexOverTheTrianglesAroundAMeshVertexIsHeldOnce) {
  // Two layers exactly one over the other, 0.8 thickness apart: each upper vertex projects onto
  // a lower vertex, within reach of every triangle around it. It is held once, along the
  // normal, by one triangle (held by each, with weights a rounding apart, the penalties
  // fought: docs/collisions.md).
  const Model model = build_model(parse_scene(layers(true, 0.8 * THICKNESS, false, 0), "aligned.json"));
  ASSERT_EQ(model.initial_positions[121].x(), model.initial_positions[0].x()) << "the layers are not aligned";
  CollisionPipeline pipeline(model, CollisionSettings{});
  CollisionCounters counters;
  const std::vector<SolveContact> contacts = pipeline.self_contacts(model.initial_positions, CONTACT_REACH, counters);
  std::map<int, int> per_vertex;  // vertex-face contacts by their vertex
  for (const SolveContact& c : contacts)
    if (c.weight[1] < 0) ++per_vertex[c.vertex[0]];
  ASSERT_FALSE(per_vertex.empty());
  for (const auto& [vertex, count] : per_vertex) EXPECT_EQ(count, 1) << "vertex " << vertex;
}
