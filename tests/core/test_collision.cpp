// The collision response itself (core/src/collision.cpp, collision_response.cpp), one resolve
// of a step at a time: impulses that keep momentum, act along the contact normal (of a face or
// of two edges, tilted or not) and replace the approach by the separation speed, proximity
// impulses that stop an approach within the thickness and no more, Coulomb's bound on
// friction, impact zones that keep linear and angular momentum or move with the pinned
// vertices they hold, the fail-safe (only the colliding vertices stopped), and kinematic
// (pinned) vertices never moved.
#include <gtest/gtest.h>

#include <sstream>

#include "drape/core/collision.h"
#include "drape/core/penetration.h"

using namespace drape;

namespace {

// Two free square cloths of 2 x 2 quads, 20 cm wide, one above the other (a gap of 2 cm, 5
// mm thickness), cloth against cloth on; rounds: more keys of the collisions section.
Model two_sheets(Scalar friction, const std::string& rounds = "") {
  std::ostringstream json;
  json << R"({"frame_time": 0.05, "frame_steps": 1, "friction": )" << friction << R"(,
    "cloths": [{"grid": {"size": [0.2, 0.2], "resolution": [2, 2]}},
               {"grid": {"size": [0.2, 0.2], "resolution": [2, 2]}, "transform": {"translate": [0.013, 0.007, 0.02]}}],
    "collisions": {"self": true, "thickness": 0.005)" << rounds << "}}";
  return build_model(parse_scene(json.str(), "inline.json"));
}

// A 1.5 cm square cloth (two triangles), turned 30 degrees, 2 cm above the inside of one
// triangle of a 20 cm sheet pinned whole (3 mm thickness): every contact of a fall is one of
// its vertices with that flat triangle, along z.
Model square_over_pinned_sheet(Scalar friction) {
  std::ostringstream json;
  json << R"({"frame_time": 0.05, "frame_steps": 1, "friction": )" << friction << R"(,
    "cloths": [{"grid": {"size": [0.2, 0.2], "resolution": [2, 2]}},
               {"grid": {"size": [0.015, 0.015], "resolution": [1, 1]},
                "transform": {"rotate": [30, 0, 0, 1], "translate": [0.05, 0.018, 0.02]}}],
    "handles": [{"cloth": 0, "box": {"min": [-1, -1, -0.001], "max": [1, 1, 0.001]}}],
    "collisions": {"self": true, "thickness": 0.003}})";
  return build_model(parse_scene(json.str(), "inline.json"));
}

// The upper cloth (the second) falling through the lower one within the step: its vertices
// move by `upper` over the step, the lower one's by `lower`.
std::vector<Vec3> motions(const Model& model, const Vec3& upper, const Vec3& lower = Vec3::Zero()) {
  std::vector<Vec3> motion(model.vertex_count());
  const ClothRange& second = model.cloths[1];
  for (std::size_t v = 0; v < motion.size(); ++v)
    motion[v] = int(v) >= second.first_vertex ? upper : model.pin_of_vertex[v] >= 0 ? Vec3::Zero() : lower;
  return motion;
}

Vec3 momentum(const Model& model, const std::vector<Vec3>& motion, int first = 0, int end = -1) {
  if (end < 0) end = int(motion.size());
  Vec3 p = Vec3::Zero();
  for (int v = first; v < end; ++v) p += model.masses[std::size_t(v)] * motion[std::size_t(v)];
  return p;
}

Vec3 angular_momentum(const Model& model, const std::vector<Vec3>& start, const std::vector<Vec3>& motion) {
  Vec3 l = Vec3::Zero();
  for (std::size_t v = 0; v < motion.size(); ++v) l += model.masses[v] * start[v].cross(motion[v]);
  return l;
}

// Whether the step's motion is free of collisions: another resolve finds no contact along it
// (exact CCD), and the end positions cross nothing (the independent check).
bool collision_free(const Model& model, const std::vector<Vec3>& start, Scalar h, const std::vector<Vec3>& motion) {
  CollisionPipeline again(model, CollisionSettings{});
  std::vector<Vec3> copy = motion;
  const CollisionCounters c = again.resolve(start, 0, h, copy, model.scene.friction);
  std::vector<Vec3> end(start.size());
  for (std::size_t v = 0; v < start.size(); ++v) end[v] = start[v] + h * motion[v];
  return c.ccd_hits == 0 && find_penetrations(model, end, h).empty();
}

}  // namespace

