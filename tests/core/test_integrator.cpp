// The implicit step: a hanging cloth settles, energy never grows without input, the two
// solvers agree, handles follow their motion, analytic obstacles are never entered.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "drape/core/integrator.h"
#include "drape/ccd/distance.h"
#include "drape/core/obstacle.h"
#include "struck_curtain.h"

using namespace drape;

namespace {

Model model_of(const std::string& json) { return build_model(parse_scene(json, "inline.json")); }

const char* HANGING = R"({"frame_time": 0.04, "frame_steps": 4,
  "cloths": [{"grid": {"size": [1, 1], "resolution": [10, 10]}, "material": {"damping": 0.01, "air_damping": 1.0}}],
  "handles": [{"corners": ["top-left", "top-right"]}]})";

Scalar total_energy(const Model& m, const State& s) { return kinetic_energy(m, s) + potential_energy(m, s); }

}  // namespace

TEST(Integrator, HangingClothSettles) {
  const Model model = model_of(HANGING);
  State state = initial_state(model);
  Integrator integrator(model);
  Scalar peak = 0;
  for (int step = 0; step < 1000; ++step) {  // 10 seconds
    ASSERT_TRUE(integrator.step(state).ok);
    peak = std::max(peak, kinetic_energy(model, state));
  }
  EXPECT_GT(peak, 1e-3);                                // it swung
  EXPECT_LT(kinetic_energy(model, state), 1e-6 * peak);  // and came to rest
  EXPECT_LT(max_stretch(model, state), 1.05);           // held by its springs, not torn
  // At rest it hangs below its pins.
  for (const Vec3& x : state.positions) EXPECT_LE(x.z(), 1e-9);
}

TEST(Integrator, EnergyNeverGrowsWithoutInput) {
  // Static pins, gravity only: backward Euler dissipates, so kinetic plus potential energy
  // must not increase from one step to the next.
  const Model model = model_of(HANGING);
  State state = initial_state(model);
  Integrator integrator(model);
  Scalar previous = total_energy(model, state);
  for (int step = 0; step < 200; ++step) {
    ASSERT_TRUE(integrator.step(state).ok);
    const Scalar now = total_energy(model, state);
    EXPECT_LE(now, previous + 1e-9 * std::abs(previous)) << "step " << step;
    previous = now;
  }
}

TEST(Integrator, CholmodAndConjugateGradientAgree) {
  const std::string base = R"({"frame_time": 0.04, "frame_steps": 4, "cloths": [{"grid": {"resolution": [8, 8]}}],
    "handles": [{"corners": ["top-left"]}], "solver": {"type": ")";
  const Model direct = model_of(base + R"(cholmod"}})");
  const Model iterative = model_of(base + R"(cg", "tolerance": 1e-12, "max_iterations": 100000}})");
  State a = initial_state(direct), b = initial_state(iterative);
  Integrator ia(direct);
  Integrator ib(iterative);
  int iterations = 0;
  for (int step = 0; step < 50; ++step) {
    ASSERT_TRUE(ia.step(a).ok);
    const StepReport r = ib.step(b);
    ASSERT_TRUE(r.ok);
    EXPECT_TRUE(r.solver_converged);
    iterations += r.solver_iterations;
  }
  EXPECT_GT(iterations, 50 * 10);  // it did iterate
  Scalar worst = 0;
  for (std::size_t v = 0; v < a.positions.size(); ++v) worst = std::max(worst, (a.positions[v] - b.positions[v]).norm());
  EXPECT_LT(worst, 1e-6);
  EXPECT_EQ(ia.analyses(), 1);  // the symbolic factorisation was reused
}

