// peer_bench: whole frames of drape beside Bullet 3.24's classic soft body, in one run, on the
// same scenes (issue 17): a 2 m cloth of N x N nodes dropped from 2.5 m onto a sphere (radius
// 0.5 m, centre 1 m above a ground plane), 30 frames a second, 8 steps a frame.
//
// Bullet is set up as its own SoftDemo cloth: btSoftBodyHelpers::CreatePatch N x N with
// diagonals, total mass 1 kg, kLST 0.4 for the stretch, shear and bending links, bending links
// of distance 2, piterations 10, collision margin 0.02, the sphere and a static box as the
// ground, stepSimulation with 8 fixed substeps a frame, VF_SS when self-collision is asked.
// drape runs the same geometry with its default material and the solvers named.
//
// Each run is a child process (its peak resident memory its own). Every frame of both sides
// goes through the same independent check: vertices inside the sphere, vertices under the
// ground, frames with intersecting cloth triangles (drape's exact penetration check, which
// shares no code with either side's collision handling), the largest stretch of a grid edge.
//
// drape may take fewer steps a frame than Bullet's 8 where its results stay correct (issue 17):
// --drape-steps lists the counts to run, each a row of its own, checked the same way, with its
// halvings (a step that made energy taken again in parts: log2 of the kept attempt's parts).
//
//   peer_bench [--cases small,fast,large,large-self] [--solvers projective,cholmod] [--drape-steps 8,2]
//              [--frames 120] [--large-frames 20]
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "child_process.h"
#include "drape/ccd_eval/evaluation.h"
#include "drape/core/integrator.h"
#include "drape/core/linear_solver.h"
#include "drape/core/penetration.h"

using namespace drape;