TEST(Collision, ImpulsesKeepMomentumAndStopTheApproach) {
  // Two free sheets: the upper one falls 10 cm in the step, through the lower one, sliding;
  // frictionless. The impulses are internal: the momentum of both sheets is kept, the upper
  // one gives downward momentum to the lower one, and the step ends free of collisions.
  const Model model = two_sheets(0);
  const Scalar h = model.scene.timestep();
  const std::vector<Vec3>& start = model.initial_positions;
  std::vector<Vec3> motion = motions(model, Vec3(0.3, -0.1, -2.0));
  const std::vector<Vec3> before = motion;
  CollisionPipeline pipeline(model, CollisionSettings{});
  const CollisionCounters c = pipeline.resolve(start, 0, h, motion, model.scene.friction);
  EXPECT_GT(c.ccd_hits, 0);
  EXPECT_EQ(c.impact_zones, 0);  // the impulses alone
  EXPECT_EQ(c.fail_safes, 0);
  EXPECT_LT((momentum(model, motion) - momentum(model, before)).norm(), 1e-12);
  const int second = model.cloths[1].first_vertex;
  EXPECT_GT(momentum(model, motion, second).z(), momentum(model, before, second).z());
  EXPECT_LT(momentum(model, motion, 0, second).z(), 0);
  EXPECT_TRUE(collision_free(model, start, h, motion));
}

TEST(Collision, AnImpulseActsAlongItsNormalAndLeavesTheSeparationSpeed) {
  // The square falls onto the pinned sheet's flat triangle: every change is along z, the
  // sheet does not move, and the square's normal speed becomes the separation speed.
  const Model model = square_over_pinned_sheet(0);
  const Scalar h = model.scene.timestep();
  std::vector<Vec3> motion = motions(model, Vec3(0.1, 0.05, -2.0));
  const std::vector<Vec3> before = motion;
  CollisionPipeline pipeline(model, CollisionSettings{});
  const CollisionCounters c = pipeline.resolve(model.initial_positions, 0, h, motion, model.scene.friction);
  EXPECT_GT(c.ccd_hits, 0);
  for (std::size_t v = 0; v < motion.size(); ++v) {
    if (model.pin_of_vertex[v] >= 0) {
      EXPECT_EQ(motion[v], Vec3::Zero()) << v;
      continue;
    }
    EXPECT_NEAR(motion[v].x(), before[v].x(), 1e-12) << v;
    EXPECT_NEAR(motion[v].y(), before[v].y(), 1e-12) << v;
    // Inelastic, with the separation speed SEPARATION_FRACTION asks for: the step's fall is
    // replaced by a rise of a tenth of the thickness, enough that the next round does not
    // find the same contact again.
    EXPECT_NEAR(motion[v].z(), SEPARATION_FRACTION * 0.003 / h, 1e-12) << v;
  }
  EXPECT_TRUE(collision_free(model, model.initial_positions, h, motion));
}

TEST(Collision, FrictionStaysWithinCoulombsBoundAndNeverReversesTheSlip) {
  // The square slides across the pinned sheet while falling onto it: each vertex's tangential
  // change is at most the friction coefficient times its normal change (every contact's
  // normal is z), it acts at that bound while the vertex slides, and the slide never reverses
  // (at friction 5 it stops).
  for (Scalar mu : {0.01, 0.05, 5.0}) {
    const Model model = square_over_pinned_sheet(mu);
    const Scalar h = model.scene.timestep();
    const Vec3 incoming(0.1, 0.05, -2.0);
    std::vector<Vec3> motion = motions(model, incoming);
    const std::vector<Vec3> before = motion;
    CollisionPipeline pipeline(model, CollisionSettings{});
    pipeline.resolve(model.initial_positions, 0, h, motion, model.scene.friction);
    for (int v = model.cloths[1].first_vertex; v < int(motion.size()); ++v) {
      const Vec3 change = motion[std::size_t(v)] - before[std::size_t(v)];
      const Scalar normal = change.z(), tangential = Vec3(change.x(), change.y(), 0).norm();
      const Vec3 slide(motion[std::size_t(v)].x(), motion[std::size_t(v)].y(), 0);
      EXPECT_GT(normal, 0) << mu << ", vertex " << v;
      EXPECT_LE(tangential, mu * normal * (1 + 1e-9)) << mu << ", vertex " << v;
      EXPECT_GE(slide.dot(Vec3(incoming.x(), incoming.y(), 0)), -1e-12) << mu << ", vertex " << v;
      if (mu < 0.1) {
        EXPECT_NEAR(tangential, mu * normal, 1e-9 * normal) << mu << ", vertex " << v;
      } else {
        EXPECT_LT(slide.norm(), 1e-9) << mu << ", vertex " << v;
      }
    }
  }
}