TEST(Integrator, AReusedFactorisationGivesTheFreshOnesAnswer) {
  // Each solve's own factorisation (factor_reuse 0) against the last one preconditioning a
  // conjugate gradient to 1e-10 of the solution in the matrix's norm: the hanging cloth
  // swinging down for 5 s (the matrix changes fast: mostly factorised afresh), and a cloth
  // falling freely for 0.5 s (one factorisation serves). After contacts begin the two part
  // like any two runs a rounding apart (a contact released or not), which this does not test.
  const std::string hanging = std::string(HANGING).substr(0, std::string(HANGING).size() - 1);
  const std::string falling = R"({"frame_time": 0.04, "frame_steps": 8,
    "cloths": [{"grid": {"size": [1, 1], "resolution": [12, 12]}, "transform": {"translate": [0, 0, 2]}}])";
  for (const auto& [scene, steps] : {std::pair{hanging, 500}, std::pair{falling, 100}}) {
    const Model fresh = model_of(scene + R"(, "solver": {"factor_reuse": 0}})");
    const Model reused = model_of(scene + R"(, "solver": {"factor_reuse": 8}})");
    State a = initial_state(fresh), b = initial_state(reused);
    Integrator ia(fresh), ib(reused);
    for (int step = 0; step < steps; ++step) {
      ASSERT_TRUE(ia.step(a).ok);
      ASSERT_TRUE(ib.step(b).ok);
    }
    Scalar worst = 0;
    for (std::size_t v = 0; v < a.positions.size(); ++v) worst = std::max(worst, (a.positions[v] - b.positions[v]).norm());
    EXPECT_LT(worst, 1e-8) << scene;
    EXPECT_LE(ib.factorisations(), ia.factorisations()) << scene;
    EXPECT_EQ(ib.analyses(), 1) << scene;
    if (scene == falling) {
      EXPECT_LT(ib.factorisations(), 5) << "of " << ia.factorisations();
    }
  }
}

TEST(Integrator, HandlesFollowTheirMotionExactly) {
  const Model model = model_of(R"({"frame_time": 0.04, "frame_steps": 4, "cloths": [{"grid": {"resolution": [6, 6]}}],
    "handles": [{"corners": ["top-left", "top-right"], "motion": {"velocity": [0, 0, 0.5], "angular_velocity": [0, 0, 1]}}]})");
  State state = initial_state(model);
  Integrator integrator(model);
  for (int step = 0; step < 40; ++step) ASSERT_TRUE(integrator.step(state).ok);
  for (const Pin& pin : model.pins) {
    const Vec3 expected = model.scene.handles[pin.handle].motion.position(model.initial_positions[pin.vertex], state.time);
    EXPECT_LT((state.positions[pin.vertex] - expected).norm(), 1e-12);
  }
}

TEST(Integrator, ClothStaysOutsideAnalyticObstacles) {
  const Model model = model_of(R"({"frame_time": 0.04, "frame_steps": 4,
    "cloths": [{"grid": {"size": [1, 1], "resolution": [12, 12]}, "transform": {"translate": [0, 0, 0.8]}}],
    "obstacles": [{"sphere": {"center": [0, 0, 0.3], "radius": 0.3}}, {"plane": {}}],
    "collisions": {"thickness": 0.01}})");
  State state = initial_state(model);
  Integrator integrator(model);
  int contacts = 0;
  for (int step = 0; step < 100; ++step) {
    const StepReport r = integrator.step(state);
    ASSERT_TRUE(r.ok);
    contacts += r.obstacle_contacts;
    for (const Obstacle& o : model.obstacles)
      EXPECT_GE(distance_to_obstacle(o, state.time, state.positions), 0.01 - 1e-12) << "step " << step;
  }
  EXPECT_GT(contacts, 0);
}

TEST(Integrator, MovingSphereCarriesTheClothWithFriction) {
  // A sphere rising under a cloth lifts it; with friction the cloth resting on top moves with it.
  const Model model = model_of(R"({"frame_time": 0.04, "frame_steps": 4, "gravity": [0, 0, -9.81],
    "cloths": [{"grid": {"size": [0.5, 0.5], "resolution": [6, 6]}, "transform": {"translate": [0, 0, 0.31]}}],
    "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.3}, "motion": {"velocity": [0, 0, 1]}}],
    "collisions": {"thickness": 0.01}, "friction": 1.0})");
  State state = initial_state(model);
  Integrator integrator(model);
  for (int step = 0; step < 50; ++step) ASSERT_TRUE(integrator.step(state).ok);
  // After 0.5 s the sphere's top is at 0.8; the cloth's centre vertex rides on it.
  const int centre = 3 * 7 + 3;
  EXPECT_NEAR(state.positions[centre].z(), 0.8 + 0.01, 0.02);
}