namespace {

constexpr Scalar FRAME_TIME = 1.0 / 30;
constexpr int STEPS_PER_FRAME = 8;  // Bullet's substeps, and drape's unless --drape-steps says
constexpr Scalar CLOTH_SIZE = 2, DROP_HEIGHT = 2.5;
const Vec3 SPHERE_CENTRE(0, 0, 1);
constexpr Scalar SPHERE_RADIUS = 0.5;
// A frame is "in contact" when a vertex is this close to the sphere or the ground (m): more
// than either side's contact gap (drape's 5 mm thickness, Bullet's 2 cm margin).
constexpr Scalar CONTACT_DISTANCE = 0.05;

struct Case {
  std::string name;
  int nodes = 32;        // per side
  Scalar speed = 0;      // initial downward speed, m/s
  bool self = false;
  int frames = 120;
  int drape_steps = STEPS_PER_FRAME;  // drape's steps a frame
};

// What one side did, written by the child through a pipe (plain data only).
struct Result {
  bool ok = false;
  char failure[160] = {};
  int frames = 0;
  double falling_ms = 0, contact_ms = 0;  // medians over the frames of each kind (0: none)
  int falling_frames = 0, contact_frames = 0;
  double solve_ms_per_step = 0;           // drape: median solve time a step
  double falling_solve_ms = 0, contact_solve_ms = 0;  // drape: the same over the steps of each kind of frame (0: none)
  double falling_broad_ms = 0;            // drape: median broad phase a step over the falling frames' steps
  long falling_pairs = 0;                 // drape: candidate triangle pairs over the falling frames' steps, summed
  long inside_sphere = 0;                 // vertex-frames inside the ball
  long under_ground = 0;                  // vertex-frames below z = 0
  int intersecting_frames = 0;            // frames with cloth triangles meeting (not sharing a vertex)
  double max_stretch = 1;                 // grid edges (axis-aligned in the rest grid)
  long halvings = -1;                     // drape: StepReport::step_halvings summed (-1: not drape)
  long peak_kib = 0;
};

std::string scene_json(const Case& c, const std::string& solver) {
  char text[1024];
  std::snprintf(text, sizeof text,
                R"({"frame_time": %.17g, "frame_steps": %d, "frames": %d,
                    "cloths": [{"grid": {"size": [%g, %g], "resolution": [%d, %d]},
                                "transform": {"translate": [0, 0, %g]}, "velocity": [0, 0, %g]}],
                    "obstacles": [{"sphere": {"center": [0, 0, 1], "radius": %g}},
                                  {"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
                    "solver": {"type": "%s"}, "collisions": {"self": %s}})",
                FRAME_TIME, c.drape_steps, c.frames, CLOTH_SIZE, CLOTH_SIZE, c.nodes - 1, c.nodes - 1, DROP_HEIGHT,
                -c.speed, SPHERE_RADIUS, solver.c_str(), c.self ? "true" : "false");
  return text;
}

// The independent check of one frame, added to result.
void check_frame(const Model& model, const std::vector<Vec3>& x, int nodes, Result& result) {
  for (const Vec3& p : x) {
    if ((p - SPHERE_CENTRE).norm() < SPHERE_RADIUS) ++result.inside_sphere;
    if (p.z() < 0) ++result.under_ground;
  }
  const Scalar rest = CLOTH_SIZE / (nodes - 1);
  for (int j = 0; j < nodes; ++j)
    for (int i = 0; i < nodes; ++i) {
      const int v = j * nodes + i;
      if (i + 1 < nodes) result.max_stretch = std::max(result.max_stretch, double((x[v + 1] - x[v]).norm() / rest));
      if (j + 1 < nodes) result.max_stretch = std::max(result.max_stretch, double((x[v + nodes] - x[v]).norm() / rest));
    }
  for (const Penetration& p : find_penetrations(model, x, 0, 1))
    if (p.obstacle < 0) {
      ++result.intersecting_frames;
      break;
    }
}

bool in_contact(const std::vector<Vec3>& x) {
  for (const Vec3& p : x)
    if ((p - SPHERE_CENTRE).norm() - SPHERE_RADIUS < CONTACT_DISTANCE || p.z() < CONTACT_DISTANCE) return true;
  return false;
}

// The frame times split by kind, as medians, into result.
void summarise(const std::vector<double>& falling, const std::vector<double>& contact, Result& result) {
  result.falling_frames = int(falling.size());
  result.contact_frames = int(contact.size());
  result.falling_ms = falling.empty() ? 0 : ccd::median(falling);
  result.contact_ms = contact.empty() ? 0 : ccd::median(contact);
}

// The check's model for a side: the scene's cloth without its obstacles (the Bullet side puts its own triangles in).
Model check_model(Model model) {
  model.obstacles.clear();  // the check here is cloth against cloth; vertices are counted above
  return model;
}

Result run_drape(const Case& c, const std::string& solver) {
  Result result;
  result.halvings = 0;
  const Model model = build_model(parse_scene(scene_json(c, solver), "peer.json"));
  const Model check = check_model(model);
  State state = initial_state(model);
  Integrator integrator(model);
  std::vector<double> falling, contact, falling_solve, contact_solve, frame_solve, falling_broad, frame_broad;
  for (int frame = 1; frame <= c.frames; ++frame) {
    const auto begin = std::chrono::steady_clock::now();
    frame_solve.clear();
    frame_broad.clear();
    long frame_pairs = 0;
    for (int k = 0; k < c.drape_steps; ++k) {
      const StepReport r = integrator.step(state);
      frame_solve.push_back(r.solve_ms);
      frame_broad.push_back(r.collisions.broad_ms);
      frame_pairs += r.collisions.bvh_pairs;
      result.halvings += r.step_halvings;
      if (!r.ok) {
        std::snprintf(result.failure, sizeof result.failure, "frame %d: %s", frame, r.failure.c_str());
        summarise(falling, contact, result);
        return result;
      }
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    const bool touching = in_contact(state.positions);
    (touching ? contact : falling).push_back(ms);
    std::vector<double>& kind = touching ? contact_solve : falling_solve;
    kind.insert(kind.end(), frame_solve.begin(), frame_solve.end());
    if (!touching) {
      falling_broad.insert(falling_broad.end(), frame_broad.begin(), frame_broad.end());
      result.falling_pairs += frame_pairs;
    }
    check_frame(check, state.positions, c.nodes, result);
    result.frames = frame;
  }
  summarise(falling, contact, result);
  std::vector<double> every = falling_solve;
  every.insert(every.end(), contact_solve.begin(), contact_solve.end());
  result.solve_ms_per_step = ccd::median(every);
  result.falling_solve_ms = falling_solve.empty() ? 0 : ccd::median(falling_solve);
  result.contact_solve_ms = contact_solve.empty() ? 0 : ccd::median(contact_solve);
  result.falling_broad_ms = falling_broad.empty() ? 0 : ccd::median(falling_broad);
  result.ok = true;
  return result;
}

Result run_bullet(const Case& c) {
  Result result;
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  const btVector3 gravity(0, 0, -9.81);
  world.setGravity(gravity);
  btSoftBodyWorldInfo& info = world.getWorldInfo();
  info.m_gravity = gravity;
  info.m_broadphase = &broadphase;
  info.m_dispatcher = &dispatcher;
  info.m_sparsesdf.Initialize();

  btBoxShape ground_shape(btVector3(10, 10, 0.5));
  btSphereShape sphere_shape(SPHERE_RADIUS);
  btDefaultMotionState ground_motion(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, -0.5)));
  btDefaultMotionState sphere_motion(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, 1)));
  btRigidBody ground(btRigidBody::btRigidBodyConstructionInfo(0, &ground_motion, &ground_shape));
  btRigidBody sphere(btRigidBody::btRigidBodyConstructionInfo(0, &sphere_motion, &sphere_shape));
  world.addRigidBody(&ground);
  world.addRigidBody(&sphere);

  const Scalar half = CLOTH_SIZE / 2;
  btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(info, btVector3(-half, -half, DROP_HEIGHT), btVector3(half, -half, DROP_HEIGHT),
                                                     btVector3(-half, half, DROP_HEIGHT), btVector3(half, half, DROP_HEIGHT),
                                                     c.nodes, c.nodes, 0, true);
  cloth->getCollisionShape()->setMargin(0.02);
  cloth->m_materials[0]->m_kLST = 0.4;
  btSoftBody::Material* bending = cloth->appendMaterial();
  bending->m_kLST = 0.4;
  cloth->generateBendingConstraints(2, bending);
  cloth->m_cfg.piterations = 10;
  cloth->setTotalMass(1);
  if (c.self) cloth->m_cfg.collisions |= btSoftBody::fCollision::VF_SS;
  if (c.speed > 0) cloth->setVelocity(btVector3(0, 0, -c.speed));
  world.addSoftBody(cloth);

  // The check's model with Bullet's own triangles (its patch alternates its diagonals).
  Model check = check_model(build_model(parse_scene(scene_json(c, "cholmod"), "peer.json")));
  check.triangles.clear();
  const btSoftBody::Node* first = &cloth->m_nodes[0];
  for (int f = 0; f < cloth->m_faces.size(); ++f) {
    const btSoftBody::Face& face = cloth->m_faces[f];
    check.triangles.push_back({int(face.m_n[0] - first), int(face.m_n[1] - first), int(face.m_n[2] - first)});
  }

  std::vector<Vec3> x(std::size_t(cloth->m_nodes.size()));
  std::vector<double> falling, contact;
  for (int frame = 1; frame <= c.frames; ++frame) {
    const auto begin = std::chrono::steady_clock::now();
    world.stepSimulation(FRAME_TIME, STEPS_PER_FRAME, FRAME_TIME / STEPS_PER_FRAME);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    for (int v = 0; v < cloth->m_nodes.size(); ++v) {
      const btVector3& p = cloth->m_nodes[v].m_x;
      x[std::size_t(v)] = Vec3(p.x(), p.y(), p.z());
    }
    (in_contact(x) ? contact : falling).push_back(ms);
    check_frame(check, x, c.nodes, result);
    result.frames = frame;
  }
  summarise(falling, contact, result);
  world.removeSoftBody(cloth);
  delete cloth;
  world.removeRigidBody(&sphere);
  world.removeRigidBody(&ground);
  result.ok = true;
  return result;
}