TEST(Collision, ImpactZonesKeepMomentumAndAngularMomentum) {
  // No impulse rounds: the collisions go straight to rigid impact zones. The upper sheet
  // falls through the lower, free one while turning; each zone keeps its momentum and
  // angular momentum, so the pair does.
  const Model model = two_sheets(0, R"(, "max_impulse_iterations": 0)");
  const Scalar h = model.scene.timestep();
  const std::vector<Vec3>& start = model.initial_positions;
  std::vector<Vec3> motion(model.vertex_count());
  const int second = model.cloths[1].first_vertex;
  const Vec3 centre(0.013, 0.007, 0.02), spin(0, 0, 3.0);
  for (std::size_t v = 0; v < motion.size(); ++v)
    motion[v] = int(v) >= second ? Vec3(Vec3(0, 0, -2.0) + spin.cross(start[v] - centre)) : Vec3(0, 0, 0.5);
  const std::vector<Vec3> before = motion;
  CollisionPipeline pipeline(model, CollisionSettings{});
  const CollisionCounters c = pipeline.resolve(start, 0, h, motion, model.scene.friction);
  EXPECT_GT(c.impact_zones, 0);
  EXPECT_EQ(c.fail_safes, 0);
  EXPECT_LT((momentum(model, motion) - momentum(model, before)).norm(), 1e-12);
  EXPECT_LT((angular_momentum(model, start, motion) - angular_momentum(model, start, before)).norm(), 1e-12);
  EXPECT_TRUE(collision_free(model, start, h, motion));
}

TEST(Collision, TheFailSafeStopsWhatNothingElseResolved) {
  // No impulse and no impact-zone rounds: the fail-safe keeps the colliding vertices at their
  // start (and, if that is not enough, every cloth vertex), and the step is then free.
  const Model model = two_sheets(0, R"(, "max_impulse_iterations": 0, "max_zone_iterations": 0)");
  const Scalar h = model.scene.timestep();
  std::vector<Vec3> motion = motions(model, Vec3(0, 0, -2.0), Vec3(0, 0, 0.5));
  CollisionPipeline pipeline(model, CollisionSettings{});
  const CollisionCounters c = pipeline.resolve(model.initial_positions, 0, h, motion, model.scene.friction);
  EXPECT_EQ(c.fail_safes, 1);
  EXPECT_TRUE(collision_free(model, model.initial_positions, h, motion));
}