namespace {

// A square cloth lying on a plane tilted 20 degrees about y, with the given friction: its
// mean displacement along the slope after `seconds`.
Scalar slide_on_incline(Scalar friction, Scalar seconds, const std::string& solver = R"({"type": "cholmod"})") {
  const Scalar tilt = 20 * M_PI / 180;
  std::ostringstream json;
  json.precision(17);
  json << R"({"frame_time": 0.03333333333333333, "cloths": [{"grid": {"size": [0.3, 0.3], "resolution": [10, 10]},
    "transform": {"translate": [0, 0, 0.0051], "rotate": [20, 0, 1, 0]}}],
    "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [)" << std::sin(tilt) << ", 0, " << std::cos(tilt) << R"(]}}],
    "friction": )" << friction << R"(, "solver": )" << solver << "}";
  const Model model = model_of(json.str());
  State state = initial_state(model);
  Integrator integrator(model);
  const int steps = int(std::lround(seconds / model.scene.timestep()));
  for (int step = 0; step < steps; ++step) EXPECT_TRUE(integrator.step(state).ok);
  const Vec3 down_slope(std::cos(tilt), 0, -std::sin(tilt));  // along the plane, downhill
  Scalar along = 0;
  for (std::size_t v = 0; v < state.positions.size(); ++v) along += (state.positions[v] - model.initial_positions[v]).dot(down_slope);
  return along / Scalar(state.positions.size());
}

}  // namespace

// Coulomb friction on a resting contact, the block-on-an-incline test: below the friction angle
// (tan 20 degrees = 0.364 < 0.5) the cloth stays; above it (friction 0.2) it slides with the
// acceleration g (sin 20 - 0.2 cos 20) = 1.511 m/s^2, 0.756 m in the first second (the air's
// default damping slows it a little).
TEST(Integrator, FrictionHoldsAClothOnAnInclineAndLetsItSlideWhenTooSteep) {
  // The projective solver holds its contacts and their friction in its objective (L-BFGS).
  for (const char* solver : {R"({"type": "cholmod"})", R"({"type": "projective"})"}) {
    EXPECT_LT(std::abs(slide_on_incline(0.5, 1.0, solver)), 5e-4) << solver;
    const Scalar slid = slide_on_incline(0.2, 1.0, solver);
    EXPECT_GT(slid, 0.95 * 0.5 * 1.511) << solver;
    EXPECT_LT(slid, 1.0 * 0.5 * 1.511) << solver;
  }
}

// Strain limiting (material.strain_limit): a cloth flung apart in every direction (no gravity,
// no obstacle) keeps every structural spring within its limit at every step's end, and the
// limiting's equal and opposite velocity changes keep its momentum; without a limit it
// stretches past it.
TEST(Integrator, StrainLimitingKeepsTheLimitAndTheMomentum) {
  const auto fling = [](const std::string& material) {
    const Model model = model_of(R"({"frame_time": 0.02, "frame_steps": 2, "gravity": [0, 0, 0],
      "cloths": [{"grid": {"size": [1, 1], "resolution": [8, 8]}, "material": )" + material + "}]}");
    State state = initial_state(model);
    for (std::size_t v = 0; v < state.positions.size(); ++v) state.velocities[v] = 10 * state.positions[v];  // outward
    Vec3 momentum = Vec3::Zero();
    for (std::size_t v = 0; v < state.positions.size(); ++v) momentum += model.masses[v] * state.velocities[v];
    Integrator integrator(model);
    Scalar stretch = 1;
    int limited = 0;
    for (int k = 0; k < 20; ++k) {
      const StepReport r = integrator.step(state);
      EXPECT_TRUE(r.ok) << r.failure;
      limited += r.strain_limited;
      stretch = std::max(stretch, max_stretch(model, state));
      Vec3 now = Vec3::Zero();
      for (std::size_t v = 0; v < state.positions.size(); ++v) now += model.masses[v] * state.velocities[v];
      EXPECT_LT((now - momentum).norm(), 1e-12) << "step " << k;
    }
    return std::make_pair(stretch, limited);
  };
  const auto [free_stretch, none] = fling(R"({"stretch": 0.5, "shear": 0.05, "bend": 0})");
  EXPECT_GT(free_stretch, 1.1);
  EXPECT_EQ(none, 0);
  const auto [limited_stretch, corrections] = fling(R"({"stretch": 0.5, "shear": 0.05, "bend": 0, "strain_limit": 1.05})");
  EXPECT_LE(limited_stretch, 1.05 * (1 + 1e-9));
  EXPECT_GT(corrections, 0);
}