// One side in a child process; its peak memory its own.
template <class Run>
Result in_child(Run run) {
  Result r;
  const bench::ChildRun child = bench::run_in_child(
      [&] {
        Result out;
        try {
          out = run();
        } catch (const std::exception& e) {
          std::snprintf(out.failure, sizeof out.failure, "%s", e.what());
        }
        return out;
      },
      r);
  if (!child.returned) {
    r = Result{};
    std::snprintf(r.failure, sizeof r.failure, "the child process died (status %d)", child.status);
  }
  r.peak_kib = child.peak_kib;
  return r;
}

// One back-substitution of the projective solver's n x n system for the case's grid (three
// right-hand sides), prefactored: the limit a solver of that design approaches. Median, ms.
double back_substitution_ms(const Case& c) {
  const Model model = build_model(parse_scene(scene_json(c, "projective"), "peer.json"));
  const Scalar h = model.scene.timestep();
  std::vector<Eigen::Triplet<Scalar>> entries;
  for (std::size_t v = 0; v < model.masses.size(); ++v) entries.emplace_back(int(v), int(v), model.masses[v]);
  for (const Spring& s : model.springs) {
    const Scalar w = h * h * s.stiffness + h * s.damping;
    entries.emplace_back(s.i, s.i, w), entries.emplace_back(s.j, s.j, w);
    entries.emplace_back(s.i, s.j, -w), entries.emplace_back(s.j, s.i, -w);
  }
  const int n = int(model.masses.size());
  SparseMatrix A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());
  A.makeCompressed();
  CholmodFactor factor(CholmodFactor::Use::ManySolves);  // as the solver's
  if (!factor.factorise(A)) return 0;
  Eigen::Matrix<Scalar, Eigen::Dynamic, 3> B = Eigen::Matrix<Scalar, Eigen::Dynamic, 3>::Random(n, 3), X;
  std::vector<double> times;
  for (int k = 0; k < 21; ++k) {
    const auto begin = std::chrono::steady_clock::now();
    factor.solve(B, X);
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
  }
  return ccd::median(times);
}