// The integrator's rounds of strain limit and response resolve one step again and again, the
// limit having changed a few vertices' motion between them. A crumpled 12 x 12 sheet and a
// 4 x 4 one 3 mm over it (within the 4 mm thickness: proximity contacts) falling through it,
// resolved once (free of collisions); then a few of the small sheet's vertices pushed down
// again and the step resolved by the same pipeline: it runs only the tests with a changed
// vertex and ends with the motion, to the bit, and the contacts of a new pipeline that runs
// every test (it fails when the last resolve's proximity contacts are not kept, and without
// the reuse).
TEST(Collision, AResolveOfTheSameStepAgainTestsOnlyWhatChangedAndEndsAsAWholeOne) {
  const Model model = build_model(parse_scene(R"({"frame_time": 0.05, "frame_steps": 1,
      "cloths": [{"grid": {"size": [0.4, 0.4], "resolution": [12, 12]}},
                 {"grid": {"size": [0.1, 0.1], "resolution": [4, 4]}, "transform": {"translate": [0.013, 0.007, 0.003]}}],
      "collisions": {"self": true, "thickness": 0.004}})",
                                              "inline.json"));
  const Scalar h = model.scene.timestep(), mu = 0.3;
  std::vector<Vec3> start = model.initial_positions;
  for (std::size_t v = 0; v < std::size_t(model.cloths[1].first_vertex); ++v)
    start[v].z() += 0.0005 * std::sin(40 * start[v].x()) * std::cos(30 * start[v].y());  // crumpled
  std::vector<Vec3> motion = motions(model, Vec3(0.1, 0, -1.0));
  CollisionPipeline pipeline(model, CollisionSettings{});
  const CollisionCounters first = pipeline.resolve(start, 0, h, motion, mu);
  ASSERT_GT(first.ccd_hits, 0);
  ASSERT_EQ(first.fail_safes, 0);
  const int second = model.cloths[1].first_vertex;
  for (int v = second; v < second + 5; ++v) motion[std::size_t(v)] += Vec3(0, 0, -0.8);
  std::vector<Vec3> whole_motion = motion;
  CollisionSettings whole;
  whole.incremental_rounds = false;
  const CollisionCounters a = pipeline.resolve(start, 0, h, motion, mu);
  const CollisionCounters b = CollisionPipeline(model, whole).resolve(start, 0, h, whole_motion, mu);
  EXPECT_GT(a.ccd_hits, 0);
  EXPECT_GT(a.proximity_impulses, 0);
  EXPECT_EQ(motion, whole_motion);
  EXPECT_EQ(a.ccd_hits, b.ccd_hits);
  EXPECT_EQ(a.impulse_iterations, b.impulse_iterations);
  EXPECT_EQ(a.impact_zones, b.impact_zones);
  EXPECT_EQ(a.proximity_impulses, b.proximity_impulses);
  EXPECT_EQ(a.rest_clamped_pairs, b.rest_clamped_pairs);
  EXPECT_LT(a.vf_tests + a.ee_tests, b.vf_tests + b.ee_tests);
  std::printf("again: %ld hits, %ld proximity impulses, tests %ld against %ld\n", a.ccd_hits, a.proximity_impulses,
              a.vf_tests + a.ee_tests, b.vf_tests + b.ee_tests);
}