// A spring that starts a step past its limit (the collision response may leave one) is not
// snapped back within the step (its excess over h as a closing speed: 0.025 m over 0.01 s):
// the limit takes back STRAIN_RECOVERY (half) of its excess in a step, so a cloth at rest with
// one corner pulled 20 % out along an edge, whose springs pull it back faster than that, moves
// exactly as without a limit.
TEST(Integrator, StrainLimitingDoesNotSnapBackASpringAlreadyPastItsLimit) {
  const auto pulled = [](const std::string& limit) {
    const Model model = model_of(R"({"frame_time": 0.02, "frame_steps": 2, "gravity": [0, 0, 0],
      "cloths": [{"grid": {"size": [1, 1], "resolution": [8, 8]},
                  "material": {"stretch": 0.5, "shear": 0.05, "bend": 0)" + limit + "}}]}");
    State state = initial_state(model);
    state.positions[0].x() -= 0.2 * 0.125;  // corner 0 away from its neighbour along x
    Integrator integrator(model);
    const StepReport r = integrator.step(state);
    EXPECT_TRUE(r.ok) << r.failure;
    EXPECT_EQ(r.strain_limited, 0);
    return state.velocities;
  };
  const std::vector<Vec3> free = pulled(""), limited = pulled(R"(, "strain_limit": 1.05)");
  for (std::size_t v = 0; v < free.size(); ++v) EXPECT_EQ(limited[v], free[v]) << v;
}

// ... and it does take back half: with springs too weak to pull the corner back themselves,
// the stretched spring ends the step half its excess shorter (left where it was, it would
// ratchet up by whatever the response adds each step).
TEST(Integrator, StrainLimitingTakesBackHalfTheExcessOfASpringPastItsLimit) {
  const Model model = model_of(R"({"frame_time": 0.02, "frame_steps": 2, "gravity": [0, 0, 0],
    "cloths": [{"grid": {"size": [1, 1], "resolution": [8, 8]},
                "material": {"stretch": 1e-9, "shear": 1e-9, "bend": 0, "damping": 0, "air_damping": 0, "strain_limit": 1.05}}]})");
  State state = initial_state(model);
  state.positions[0].x() -= 0.2 * 0.125;  // corner 0 away from vertex 1 along x
  const Scalar rest = 0.125, start = (state.positions[1] - state.positions[0]).norm();
  Integrator integrator(model);
  const StepReport r = integrator.step(state);
  ASSERT_TRUE(r.ok) << r.failure;
  EXPECT_GT(r.strain_limited, 0);
  const Scalar end = (state.positions[1] - state.positions[0]).norm();
  EXPECT_NEAR(end, start - STRAIN_RECOVERY * (start - 1.05 * rest), 1e-6 * rest) << "start " << start;
}

namespace {

// A scene run step by step to its last frame, with its worst figures after any step: the
// largest structural stretch, and the largest length over its limit of the limited structural
// and of the limited shear springs.
struct LimitedRun {
  std::string failure;  // empty if every step succeeded
  Scalar largest = 1, over_limit = 0, shear_over_limit = 0;
  int halvings = 0;  // summed over the steps (StepReport::step_halvings)
};

LimitedRun run_limited(const Model& model) {
  LimitedRun run;
  State state = initial_state(model);
  Integrator integrator(model);
  for (int k = 0; k < model.scene.frames * model.scene.frame_steps; ++k) {
    const StepReport r = integrator.step(state);
    if (!r.ok) {
      run.failure = r.failure;
      return run;
    }
    run.halvings += r.step_halvings;
    run.largest = std::max(run.largest, max_stretch(model, state));
    for (const Spring& s : model.springs) {
      if (!(s.limit > 0)) continue;
      Scalar& worst = s.kind == SpringKind::Shear ? run.shear_over_limit : run.over_limit;
      worst = std::max(worst, (state.positions[s.i] - state.positions[s.j]).norm() / (s.limit * s.rest_length));
    }
  }
  return run;
}

}  // namespace

