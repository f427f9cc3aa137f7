// Self-collision on meshes finer than the thickness: a cloth whose neighbours are closer than
// the thickness in its own rest shape must not push itself apart. At edge lengths from 4x down
// to 0.25x the thickness, a flat cloth falling freely or resting on the ground behaves the same
// with self-collision on as off (energy and stretch within 1e-6), and receives no proximity
// impulse; repulsion only ever slows an approach, so it never adds energy.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "drape/core/integrator.h"
#include "drape/core/penetration.h"

using namespace drape;

namespace {

constexpr Scalar THICKNESS = 0.005;  // the default, m
constexpr int QUADS = 12;            // quads along each side
constexpr Scalar RATIOS[] = {4, 2, 1, 0.5, 0.25};  // edge length / thickness

struct Outcome {
  Scalar energy = 0, max_energy = 0, initial_energy = 0, stretch = 0;
  long proximity_impulses = 0, rest_clamped_pairs = 0;
  std::size_t penetrations = 0;
};

// A square cloth of QUADS x QUADS quads with edges ratio * THICKNESS, flat, either high above
// everything (free fall) or resting one thickness above a ground plane.
std::string scene(Scalar ratio, bool self, bool on_ground) {
  const Scalar size = QUADS * ratio * THICKNESS;
  std::ostringstream s;
  s.precision(17);
  s << R"({"frame_time": 0.02, "frame_steps": 4, "cloths": [{"grid": {"size": [)" << size << ", " << size
    << R"(], "resolution": [)" << QUADS << ", " << QUADS << R"(]}, "transform": {"translate": [0, 0, )"
    << (on_ground ? THICKNESS : 1.0) << R"(]}}], "collisions": {"self": )" << (self ? "true" : "false")
    << R"(, "thickness": )" << THICKNESS << "}";
  if (on_ground) s << R"(, "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}])";
  s << "}";
  return s.str();
}

Outcome simulate(const std::string& json, int steps) {
  const Model model = build_model(parse_scene(json, "self_collision.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  Outcome out;
  out.initial_energy = out.max_energy = kinetic_energy(model, state) + potential_energy(model, state);
  for (int s = 0; s < steps; ++s) {
    const StepReport r = integrator.step(state);
    EXPECT_TRUE(r.ok) << r.failure;
    out.proximity_impulses += r.collisions.proximity_impulses;
    out.rest_clamped_pairs += r.collisions.rest_clamped_pairs;
    out.max_energy = std::max(out.max_energy, kinetic_energy(model, state) + potential_energy(model, state));
  }
  out.energy = kinetic_energy(model, state) + potential_energy(model, state);
  out.stretch = max_stretch(model, state);
  out.penetrations = find_penetrations(model, state.positions, state.time).size();
  return out;
}

Scalar relative(Scalar a, Scalar b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

void expect_self_collision_changes_nothing(bool on_ground) {
  for (const Scalar ratio : RATIOS) {
    const std::string what = std::string(on_ground ? "resting" : "falling") + ", edge " + std::to_string(ratio) + " x thickness";
    const Outcome off = simulate(scene(ratio, false, on_ground), 40);
    const Outcome on = simulate(scene(ratio, true, on_ground), 40);
    EXPECT_LE(relative(on.energy, off.energy), 1e-6) << what << ": " << on.energy << " against " << off.energy;
    EXPECT_LE(relative(on.stretch, off.stretch), 1e-6) << what << ": " << on.stretch << " against " << off.stretch;
    EXPECT_EQ(on.proximity_impulses, 0) << what;
    EXPECT_EQ(on.penetrations, 0u) << what;
    // The cloth never gains energy: falling, it only trades height for speed (and air damping
    // takes some); resting, it only settles.
    EXPECT_LE(on.max_energy, on.initial_energy * (1 + 1e-9) + 1e-12) << what;
    // Below the thickness, the rest shape sets the gap of the nearest pairs (when any pair is
    // close enough to be asked).
    if (ratio >= 2) {
      EXPECT_EQ(on.rest_clamped_pairs, 0) << what;
    }
  }
}

}  // namespace

TEST(SelfCollision, AFallingClothOfAnyResolutionIsUntouchedBySelfCollision) { expect_self_collision_changes_nothing(false); }

TEST(SelfCollision, ARestingClothOfAnyResolutionIsUntouchedBySelfCollision) { expect_self_collision_changes_nothing(true); }