TEST(Collision, LaterRoundsTestingOnlyWhatMovedFindWhatWholeRoundsFind) {
  // A crumpled 12 x 12 sheet, a small 4 x 4 one falling fast and turning through it, and a
  // third 3 mm above the first, away from the fall, scripted down through the first's pinned
  // part (collisions no response can move, found again every round): the response moves only
  // the vertices near the falling sheet. Impulse rounds, impact zones alone,
  // and the fail-safe: rounds that run only the tests with a moved vertex end with the same
  // motion, to the bit, and the same hits, as rounds that run every test.
  for (const char* rounds : {"", R"(, "max_impulse_iterations": 0)", R"(, "max_impulse_iterations": 0, "max_zone_iterations": 1)"}) {
    std::ostringstream json;
    json << R"({"frame_time": 0.05, "frame_steps": 1, "friction": 0.3,
      "cloths": [{"grid": {"size": [0.4, 0.4], "resolution": [12, 12]}},
                 {"grid": {"size": [0.1, 0.1], "resolution": [4, 4]}, "transform": {"translate": [0.013, 0.007, 0.02]}},
                 {"grid": {"size": [0.1, 0.1], "resolution": [3, 3]}, "transform": {"translate": [0.13, 0.12, 0.003]}}],
      "handles": [{"cloth": 0, "box": {"min": [0.12, -1, -1], "max": [1, 1, 1]}}, {"cloth": 2, "box": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
      "collisions": {"self": true, "thickness": 0.004)" << rounds << "}}";
    const Model model = build_model(parse_scene(json.str(), "inline.json"));
    const Scalar h = model.scene.timestep();
    std::vector<Vec3> start = model.initial_positions;
    std::vector<Vec3> motion(model.vertex_count());
    const int second = model.cloths[1].first_vertex, third = model.cloths[2].first_vertex;
    const Vec3 centre(0.013, 0.007, 0.02), spin(3, 0, 12.0);
    for (std::size_t v = 0; v < motion.size(); ++v) {
      const Vec3 p = start[v];
      start[v].z() += 0.001 * std::sin(40 * p.x()) * std::cos(30 * p.y());  // crumpled, every sheet
      motion[v] = int(v) >= third    ? Vec3(0, 0, -0.2)
                  : int(v) >= second ? Vec3(Vec3(0, 0, -1.5) + spin.cross(p - centre))
                                     : Vec3(0, 0, 0.1 * std::sin(50 * p.x()) * std::max(Scalar(0), 0.1 - p.x()));
    }
    CollisionSettings whole;
    whole.incremental_rounds = false;
    std::vector<Vec3> incremental_motion = motion, whole_motion = motion;
    const Scalar mu = model.scene.friction;
    const CollisionCounters a = CollisionPipeline(model, CollisionSettings{}).resolve(start, 0, h, incremental_motion, mu);
    const CollisionCounters b = CollisionPipeline(model, whole).resolve(start, 0, h, whole_motion, mu);
    EXPECT_GT(a.impulse_iterations + a.impact_zones, 1) << rounds;
    EXPECT_EQ(incremental_motion, whole_motion) << rounds;
    EXPECT_EQ(a.ccd_hits, b.ccd_hits) << rounds;
    EXPECT_EQ(a.impulse_iterations, b.impulse_iterations) << rounds;
    EXPECT_EQ(a.impact_zones, b.impact_zones) << rounds;
    EXPECT_EQ(a.fail_safes, b.fail_safes) << rounds;
    EXPECT_LT(a.vf_tests + a.ee_tests, b.vf_tests + b.ee_tests) << rounds;
    std::printf("rounds '%s': %ld hits, %ld impulse rounds, %ld zones, %ld fail-safes; tests %ld against %ld\n", rounds,
                a.ccd_hits, a.impulse_iterations, a.impact_zones, a.fail_safes, a.vf_tests + a.ee_tests,
                b.vf_tests + b.ee_tests);
  }
}

namespace {

// Turns a configuration as a whole (positions and motions) by angle degrees about axis.
std::vector<Vec3> turned(const std::vector<Vec3>& points, Scalar degrees, const Vec3& axis) {
  const Eigen::AngleAxis<Scalar> turn(degrees * EIGEN_PI / 180, axis.normalized());
  std::vector<Vec3> out(points.size());
  for (std::size_t v = 0; v < points.size(); ++v) out[v] = turn * points[v];
  return out;
}

// Two strips 40 x 4 cm of one quad each, crossing at right angles 2 cm apart, the lower one
// pinned: neither has a vertex over the other's faces, so every contact of a fall is one of
// the upper's edges with one of the lower's, and every edge lies in a horizontal plane.
Model crossing_strips() {
  return build_model(parse_scene(R"({"frame_time": 0.05, "frame_steps": 1, "friction": 0,
    "cloths": [{"grid": {"size": [0.04, 0.4], "resolution": [1, 1]}},
               {"grid": {"size": [0.4, 0.04], "resolution": [1, 1]}, "transform": {"translate": [0.003, -0.002, 0.02]}}],
    "handles": [{"cloth": 0, "box": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
    "collisions": {"self": true, "thickness": 0.003}})",
                                 "inline.json"));
}

}  // namespace