// Issue 20's target for strain limiting: a curtain pinned along its top and struck by a ball
// keeps every limited spring within its limit plus 1 % after every step, though the collision
// response moves the cloth after the limit acts (the limit and the response are taken again
// while a spring is past it, STRAIN_RESPONSE_ROUNDS). Largest stretch of a structural spring
// over its limit: springs at 4 and 8 m/s 1.0149 / 1.05 and 1.0500 / 1.05; the royal-target
// fabric at 4 and 8 m/s 1.0504 / 1.05 and 1.0559 / 1.05, where without the rounds its contact
// vertices, dragged by the ball's friction, left their neighbours at 1.18 (docs/materials.md).
// With a shear locking angle of 5 degrees the fabric's diagonals are limited to 1.0948 too,
// with either solver.
TEST(Integrator, StrainLimitingHoldsAStruckCurtainWithinTheLimitEveryStep) {
  const std::string springs = R"({"density": 0.15, "stretch": 2000, "shear": 200, "bend": 0.2, "strain_limit": 1.05})";
  const std::string fabric = R"({"preset": "royal-target", "strain_limit": 1.05})";
  const std::string locked = R"({"preset": "royal-target", "strain_limit": 1.05, "shear_locking_angle": 5})";
  struct Case {
    std::string material;
    double speed;
    bool projective;
  };
  for (const auto& [material, speed, projective] :
       {Case{springs, 4, false}, Case{springs, 8, false}, Case{fabric, 4, false}, Case{fabric, 8, false},
        Case{locked, 4, false}, Case{locked, 8, false}, Case{locked, 8, true}}) {
    Scene scene = parse_scene(struck_curtain_json(material, speed, 0.3), "inline.json");
    if (projective) scene.solver.kind = SolverKind::Projective;
    const auto [failure, largest, over_limit, shear_over_limit, halvings] = run_limited(build_model(scene));
    ASSERT_TRUE(failure.empty()) << failure;
    EXPECT_LE(over_limit, 1.01) << material << " at " << speed << " m/s";
    EXPECT_LE(shear_over_limit, 1.01) << material << " at " << speed << " m/s";
    EXPECT_GT(largest, 1.01) << material << " at " << speed << " m/s";  // struck hard enough to stretch
    if (material == locked) {
      EXPECT_GT(shear_over_limit, 0.99) << speed << " m/s";  // sheared to the limit
    }
  }
}

// A curtain pinned at its top corners, struck by a ball of triangles (a mesh obstacle, the
// collision pipeline's) that goes on 1.5 m past it: the cloth wraps the ball and must slide off
// it. Held for the step, the pulls of its contacts behind the ball moved them with the ball and
// the cloth was dragged on: it stretched to 1.55 times its rest length at 6 m/s and 1.71 at
// 8 m/s. With friction (0.3 is the default) the rounds of limit and response could not undo a
// step's travel of the ball over the cloth and the excess grew step by step: 1.61 at 0.3 and
// 2.21 at 0.6, where the run stopped; the step is now taken again in parts while it ends past
// the limit (STRAIN_RETAKE, docs/collisions.md).
TEST(Integrator, StrainLimitingHoldsACurtainStruckByAMovingMeshBall) {
  // With friction, 8 frames (0.27 s): at 7910fd6 the curtain reached 1.612 in frame 7 at 0.3
  // and the run stopped in frame 6 at 0.6.
  struct Case {
    double speed, friction;
    int frames;
  };
  for (const auto& [speed, friction, frames] : {Case{6, 0, 20}, Case{8, 0, 20}, Case{6, 0.3, 8}, Case{6, 0.6, 8}}) {
    const std::string json = R"({"frame_time": 0.033333333333333333, "frame_steps": 8, "frames": )" + std::to_string(frames) + R"(,
      "cloths": [{"grid": {"size": [1, 1], "resolution": [24, 24]}, "transform": {"translate": [0, 0, 1.2], "rotate": [90, 1, 0, 0]},
                  "material": {"preset": "royal-target", "strain_limit": 1.1}}],
      "handles": [{"cloth": 0, "corners": ["top-left", "top-right"]}],
      "obstacles": [{"mesh": ")" + std::string(DRAPE_SOURCE_DIR) +
                             R"(/scenes/meshes/icosphere.obj", "transform": {"translate": [0, -0.3, 1.1], "scale": 0.15},
                     "motion": {"velocity": [0, )" + std::to_string(speed) + R"(, 0], "end": )" + std::to_string(1.8 / speed) +
                             R"(}}],
      "friction": )" + std::to_string(friction) + R"(, "collisions": {"self": true, "thickness": 0.004}})";
    const auto [failure, largest, over_limit, shear_over_limit, halvings] = run_limited(model_of(json));
    ASSERT_TRUE(failure.empty()) << failure;
    EXPECT_LE(over_limit, 1.01) << speed << " m/s, friction " << friction;
    EXPECT_GT(largest, 1.09) << speed << " m/s, friction " << friction;  // struck hard enough to reach the limit
  }
}