void print_row(const std::string& side, const Result& r, const Result* bullet) {
  if (!r.ok && r.frames == 0) {
    std::printf("  %-28s failed: %s\n", side.c_str(), r.failure);
    return;
  }
  const auto cell = [](double ms) {
    char text[32];
    if (ms > 0) std::snprintf(text, sizeof text, "%.1f", ms);
    else std::snprintf(text, sizeof text, "-");
    return std::string(text);
  };
  std::printf("  %-28s %10s %10s %9.0f %8ld %8ld %8d/%-4d %8.3f %8s", side.c_str(), cell(r.falling_ms).c_str(),
              cell(r.contact_ms).c_str(), r.peak_kib / 1024.0, r.inside_sphere, r.under_ground, r.intersecting_frames,
              r.frames, r.max_stretch, r.halvings < 0 ? "-" : std::to_string(r.halvings).c_str());
  if (bullet && bullet->ok) {
    const auto ratio = [](double a, double b) {
      char text[32];
      if (a > 0 && b > 0) std::snprintf(text, sizeof text, "%.2fx", a / b);
      else std::snprintf(text, sizeof text, "-");
      return std::string(text);
    };
    std::printf("   %s / %s", ratio(r.falling_ms, bullet->falling_ms).c_str(), ratio(r.contact_ms, bullet->contact_ms).c_str());
  }
  if (!r.ok) std::printf("   stopped: %s", r.failure);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  drape::keep_freed_memory();  // as the drape program does
  CLI::App app{"Whole frames of drape beside Bullet's soft body on the same cloth-on-sphere scenes, in one run."};
  std::vector<std::string> case_names{"small", "fast", "large", "large-self"};
  std::vector<std::string> solvers{"projective", "cholmod"};
  int frames = 120, large_frames = 20;
  std::vector<int> drape_steps{STEPS_PER_FRAME, 2};
  app.add_option("--cases", case_names,
                 "small (32 x 32, gentle), fast (32 x 32 at 100 m/s), large (128 x 128), large-self (128 x 128 with "
                 "self-collision)")
      ->delimiter(',')
      ->check(CLI::IsMember({"small", "fast", "large", "large-self"}));
  app.add_option("--solvers", solvers, "drape's solvers to run (solver.type)")
      ->delimiter(',')
      ->check(CLI::IsMember({"projective", "cholmod", "cg"}));
  app.add_option("--drape-steps", drape_steps,
                 "drape's steps a frame, a row for each (Bullet always takes 8 substeps); drape may take fewer where its "
                 "results stay correct, which the checks of its row show")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option("--frames", frames, "Frames of the 32 x 32 cases")->capture_default_str()->check(CLI::Range(1, 100000));
  app.add_option("--large-frames", large_frames, "Frames of the 128 x 128 cases")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  CLI11_PARSE(app, argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // each row as it is measured, also into a file

  std::printf("peer_bench: a 2 m cloth dropped from 2.5 m onto a 0.5 m sphere 1 m above the ground; 30 frames a\n"
              "second, Bullet 8 substeps a frame, drape the steps its row says; each side in its own process, one\n"
              "thread. ms a frame: medians over the frames before any vertex is within %.0f cm of the sphere or the\n"
              "ground (falling) and after (contact).\n"
              "Checks over every frame: vertex-frames inside the sphere and under the ground, frames with cloth\n"
              "triangles meeting, the largest stretch of a grid edge; drape's halvings (a step that made energy is\n"
              "taken again in 2, 4, ... parts: log2 of the kept attempt's parts, summed; docs/solvers.md). Ratios:\n"
              "drape / Bullet.\n\n",
              CONTACT_DISTANCE * 100);
  for (const std::string& name : case_names) {
    Case c;
    c.name = name;
    if (name == "fast") c.speed = 100;
    if (name == "large" || name == "large-self") c.nodes = 128, c.frames = large_frames;
    else c.frames = frames;
    c.self = name == "large-self";
    std::printf("%s: %d x %d nodes%s%s, %d frames\n", name.c_str(), c.nodes, c.nodes, c.speed > 0 ? ", at 100 m/s" : "",
                c.self ? ", self-collision" : "", c.frames);
    std::printf("  %-28s %10s %10s %9s %8s %8s %13s %8s %8s   %s\n", "side", "falling ms", "contact ms", "peak MiB", "in ball",
                "in ground", "intersecting", "stretch", "halvings", "ratio falling / contact");
    const Result bullet = in_child([&] { return run_bullet(c); });
    print_row("Bullet 3.24 soft body", bullet, nullptr);
    for (const std::string& solver : solvers)
      for (const int steps : drape_steps) {
        c.drape_steps = steps;
        const Result r = in_child([&] { return run_drape(c, solver); });
        char side[64];
        std::snprintf(side, sizeof side, "drape %s, %d steps", solver.c_str(), steps);
        print_row(side, r, &bullet);
        if (c.self && r.ok && r.falling_frames > 0)
          // Issue 18's: the cloth falling flat gives no candidate pair and a cheap broad phase.
          std::printf("  %-28s falling frames: %ld candidate triangle pairs, broad phase %.3f ms a step (median); target: "
                      "none and under 1 ms a step: %s\n",
                      "", r.falling_pairs, r.falling_broad_ms, r.falling_pairs == 0 && r.falling_broad_ms < 1 ? "met" : "not met");
        if (solver != "projective" || !r.ok) continue;
        // In a child too: the parent must not start OpenMP or BLAS threads before it forks.
        const Result measured = in_child([&] {
          Result out;
          out.solve_ms_per_step = back_substitution_ms(c);
          out.ok = out.solve_ms_per_step > 0;
          return out;
        });
        const double limit = measured.ok ? measured.solve_ms_per_step : 0;
        const double solve_ratio = limit > 0 ? r.solve_ms_per_step / limit : 0.0;
        std::printf("  %-28s solve a step %.2f ms, one prefactored back-substitution %.3f ms: %.1fx (steps of falling "
                    "frames %.1fx, of contact frames %.1fx)\n",
                    "", r.solve_ms_per_step, limit, solve_ratio, limit > 0 ? r.falling_solve_ms / limit : 0.0,
                    limit > 0 ? r.contact_solve_ms / limit : 0.0);
        // Issue 17's targets, from this run's figures.
        const auto met = [](bool ok) { return ok ? "met" : "not met"; };
        const bool fast_enough = bullet.ok && r.falling_ms > 0 && r.contact_ms > 0 && r.falling_ms <= 0.5 * bullet.falling_ms &&
                                 r.contact_ms <= 0.5 * bullet.contact_ms;
        if (name == "small")
          std::printf("  %-28s target: at most 0.5x Bullet's ms a frame, nothing inside the sphere, no intersecting "
                      "triangles: %s\n", "", met(fast_enough && r.inside_sphere == 0 && r.intersecting_frames == 0));
        if (name == "large") {
          std::printf("  %-28s target: at most 0.5x Bullet's ms a frame: %s\n", "", met(fast_enough));
          const double contact_ratio = limit > 0 ? r.contact_solve_ms / limit : 0.0;
          std::printf("  %-28s target: the solve a step within 5x of one back-substitution: %s over every step, %s "
                      "over the contact frames' steps\n",
                      "", met(solve_ratio > 0 && solve_ratio <= 5), met(contact_ratio > 0 && contact_ratio <= 5));
        }
      }
    std::printf("\n");
  }
  return 0;
}