TEST(Collision, ImpulsesActAlongTiltedNormalsOfFacesAndEdges) {
  // The falling square on the pinned sheet (vertex-face contacts) and the falling strip across
  // the pinned one (edge-edge contacts), both turned 35 degrees about a tilted axis as a whole:
  // frictionless, every free vertex's change is along the turned sheet's normal, and its
  // motion along that normal ends at the separation speed.
  const Vec3 axis(1, 0.4, 0.2);
  const Scalar degrees = 35;
  const Vec3 normal = turned({Vec3::UnitZ()}, degrees, axis)[0];
  for (const bool edges : {false, true}) {
    const Model model = edges ? crossing_strips() : square_over_pinned_sheet(0);
    const Scalar h = model.scene.timestep();
    const std::vector<Vec3> start = turned(model.initial_positions, degrees, axis);
    std::vector<Vec3> motion = turned(motions(model, Vec3(0.1, 0.05, -2.0)), degrees, axis);
    const std::vector<Vec3> before = motion;
    CollisionPipeline pipeline(model, CollisionSettings{});
    const CollisionCounters c = pipeline.resolve(start, 0, h, motion, model.scene.friction);
    EXPECT_GT(c.ccd_hits, 0) << edges;
    EXPECT_EQ(c.impact_zones, 0) << edges;
    int changed = 0;
    for (int v = model.cloths[1].first_vertex; v < int(motion.size()); ++v) {
      const Vec3 change = motion[std::size_t(v)] - before[std::size_t(v)];
      if (change.norm() == 0) continue;
      ++changed;
      EXPECT_LT(change.cross(normal).norm(), 1e-9 * change.norm()) << edges << ", vertex " << v;
      EXPECT_GT(change.dot(normal), 0) << edges << ", vertex " << v;
    }
    EXPECT_GT(changed, 0) << edges;
    // The strip's contacts are at inner points of its edges, so its vertices share the
    // separation by their weights; the square's are its vertices themselves.
    if (!edges) {
      for (int v = model.cloths[1].first_vertex; v < int(motion.size()); ++v)
        EXPECT_NEAR(motion[std::size_t(v)].dot(normal), SEPARATION_FRACTION * 0.003 / h, 1e-9) << v;
    }
    EXPECT_TRUE(collision_free(model, start, h, motion)) << edges;
  }
}

TEST(Collision, ProximityStopsAnApproachWithinTheThicknessAndNoMore) {
  // The square 2 mm above the pinned sheet (within its 3 mm thickness): approaching slowly
  // (no crossing within the step), the proximity impulses stop the approach and leave no
  // separating speed; at rest, or moving away, it gets nothing.
  const Model flat = square_over_pinned_sheet(0);
  std::vector<Vec3> start = flat.initial_positions;
  for (int v = flat.cloths[1].first_vertex; v < int(start.size()); ++v) start[std::size_t(v)].z() = 0.002;
  const Scalar h = flat.scene.timestep();
  for (const Scalar speed : {-0.01, 0.0, 0.01}) {
    std::vector<Vec3> motion = motions(flat, Vec3(0.02, 0, speed));
    const std::vector<Vec3> before = motion;
    CollisionPipeline pipeline(flat, CollisionSettings{});
    const CollisionCounters c = pipeline.resolve(start, 0, h, motion, flat.scene.friction);
    EXPECT_EQ(c.ccd_hits, 0) << speed;
    if (speed < 0) {
      EXPECT_GT(c.proximity_impulses, 0) << speed;
      for (int v = flat.cloths[1].first_vertex; v < int(motion.size()); ++v) {
        EXPECT_NEAR(motion[std::size_t(v)].z(), 0, 1e-12) << v;
        EXPECT_NEAR(motion[std::size_t(v)].x(), before[std::size_t(v)].x(), 1e-12) << v;  // frictionless
      }
    } else {
      EXPECT_EQ(c.proximity_impulses, 0) << speed;
      EXPECT_EQ(motion, before) << speed;
    }
  }
}

TEST(Collision, AnImpactZoneTouchingAPinnedVertexMovesWithIt) {
  // No impulse rounds: the square's fall onto the pinned sheet, which its handle carries
  // sideways, goes to impact zones, which hold pinned vertices; such a zone moves with them
  // (the square's vertices in it take the handle's velocity), and the pinned sheet keeps its
  // own motion.
  Model zones_only = square_over_pinned_sheet(0.3);
  zones_only.scene.collisions.max_impulse_iterations = 0;
  const Scalar h = zones_only.scene.timestep();
  const Vec3 carried(0.2, -0.1, 0.05);
  std::vector<Vec3> motion = motions(zones_only, Vec3(0.1, 0.05, -2.0));
  for (std::size_t v = 0; v < motion.size(); ++v)
    if (zones_only.pin_of_vertex[v] >= 0) motion[v] = carried;
  CollisionPipeline pipeline(zones_only, CollisionSettings{});
  const CollisionCounters c = pipeline.resolve(zones_only.initial_positions, 0, h, motion, zones_only.scene.friction);
  EXPECT_GT(c.impact_zones, 0);
  EXPECT_EQ(c.fail_safes, 0);
  int carried_along = 0;
  for (std::size_t v = 0; v < motion.size(); ++v) {
    if (zones_only.pin_of_vertex[v] >= 0) {
      EXPECT_EQ(motion[v], carried) << v;
    }
    carried_along += int(v) >= zones_only.cloths[1].first_vertex && (motion[v] - carried).norm() < 1e-12;
  }
  EXPECT_GT(carried_along, 0);
  EXPECT_TRUE(collision_free(zones_only, zones_only.initial_positions, h, motion));
}