// A denim cloth (1 cm cells, 3 mm thickness, no strain limit) thrown at 3 m/s onto a box mesh
// moving at 0.3 m/s, 6 steps a frame: in frame 6 the box's top corner met it, the contacts on
// the box's faces stopped the vertices on either side and the spring across the corner took
// the motion, 1.514 times its rest length (1.195 at 12 steps a frame, 1.091 with the box
// still; the step's energy within tolerance). A step that takes the cloth past
// limits.stretch_warn from below it is now taken again in parts while they halve it: every
// step ends within the warning limit (without the retake the test fails at frame 6).
TEST(Integrator, AStepThatSpikesTheStretchPastTheWarningIsTakenAgainInParts) {
  const Model model = model_of(R"({"frame_time": 0.033333333333333333, "frame_steps": 6,
    "cloths": [{"grid": {"size": [0.5, 0.5], "resolution": [50, 50]}, "transform": {"translate": [-0.2, -0.25, 0.9]},
                "material": {"preset": "11oz-black-denim"}, "velocity": [0, 0, -3]}],
    "obstacles": [{"mesh": ")" + std::string(DRAPE_SOURCE_DIR) + R"(/scenes/meshes/box.obj", "transform": {"scale": 0.4, "translate": [0, 0, 0.2]},
                   "motion": {"velocity": [0.3, 0, 0]}},
                  {"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
    "collisions": {"self": true, "obstacles": true, "thickness": 0.003}})");
  State state = initial_state(model);
  Integrator integrator(model);
  Scalar largest = 1;
  int halved_steps = 0;
  for (int k = 0; k < 6 * 6; ++k) {
    const StepReport report = integrator.step(state);
    ASSERT_TRUE(report.ok) << report.failure;
    largest = std::max(largest, max_stretch(model, state));
    halved_steps += report.step_halvings > 0;
  }
  EXPECT_LE(largest, model.scene.limits.stretch_warn);
  EXPECT_GT(largest, 1.05);  // the corner did strain it
  EXPECT_GT(halved_steps, 0);
}

// Issue 20's other target for strain limiting: every shipped scene with a limit of 1.1 on every
// cloth keeps its structural springs within 1.1 plus 1 % after every step (the first frames;
// bench/penetration_runs.sh runs the scenes in full), and its energy within the run's warning
// limit (fast_drop's cloth thrown at 30 m/s stopped its run in the first frame with 145.6 J
// against a bound of 24.8 J, its retakes cut short: docs/collisions.md).
TEST(Integrator, StrainLimitingHoldsEveryShippedScene) {
  const std::map<std::string, int> frames = {{"cloth_fold", 14}, {"mesh_obstacle", 10}, {"fast_drop", 3}, {"drape_sphere", 10},
                                             {"hanging", 6},     {"flag", 6},           {"cantilever", 20}, {"tablecloth", 3}};
  for (const auto& [name, count] : frames) {
    Scene scene = load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/" + name + ".json");
    for (ClothSpec& cloth : scene.cloths) cloth.material.strain_limit = 1.1;
    const Model model = build_model(scene);
    State state = initial_state(model);
    Integrator integrator(model);
    Scalar largest = 1, bound = kinetic_energy(model, state) + potential_energy(model, state), excess = 0;
    for (int k = 0; k < count * scene.frame_steps; ++k) {
      const StepReport r = integrator.step(state);
      ASSERT_TRUE(r.ok) << name << ": " << r.failure;
      largest = std::max(largest, max_stretch(model, state));
      bound += r.external_work;
      excess = std::max(excess, kinetic_energy(model, state) + potential_energy(model, state) - bound);
    }
    EXPECT_LE(largest, 1.1 * 1.01) << name;
    EXPECT_LE(excess, scene.limits.energy_warn * energy_scale(model)) << name;
  }
}

// A knit with a strain limit of 1.1 dropped on a needle's tip hangs from the few vertices the
// tip holds, every spring around them at the limit. The limit's rounds pulled those vertices
// down into the tip and the response pushed them out again, round after round: each ran out of
// rounds (the excess falling by 5-8 % a round) and the steps of frames 6 to 9 were taken again
// in parts (55 halvings in all, 14.4 s against 4.0 s of this cloth's 14 frames by drape run).
// Heavier in the limit's sweeps once the response has moved them (HELD_WEIGHT), the held
// vertices bear the pull and the rounds end within the slack.
TEST(Integrator, StrainLimitingHoldsAKnitCaughtOnANeedleWithoutTakingStepsAgain) {
  const Model model = model_of(R"({"frames": 10,
      "cloths": [{"grid": {"size": [0.8, 0.8], "resolution": [32, 32]}, "transform": {"translate": [0.006, 0.004, 0.35]},
                  "material": {"preset": "navy-sparkle-sweat", "strain_limit": 1.1}}],
      "obstacles": [{"mesh": ")" + std::string(DRAPE_SOURCE_DIR) + R"(/bench/user_scenes/needle.obj"}, {"plane": {}}],
      "collisions": {"self": true, "thickness": 0.003}})");
  const auto [failure, largest, over_limit, shear_over_limit, halvings] = run_limited(model);
  ASSERT_TRUE(failure.empty()) << failure;
  EXPECT_GT(over_limit, 0.99);  // the cloth hangs from the tip at its limit
  EXPECT_LE(over_limit, 1.01);
  EXPECT_LE(shear_over_limit, 1.01);
  EXPECT_EQ(halvings, 0);
}

// stats.csv's broad_ms and bvh_pairs count the searches for the contacts held in the solve as
// well as the detection rounds (docs/collisions.md): the mesh obstacles' search (its tree's
// overlapping pairs at the step's start) was left out of both until session 29, while the
// cloth's own was counted. A cloth lying 1 mm over a box (within reach of its top) takes one
// step: the step's pairs exceed those of its detection rounds by the search's.
TEST(Integrator, TheSolveContactsSearchOfAMeshObstacleIsCounted) {
  const Model model = model_of(R"({"frame_time": 0.01, "frame_steps": 1, "frames": 1,
      "cloths": [{"grid": {"size": [0.4, 0.4], "resolution": [8, 8]}, "transform": {"translate": [0, 0, 0.501]}}],
      "obstacles": [{"mesh": ")" + std::string(DRAPE_SOURCE_DIR) + R"(/scenes/meshes/box.obj"}],
      "collisions": {"self": false}})");
  State state = initial_state(model);
  Integrator integrator(model);
  ASSERT_NE(integrator.collisions(), nullptr);
  long round_pairs = 0;
  integrator.collisions()->set_observer([&](const ccd::BatchInput&, long pairs) { round_pairs += pairs; });
  const StepReport r = integrator.step(state);
  ASSERT_TRUE(r.ok) << r.failure;
  EXPECT_GT(round_pairs, 0);
  // Each of the 128 cloth triangles overlaps at least one of the box top's within reach.
  EXPECT_GE(r.collisions.bvh_pairs, round_pairs + 128);
}