TEST(Collision, TheFailSafeKeepsOnlyTheCollidingVerticesAtTheirStart) {
  // With no impulse and no impact-zone rounds, a small square falls through the middle of a
  // large free sheet: the fail-safe stops the vertices of the collisions (their motion
  // becomes zero), every other vertex keeps its motion, and the step is free.
  const Model model = build_model(parse_scene(R"({"frame_time": 0.05, "frame_steps": 1,
    "cloths": [{"grid": {"size": [0.4, 0.4], "resolution": [8, 8]}},
               {"grid": {"size": [0.02, 0.02], "resolution": [1, 1]}, "transform": {"translate": [0.013, 0.007, 0.02]}}],
    "collisions": {"self": true, "thickness": 0.003, "max_impulse_iterations": 0, "max_zone_iterations": 0}})",
                                              "inline.json"));
  const Scalar h = model.scene.timestep();
  std::vector<Vec3> motion = motions(model, Vec3(0, 0, -2.0), Vec3(0, 0, 0.1));
  const std::vector<Vec3> before = motion;
  CollisionPipeline pipeline(model, CollisionSettings{});
  const CollisionCounters c = pipeline.resolve(model.initial_positions, 0, h, motion, model.scene.friction);
  EXPECT_EQ(c.fail_safes, 1);
  int stopped = 0, kept = 0;
  for (std::size_t v = 0; v < motion.size(); ++v) {
    if (motion[v] == Vec3::Zero()) {
      ++stopped;
    } else {
      EXPECT_EQ(motion[v], before[v]) << v;
      ++kept;
    }
  }
  EXPECT_GT(stopped, 0);
  EXPECT_GT(kept, stopped);  // the sheet's far part is untouched
  EXPECT_TRUE(collision_free(model, model.initial_positions, h, motion));
}