TEST(Integrator, AMeshObstaclesDistanceIsTheNearestOfEveryPointAndTriangle) {
  // distance_to_obstacle skips the boxes beyond the nearest triangle found: the same number as
  // every point against every triangle, for clouds near and far, inside and touching the
  // cylinder of the Cusick support (1,024 triangles, long thin fans on its caps).
  const Model model = model_of(R"({"cloths": [{"grid": {"resolution": [2, 2]}}], "obstacles": [{"mesh": ")" +
                               std::string(DRAPE_SOURCE_DIR) + R"(/scenes/meshes/cusick_support.obj", "transform": {"rotate": [20, 1, 2, 0]}}]})");
  const Obstacle& obstacle = model.obstacles[0];
  const std::vector<Vec3> v = posed_vertices(obstacle, 0);
  std::mt19937 random(3);
  for (const Scalar spread : {0.01, 0.1, 1.0, 10.0}) {
    std::normal_distribution<Scalar> at(0, spread);
    std::vector<Vec3> points(300);
    for (Vec3& p : points) p = Vec3(at(random), at(random), 0.15 + at(random));
    points[0] = v[7];  // touching: 0
    if (spread > 0.5) points[0] = Vec3(0.3, 0.3, 0.3);
    Scalar every = std::numeric_limits<Scalar>::infinity();
    for (const Vec3& p : points)
      for (const Triangle& t : obstacle.mesh.triangles)
        every = std::min(every, ccd::closest_point_triangle<Scalar>(p, v[t[0]], v[t[1]], v[t[2]]).distance_squared);
    EXPECT_EQ(distance_to_obstacle(obstacle, 0, points), std::sqrt(every)) << spread;
  }
}

TEST(Integrator, AClampedClothsContactsOverASupportsRimAreHeldInTheSolve) {
  // scenes/cusick_drape.json: the ring of free vertices next to the clamp lies over the
  // support's rim, its edges' and triangles' contacts with the rim sharing pinned corners.
  // Held in the solve with their pinned part in the target, nothing is left to the response;
  // left to it, about 90 proximity impulses stopped that ring every step of frames 2-3 and
  // each step spread them through a second factorisation.
  const Model model = build_model(load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/cusick_drape.json"));
  State state = initial_state(model);
  Integrator integrator(model);
  for (int s = 0; s < 10; ++s) ASSERT_TRUE(integrator.step(state).ok);
  long impulses = 0;
  const int before = integrator.factorisations();
  for (int s = 0; s < 20; ++s) {
    const StepReport r = integrator.step(state);
    ASSERT_TRUE(r.ok) << r.failure;
    impulses += r.collisions.proximity_impulses;
  }
  EXPECT_EQ(impulses, 0);
  EXPECT_LE(integrator.factorisations() - before, 25);
}

TEST(Integrator, AnObstaclesVertexUnderAClothEdgeIsHeldInTheSolve) {
  // A cloth held on a box's top overhangs its rim: the edge along y = 0 from the last held
  // vertex (x = 0.4606) to the first free one (x = 0.5006) lies over the box's rim vertex
  // (0.5, 0, 0.5), the grid's other edges over the rim's edges. That vertex's closest point is on
  // the cloth's edge, inside no triangle, and the ends of the box's edges: it was no contact of
  // the solve, and the response stopped that edge with an impulse in every step (10 a frame
  // from frame 7 on; the Cusick discs cut from a grid along the support's axes, 4 a step).
  const Model model = model_of(R"({"frame_time": 0.033333333333333333, "frame_steps": 10,
      "cloths": [{"grid": {"size": [0.6, 0.4], "resolution": [15, 10]}, "transform": {"translate": [0.3206, 0, 0.505]},
                  "material": {"preset": "gray-interlock"}}],
      "handles": [{"box": {"min": [0, -1, 0], "max": [0.47, 1, 1]}}],
      "obstacles": [{"mesh": ")" + std::string(DRAPE_SOURCE_DIR) + R"(/scenes/meshes/box.obj"}],
      "collisions": {"self": false}})");
  State state = initial_state(model);
  Integrator integrator(model);
  for (int s = 0; s < 80; ++s) ASSERT_TRUE(integrator.step(state).ok);
  long impulses = 0;
  for (int s = 0; s < 60; ++s) {
    const StepReport r = integrator.step(state);
    ASSERT_TRUE(r.ok) << r.failure;
    impulses += r.collisions.proximity_impulses;
  }
  EXPECT_EQ(impulses, 0);
}