TEST(Collision, NoTestIsMadeOfPinnedAndObstacleVerticesThatStayStill) {
  // A 20 cm cloth of 8 x 8 quads lying 3 mm above the top of a still 1 m mesh box (4 mm
  // thickness), self-collision on. Its right half pinned and its left half falling 1 cm within
  // the step: every test of every round has a free or moving vertex (a clamped region resting
  // on a still support, the Cusick drape's, adds none). Pinned whole and still: not one
  // triangle pair. Pinned whole with the handle or the box moving: tests again.
  struct Case {
    const char* name;
    Scalar pinned_from;  // m: vertices at x >= this are pinned
    Vec3 handle_motion, box_velocity;
  };
  for (const Case& c : {Case{"half pinned", 0, Vec3::Zero(), Vec3::Zero()}, Case{"pinned still", -1, Vec3::Zero(), Vec3::Zero()},
                        Case{"handle moving", -1, Vec3(0.1, 0, 0), Vec3::Zero()}, Case{"box moving", -1, Vec3::Zero(), Vec3(0, 0, 0.1)}}) {
    std::ostringstream json;
    json << R"({"frame_time": 0.05, "frame_steps": 1,
      "cloths": [{"grid": {"size": [0.2, 0.2], "resolution": [8, 8]}, "transform": {"translate": [0, 0, 0.503]}}],
      "handles": [{"box": {"min": [)" << c.pinned_from - 1e-9 << R"(, -1, -1], "max": [1, 1, 1]}}],
      "obstacles": [{"mesh": ")" << DRAPE_SOURCE_DIR << R"(/scenes/meshes/box.obj", "motion": {"velocity": [)"
         << c.box_velocity.x() << ", " << c.box_velocity.y() << ", " << c.box_velocity.z() << R"(]}}],
      "collisions": {"self": true, "thickness": 0.004}})";
    const Model model = build_model(parse_scene(json.str(), "inline.json"));
    const Scalar h = model.scene.timestep();
    std::vector<Vec3> motion(model.vertex_count());
    for (std::size_t v = 0; v < motion.size(); ++v) motion[v] = model.pin_of_vertex[v] >= 0 ? c.handle_motion : Vec3(0, 0, -0.2);
    CollisionPipeline pipeline(model, CollisionSettings{});
    long tests = 0, idle = 0;
    pipeline.set_observer([&](const ccd::BatchInput& input, long) {
      const auto active = [&](int v) {
        return input.start[std::size_t(v)] != input.end[std::size_t(v)] ||
               (v < int(model.vertex_count()) && model.pin_of_vertex[std::size_t(v)] < 0);
      };
      for (const auto& p : input.vertex_face) ++tests, idle += !(active(p.vertex) || active(p.face[0]) || active(p.face[1]) || active(p.face[2]));
      for (const auto& p : input.edge_edge) ++tests, idle += !(active(p.edge_a[0]) || active(p.edge_a[1]) || active(p.edge_b[0]) || active(p.edge_b[1]));
    });
    const CollisionCounters counters = pipeline.resolve(model.initial_positions, 0, h, motion, 0);
    EXPECT_EQ(idle, 0) << c.name;
    if (std::string(c.name) == "pinned still") {
      EXPECT_EQ(counters.bvh_pairs, 0) << c.name;
      EXPECT_EQ(tests, 0) << c.name;
    } else {
      EXPECT_GT(counters.bvh_pairs, 0) << c.name;
      EXPECT_GT(tests, 0) << c.name;
    }
    std::printf("%s: %ld triangle pairs, %ld tests, %ld hits\n", c.name, counters.bvh_pairs, tests, counters.ccd_hits);
  }
}

TEST(Collision, FeaturesAreTestedWhenCloserThanTheThicknessAndNotWhenFarther) {
  // Two free square cloths of 2 x 2 quads, 20 cm wide, one over the other, at rest: their
  // features are tested (for proximity) when the sheets lie just within the 5 mm thickness,
  // and not at all just beyond it, where no gap can be kept and no collision found (the boxes
  // and feature volumes grown by half the thickness on each side; grown by all of it, they
  // listed pairs up to twice the thickness apart).
  for (const Scalar gap : {0.99, 1.01, 1.5}) {
    std::ostringstream json;
    json << R"({"frame_time": 0.05, "frame_steps": 1,
      "cloths": [{"grid": {"size": [0.2, 0.2], "resolution": [2, 2]}},
                 {"grid": {"size": [0.2, 0.2], "resolution": [2, 2]}, "transform": {"translate": [0.013, 0.007, )"
         << gap * 0.005 << R"(]}}],
      "collisions": {"self": true, "thickness": 0.005}})";
    const Model model = build_model(parse_scene(json.str(), "inline.json"));
    std::vector<Vec3> motion(model.vertex_count(), Vec3::Zero());
    CollisionPipeline pipeline(model, CollisionSettings{});
    long across = 0;  // tests of one cloth's feature against the other's
    pipeline.set_observer([&](const ccd::BatchInput& input, long) {
      const int second = model.cloths[1].first_vertex;
      for (const auto& p : input.vertex_face) across += (p.vertex >= second) != (p.face[0] >= second);
      for (const auto& p : input.edge_edge) across += (p.edge_a[0] >= second) != (p.edge_b[0] >= second);
    });
    const CollisionCounters c = pipeline.resolve(model.initial_positions, 0, model.scene.timestep(), motion, 0);
    EXPECT_EQ(c.ccd_hits, 0) << gap;
    EXPECT_EQ(c.proximity_impulses, 0) << gap;  // at rest: nothing to stop
    if (gap < 1)
      EXPECT_GT(across, 0) << gap;
    else
      EXPECT_EQ(across, 0) << gap;
  }
}
