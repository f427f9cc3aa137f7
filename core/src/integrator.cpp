#include "drape/core/integrator.h"

#include <algorithm>
#include <chrono>
#include <optional>

#include "drape/core/obstacle.h"
#include "projective.h"

namespace drape {

State initial_state(const Model& model) {
  State s;
  s.positions = model.initial_positions;
  s.velocities = model.initial_velocities;
  return s;
}

// The system matrix over the free vertices, with the place of every 3x3 block in its
// compressed storage: a block (a, b) occupies rows 3a..3a+2 of columns 3b..3b+2, and the three
// rows of one column are contiguous, so the offset of row 3a in each column is enough.
// The penalty that holds a contact vertex to the velocity the collision response gave it while
// the response is spread through the implicit system: its diagonal block's largest entry times
// this, added to the block, so it follows its target to about 1 / RESPONSE_HOLD of its change.
constexpr Scalar RESPONSE_HOLD = 1e8;
// The linearised solve holds a cloth vertex against an obstacle (Integrator::find_contacts) when
// it starts within this many thicknesses of it: a little more than one, since the response
// leaves a resting vertex at the thickness.
constexpr Scalar CONTACT_REACH = 1.1;
// A change of the step's motion smaller than this fraction of the thickness is negligible: a
// vertex the response moved by less is not held for the re-solve, and a held contact that would
// pull its vertex by less is not released (Integrator::advance, solve_linearised).
constexpr Scalar NEGLIGIBLE_MOTION = 1e-2;
// m/s: a contact vertex slipping slower than this across its obstacle sticks (the friction in
// Integrator::solve_linearised).
constexpr Scalar FRICTION_SLIP = 1e-4;
// The projective solve keeps the cloth this many thicknesses from spheres and planes: a held
// contact yields a little (its penalty's force needs a depth), and within this margin it
// yields outside the thickness, where the response after the solve has nothing to do.
constexpr Scalar HELD_GAP = 1.05;

// A step may end with at most this fraction of the scene's energy scale (energy_scale) more
// than it started with, plus the sources' work; beyond it the step is taken again in 2, 4, ...
// parts, at most 2^solver.max_halvings. The tolerance covers what the analytic obstacles'
// projection out of the thickness adds (m g times a step's sag, far below it).
constexpr Scalar STEP_ENERGY_TOLERANCE = 1e-3;

struct Integrator::Workspace {
  std::vector<int> free_index;               // vertex -> free vertex index, or -1 if pinned
  int free_count = 0;
  SparseMatrix matrix;
  std::vector<std::array<int, 3>> diagonal;  // free vertex -> offsets of its (a, a) block
  struct SpringBlocks {
    std::array<int, 3> ij{-1, -1, -1}, ji{-1, -1, -1};
  };
  std::vector<SpringBlocks> spring_blocks;
  std::vector<std::array<std::array<std::array<int, 3>, 4>, 4>> hinge_blocks;  // [hinge][i][j]: block (v_i, v_j)
  VectorX rhs, solution;
  std::vector<Vec3> forces;
  // The projective step's start velocities and explicit forces (gravity, wind), kept for the
  // response's spread.
  std::vector<Vec3> start_velocities, explicit_forces;
  ProjectiveContacts projective_contacts;  // what the projective step holds in its solve
  // The contacts the linearised solve keeps, and the impulse (N s, along the normal) each
  // applied; zero for the ones released.
  std::vector<SolveContact> contacts;
  std::vector<std::array<std::array<std::array<int, 3>, 3>, 3>> contact_blocks;  // [contact][i][j]: block (vertex i, vertex j)
  std::vector<Scalar> contact_holds, contact_impulses;
  std::vector<Scalar> assembled;  // the matrix's values before the contacts' penalties and friction
  std::vector<Scalar> scale;  // per free vertex: its diagonal block's largest entry before penalties
  Scalar contact_work = 0;           // J: what the held contacts did at moving obstacles in the last solve
  std::vector<Scalar> normal_force;  // per vertex, N: what its contacts pushed with in the last solve

  std::array<int, 3> block(int a, int b) const {
    std::array<int, 3> offsets{};
    for (int c = 0; c < 3; ++c) {
      const int column = 3 * b + c;
      const auto* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column];
      const auto* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column + 1];
      offsets[c] = int(std::lower_bound(begin, end, 3 * a) - matrix.innerIndexPtr());
    }
    return offsets;
  }
  // The offsets of block (a, b) when the pattern holds it.
  std::optional<std::array<int, 3>> find_block(int a, int b) const {
    const int column = 3 * b;
    const auto* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column];
    const auto* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[column + 1];
    const auto* found = std::lower_bound(begin, end, 3 * a);
    if (found == end || *found != 3 * a) return std::nullopt;
    return block(a, b);
  }
  void add_block(const std::array<int, 3>& offsets, const Mat3& value) {
    Scalar* values = matrix.valuePtr();
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) values[offsets[c] + r] += value(r, c);
  }
};

Integrator::Integrator(const Model& model, int threads) : model_(model), work_(std::make_unique<Workspace>()) {
  if (CollisionPipeline::needed(model)) {
    CollisionSettings settings;
    settings.threads = threads;
    collisions_ = std::make_unique<CollisionPipeline>(model, settings);
  }
  Workspace& w = *work_;
  const int n = int(model.vertex_count());
  w.free_index.assign(n, -1);
  w.normal_force.assign(std::size_t(n), 0);
  for (int v = 0; v < n; ++v)
    if (model.pin_of_vertex[v] < 0) w.free_index[v] = w.free_count++;
  energy_tolerance_ = STEP_ENERGY_TOLERANCE * energy_scale(model);
  if (model.scene.solver.kind == SolverKind::Projective) {  // a scene pays only for what it asks for
    projective_ = std::make_unique<ProjectiveSolver>(model, w.free_index, w.free_count, threads);
    return;
  }
  solver_ = make_linear_solver(model.scene.solver);
  std::vector<Eigen::Triplet<Scalar>> pattern;
  const auto add_pattern = [&](int a, int b) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) pattern.emplace_back(3 * a + r, 3 * b + c, 0.0);
  };
  for (int a = 0; a < w.free_count; ++a) add_pattern(a, a);
  for (const Spring& s : model.springs) {
    const int a = w.free_index[s.i], b = w.free_index[s.j];
    if (a >= 0 && b >= 0) add_pattern(a, b), add_pattern(b, a);
  }
  for (const Hinge& hinge : model.hinges)
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = 0; j < 4; ++j) {
        const int a = w.free_index[std::size_t(hinge.v[i])], b = w.free_index[std::size_t(hinge.v[j])];
        if (a >= 0 && b >= 0 && hinge.k[i] != 0 && hinge.k[j] != 0) add_pattern(a, b);
      }
  w.matrix.resize(3 * w.free_count, 3 * w.free_count);
  w.matrix.setFromTriplets(pattern.begin(), pattern.end());
  w.matrix.makeCompressed();
  w.diagonal.resize(w.free_count);
  for (int a = 0; a < w.free_count; ++a) w.diagonal[a] = w.block(a, a);
  w.spring_blocks.resize(model.springs.size());
  for (std::size_t k = 0; k < model.springs.size(); ++k) {
    const int a = w.free_index[model.springs[k].i], b = w.free_index[model.springs[k].j];
    if (a >= 0 && b >= 0) w.spring_blocks[k] = {w.block(a, b), w.block(b, a)};
  }
  w.hinge_blocks.resize(model.hinges.size());
  for (auto& blocks : w.hinge_blocks)
    for (auto& row : blocks) row.fill({-1, -1, -1});  // as the springs' unassembled pairs
  for (std::size_t k = 0; k < model.hinges.size(); ++k)
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = 0; j < 4; ++j) {
        const int a = w.free_index[model.hinges[k].v[i]], b = w.free_index[model.hinges[k].v[j]];
        if (a >= 0 && b >= 0 && model.hinges[k].k[i] != 0 && model.hinges[k].k[j] != 0) w.hinge_blocks[k][i][j] = w.block(a, b);
      }
  w.rhs.setZero(3 * w.free_count);
  w.solution.setZero(3 * w.free_count);
}

int Integrator::analyses() const { return projective_ ? projective_->analyses() : solver_->analyses(); }
int Integrator::factorisations() const { return projective_ ? 0 : solver_->factorisations(); }

Scalar energy_scale(const Model& model) {
  const Box extent = initial_extent(model);
  Scalar mass = 0, kinetic = 0;
  for (std::size_t v = 0; v < model.masses.size(); ++v) {
    mass += model.masses[v];
    kinetic += 0.5 * model.masses[v] * model.initial_velocities[v].squaredNorm();
  }
  // Without gravity or motion, what a speed of 1 cm/s would give: a floor, so that a scale is
  // never zero.
  return std::max(kinetic + mass * model.scene.gravity.norm() * (extent.max - extent.min).norm(), 0.5 * mass * 1e-4);
}

Integrator::~Integrator() = default;

namespace {

// Air drag on each triangle along its normal, shared equally by its corners.
void add_wind(const Model& model, const State& state, std::vector<Vec3>& forces) {
  const WindSpec& wind = *model.scene.wind;
  for (const Triangle& t : model.triangles) {
    const Vec3 n = (state.positions[t[1]] - state.positions[t[0]]).cross(state.positions[t[2]] - state.positions[t[0]]);
    const Scalar twice_area = n.norm();
    if (!(twice_area > 0)) continue;
    const Vec3 unit = n / twice_area;
    const Vec3 relative = wind.velocity - (state.velocities[t[0]] + state.velocities[t[1]] + state.velocities[t[2]]) / 3;
    const Scalar normal_speed = relative.dot(unit);
    const Vec3 f = 0.5 * wind.density * wind.drag * (0.5 * twice_area) * std::abs(normal_speed) * normal_speed * unit;
    for (int k = 0; k < 3; ++k) forces[t[k]] += f / 3;
  }
}

// Spheres and planes: a vertex whose predicted position x0 + h u lies within the thickness of
// the surface moves (u) to land on it; its velocity (v) loses the approaching normal part and
// feels Coulomb friction relative to the surface (Bridson, Fedkiw and Anderson 2002, 7.1).
int respond_to_analytic_obstacles(const Model& model, const std::vector<Vec3>& start, Scalar t_next, Scalar h,
                                  std::vector<Vec3>& velocities, std::vector<Vec3>& motion) {
  const Scalar thickness = model.scene.collisions.thickness;
  const Scalar mu = model.scene.friction;
  int contacts = 0;
  for (const Obstacle& obstacle : model.obstacles) {
    if (obstacle.spec.kind == ObstacleSpec::Kind::Mesh) continue;  // the collision pipeline's
    const PosedShape shape = pose_shape(obstacle, t_next);
    for (std::size_t v = 0; v < start.size(); ++v) {
      if (model.pin_of_vertex[v] >= 0) continue;
      const Vec3 before = motion[v];
      const auto contact = push_out(shape, t_next, start[v], h, thickness, motion[v]);
      if (!contact) continue;
      ++contacts;
      const SurfaceContact& c = *contact;
      // Friction on the motion too, from the normal change the projection made: without it
      // the projection slides a vertex along the surface by the tangential part of its whole
      // step (a cloth landing on a sphere spread outward, its springs stretched: energy grew).
      const Scalar pushed = (motion[v] - before).dot(c.normal);
      const Vec3 slide = motion[v] - c.surface_velocity;
      const Vec3 slide_tangential = slide - slide.dot(c.normal) * c.normal;
      const Scalar slide_speed = slide_tangential.norm();
      if (slide_speed > 0 && pushed > 0) motion[v] -= slide_tangential * std::min<Scalar>(1, mu * pushed / slide_speed);
      const Vec3 relative = velocities[v] - c.surface_velocity;
      const Scalar normal_speed = relative.dot(c.normal);
      if (normal_speed >= 0) continue;  // already separating
      Vec3 tangential = relative - normal_speed * c.normal;
      const Scalar speed = tangential.norm();
      if (speed > 0) tangential *= std::max<Scalar>(0, 1 - mu * -normal_speed / speed);
      velocities[v] = c.surface_velocity + tangential;
    }
  }
  return contacts;
}

// Each vertex's contact of largest weight among contacts (-1: none), for its friction.
std::vector<int> strongest_contacts(const std::vector<SolveContact>& contacts, int n) {
  std::vector<int> strongest(std::size_t(n), -1);
  std::vector<Scalar> weight(std::size_t(n), 0);
  for (std::size_t k = 0; k < contacts.size(); ++k)
    for (int i = 0; i < contacts[k].count; ++i) {
      const std::size_t v = std::size_t(contacts[k].vertex[i]);
      if (contacts[k].weight[i] > weight[v]) weight[v] = contacts[k].weight[i], strongest[v] = int(k);
    }
  return strongest;
}

}  // namespace

StepReport Integrator::advance(State& state) {
  const Model& m = model_;
  Workspace& w = *work_;
  const Scalar h = h_;
  const Scalar t_next = state.time + h;
  const int n = int(m.vertex_count());
  StepReport report;

  // Prescribed velocities of the pinned vertices: to reach their scripted position at t + h.
  std::vector<Vec3> pinned_dv(n, Vec3::Zero());
  for (const Pin& pin : m.pins) {
    const Vec3 target = m.scene.handles[pin.handle].motion.position(m.initial_positions[pin.vertex], t_next);
    pinned_dv[pin.vertex] = (target - state.positions[pin.vertex]) / h - state.velocities[pin.vertex];
  }

  // The forces the scene applies: gravity, the air's damping, the wind.
  w.forces.assign(n, Vec3::Zero());
  const Vec3 air_velocity = m.scene.wind ? m.scene.wind->velocity : Vec3::Zero();
  for (int v = 0; v < n; ++v)
    w.forces[v] = m.masses[v] * m.scene.gravity - m.air_damping[v] * m.masses[v] * (state.velocities[v] - air_velocity);
  if (m.scene.wind) add_wind(m, state, w.forces);
  // With wind, the air's forces may put energy in: kept apart for the step's energy ledger.
  std::vector<Vec3> air_forces;
  if (m.scene.wind) {
    air_forces = w.forces;
    for (int v = 0; v < n; ++v) air_forces[v] -= m.masses[v] * m.scene.gravity;
  }
  if (m.scene.solver.kind == SolverKind::Cholmod || (projective_ && m.scene.solver.history > 0)) find_contacts(state);
  else w.contacts.clear();
  if (!(projective_ ? solve_projective(state, pinned_dv, report) : solve_linearised(state, pinned_dv, report)))
    return report;
  report.external_work = source_work(pinned_dv, air_forces, state.velocities) + w.contact_work;
  const bool obstacles_move = std::any_of(m.obstacles.begin(), m.obstacles.end(),
                                          [](const Obstacle& o) { return o.spec.motion.moves(); });
  const Scalar kinetic_before_response = obstacles_move ? kinetic_energy(m, state) : 0;
  // The response: analytic obstacles, then the collision pipeline. Each changes the motion of
  // the step (what positions advance by) and the velocities alike, but for the analytic
  // obstacles' projection out of the thickness, which is motion only.
  std::vector<Vec3> motion = state.velocities;
  const std::vector<Vec3> solved = motion;
  // The response changes only the contact vertices; their neighbours keep the velocities the
  // solve gave them for a different motion of those vertices, and against stiff springs that
  // mismatch becomes strain (on a mesh obstacle's rim, or where a cloth's flap hits a table's
  // leg, energy grew). So the change is spread through the implicit system: solved again with
  // the contact vertices held (a penalty) to their new motion and velocity, then the response
  // runs once more on the result. Motion and velocity are held apart: an analytic
  // obstacle's projection out of the thickness moves its vertex without giving it speed, and
  // spread into the neighbours' velocities it became energy (drape_sphere's landing: 4.5 J to
  // 11.7 J).
  respond(state, motion, report);
  std::vector<char> held(std::size_t(n), 0);
  bool changed = false;
  const Scalar negligible = NEGLIGIBLE_MOTION * m.scene.collisions.thickness;  // a change within the step, m
  for (int v = 0; v < n; ++v)
    if (w.free_index[v] >= 0 && h * std::max((motion[v] - solved[v]).norm(), (state.velocities[v] - solved[v]).norm()) > negligible)
      held[std::size_t(v)] = 1, changed = true;
  const int first_contacts = report.obstacle_contacts;
  if (changed) {
    if (projective_) spread_projective(state.positions, solved, motion, state.velocities, report);
    else spread_response(solved, held, motion, state.velocities, report);
    if (!report.ok) return report;
    respond(state, motion, report);
  }
  report.obstacle_contacts = first_contacts;
  if (obstacles_move) report.external_work += std::max<Scalar>(0, kinetic_energy(m, state) - kinetic_before_response);
  for (int v = 0; v < n; ++v) state.positions[v] += h * motion[v];
  state.time = t_next;
  ++state.steps;

  // Checks: numbers and bounds.
  for (int v = 0; v < n; ++v) {
    if (!state.positions[v].allFinite() || !state.velocities[v].allFinite()) {
      report.ok = false;
      report.failure = "vertex " + std::to_string(v) + " has a NaN or infinite position or velocity";
      return report;
    }
    if (!m.bounds.contains(state.positions[v])) {
      report.ok = false;
      report.failure = "the cloth exploded: vertex " + std::to_string(v) + " left the scene bounds";
      return report;
    }
  }
  return report;
}

void Integrator::assemble(const std::vector<Vec3>& x, const std::vector<Vec3>& v, std::vector<Vec3>& forces,
                          std::vector<Vec3>* stiffness_times_v, const std::vector<Vec3>* pinned_dv,
                          std::vector<Vec3>* coupling) {
  const Model& m = model_;
  Workspace& w = *work_;
  const Scalar h = h_;
  const int n = int(m.vertex_count());
  std::fill(w.matrix.valuePtr(), w.matrix.valuePtr() + w.matrix.nonZeros(), 0.0);
  for (int k = 0; k < n; ++k)
    if (w.free_index[k] >= 0)  // M - h d(air drag)/dv
      w.add_block(w.diagonal[w.free_index[k]], m.masses[k] * (1 + h * m.air_damping[k]) * Mat3::Identity());
  for (std::size_t k = 0; k < m.springs.size(); ++k) {
    const Spring& s = m.springs[k];
    const SpringEvaluation e = evaluate_spring(x[s.i], x[s.j], v[s.i], v[s.j], s.rest_length, s.stiffness, s.damping);
    forces[s.i] += e.force;
    forces[s.j] -= e.force;
    if (stiffness_times_v) {
      const Vec3 kv = e.d_force_d_x * (v[s.i] - v[s.j]);
      (*stiffness_times_v)[s.i] += kv;
      (*stiffness_times_v)[s.j] -= kv;
    }
    const Mat3 diagonal_block = -h * e.d_force_d_v - h * h * e.d_force_d_x;  // A's (i,i) and (j,j)
    const int a = w.free_index[s.i], b = w.free_index[s.j];
    if (a >= 0) w.add_block(w.diagonal[a], diagonal_block);
    if (b >= 0) w.add_block(w.diagonal[b], diagonal_block);
    if (a >= 0 && b >= 0) {
      w.add_block(w.spring_blocks[k].ij, -diagonal_block);
      w.add_block(w.spring_blocks[k].ji, -diagonal_block);
    } else if (coupling && a >= 0) {  // j prescribed: A's (i,j) block times its dv moves to the right-hand side
      (*coupling)[s.i] -= diagonal_block * (*pinned_dv)[s.j];
    } else if (coupling && b >= 0) {
      (*coupling)[s.j] -= diagonal_block * (*pinned_dv)[s.i];
    }
  }
  // The bending hinges: F_i = -k_i (u + c du/dt) with u = sum k_j x_j, so -dF_i/dx_j = k_i k_j I
  // and -dF_i/dv_j = c k_i k_j I, constant (Hinge).
  for (std::size_t k = 0; k < m.hinges.size(); ++k) {
    const Hinge& hinge = m.hinges[k];
    const Vec3 du = hinge_vector(hinge, v), pull = hinge_pull(hinge, x, v);
    const Scalar weight = h * hinge.damping + h * h;  // A's (i, j) block over k_i k_j
    for (int i = 0; i < 4; ++i) {
      const int vi = hinge.v[std::size_t(i)];
      const Scalar ki = hinge.k[std::size_t(i)];
      if (ki == 0) continue;
      forces[std::size_t(vi)] -= ki * pull;
      if (stiffness_times_v) (*stiffness_times_v)[std::size_t(vi)] -= ki * du;
      const int a = w.free_index[std::size_t(vi)];
      if (a < 0) continue;
      for (int j = 0; j < 4; ++j) {
        const int vj = hinge.v[std::size_t(j)];
        const Scalar block = weight * ki * hinge.k[std::size_t(j)];
        if (block == 0) continue;
        if (w.free_index[std::size_t(vj)] >= 0) w.add_block(w.hinge_blocks[k][std::size_t(i)][std::size_t(j)], block * Mat3::Identity());
        else if (coupling) (*coupling)[std::size_t(vi)] += block * (*pinned_dv)[std::size_t(vj)];
      }
    }
  }
}

void Integrator::find_contacts(const State& state) {
  const Model& m = model_;
  Workspace& w = *work_;
  const Scalar h = h_;
  w.contacts.clear();
  if (!m.scene.collisions.obstacles) return;
  const Scalar thickness = m.scene.collisions.thickness;
  const Scalar reach = CONTACT_REACH * thickness;
  for (const Obstacle& obstacle : m.obstacles) {
    if (obstacle.spec.kind == ObstacleSpec::Kind::Mesh) continue;
    const PosedShape shape = pose_shape(obstacle, state.time);
    for (std::size_t v = 0; v < state.positions.size(); ++v) {
      if (w.free_index[v] < 0) continue;
      if (!(shape.distance(state.positions[v]).first < reach)) continue;
      const SurfaceContact c = analytic_contact(shape, state.time, state.positions[v]);
      SolveContact contact;
      contact.vertex = {int(v), -1, -1};
      contact.weight = {1, 0, 0};
      contact.normal = c.normal;
      contact.surface_velocity = c.surface_velocity;
      contact.target = c.normal.dot(c.surface_velocity);
      contact.analytic = true;
      w.contacts.push_back(contact);
    }
  }
  if (collisions_) {
    const auto mesh = collisions_->mesh_contacts(state.positions, state.time, h, reach);
    w.contacts.insert(w.contacts.end(), mesh.begin(), mesh.end());
  }
  if (projective_) return;  // its contacts are terms of its objective, not blocks of a matrix
  // Each contact's place in the matrix: the blocks joining its vertices. A contact whose
  // vertices the matrix does not join (no spring between them) keeps its heaviest vertex alone.
  w.contact_blocks.clear();
  for (SolveContact& c : w.contacts) {
    std::array<std::array<std::array<int, 3>, 3>, 3> blocks{};
    bool joined = true;
    for (int i = 0; i < c.count && joined; ++i)
      for (int j = 0; j < c.count && joined; ++j) {
        const int a = w.free_index[std::size_t(c.vertex[i])], b = w.free_index[std::size_t(c.vertex[j])];
        if (a == b) blocks[i][j] = w.diagonal[a];
        else if (const auto offsets = w.find_block(a, b)) blocks[i][j] = *offsets;
        else joined = false;
      }
    if (!joined) {
      const int heaviest = int(std::max_element(c.weight.begin(), c.weight.begin() + c.count) - c.weight.begin());
      c.vertex = {c.vertex[heaviest], -1, -1};
      c.weight = {1, 0, 0};
      c.count = 1;
      blocks[0][0] = w.diagonal[w.free_index[std::size_t(c.vertex[0])]];
    }
    w.contact_blocks.push_back(blocks);
  }
}

bool Integrator::solve_linearised(State& state, const std::vector<Vec3>& pinned_dv, StepReport& report) {
  const Model& m = model_;
  Workspace& w = *work_;
  const Scalar h = h_;
  const int n = int(m.vertex_count());
  // The system matrix A = M - h dF/dv - h^2 dF/dx over the free vertices, and the right-hand
  // side h (F + h dF/dx v) less A's coupling to the prescribed dv; spring forces join the
  // workspace's.
  std::vector<Vec3> stiffness_times_v(n, Vec3::Zero());  // dF/dx v
  std::vector<Vec3> coupling(n, Vec3::Zero());           // A_(free, pinned) dv_pinned
  assemble(state.positions, state.velocities, w.forces, &stiffness_times_v, &pinned_dv, &coupling);
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    if (a >= 0) w.rhs.segment<3>(3 * a) = h * (w.forces[v] + h * stiffness_times_v[v]) - coupling[v];
  }
  // The matrix as assembled, kept for the response's re-solve (spread_response) when the
  // contacts' penalties and friction are about to change it.
  if (!w.contacts.empty()) w.assembled.assign(w.matrix.valuePtr(), w.matrix.valuePtr() + w.matrix.nonZeros());
  // Each free vertex's own scale in the system, for the penalties that hold it: its diagonal
  // block's largest entry (the mass, or h^2 k where springs are stiffer), before any penalty.
  w.scale.resize(std::size_t(w.free_count));
  for (int a = 0; a < w.free_count; ++a) {
    w.scale[std::size_t(a)] = 0;
    for (int c = 0; c < 3; ++c) w.scale[std::size_t(a)] = std::max(w.scale[std::size_t(a)], w.matrix.valuePtr()[w.diagonal[a][c] + c]);
  }

  // The contacts known at the step's start, held along their normals by a penalty: a contact's
  // cloth points may not approach the obstacle faster than its target. A contact that pulls
  // them towards the obstacle (its impulse negative) is released and the step solved again,
  // once: one that pulls after that stays held for this step (counted as no force).
  const auto normal_velocity = [&](const SolveContact& c, const VectorX* dv) {
    Scalar speed = 0;
    for (int i = 0; i < c.count; ++i) {
      Vec3 v = state.velocities[c.vertex[i]];
      if (dv) v += dv->segment<3>(3 * w.free_index[std::size_t(c.vertex[i])]);
      speed += c.weight[i] * c.normal.dot(v);
    }
    return speed;
  };
  const auto hold_contacts = [&](Scalar sign, const std::vector<char>& which) {
    for (std::size_t k = 0; k < w.contacts.size(); ++k) {
      if (!which[k]) continue;
      const SolveContact& c = w.contacts[k];
      const Scalar hold = sign * w.contact_holds[k];
      const Mat3 nn = c.normal * c.normal.transpose();
      const Scalar missing = c.target - normal_velocity(c, nullptr);
      for (int i = 0; i < c.count; ++i) {
        for (int j = 0; j < c.count; ++j) w.add_block(w.contact_blocks[k][i][j], hold * c.weight[i] * c.weight[j] * nn);
        w.rhs.segment<3>(3 * w.free_index[std::size_t(c.vertex[i])]) += hold * c.weight[i] * missing * c.normal;
      }
    }
  };
  // Coulomb friction of the contacts, in the solve, from the normal force each vertex's
  // contacts made the step before (lagged, as in Baraff and Witkin 1998, section 5.3): a vertex
  // slipping across its contact's normal at the step's start feels friction times that force
  // against its slip. Where that could stop the slip within the step, as an implicit drag that
  // reaches the force at the slip speed (or at FRICTION_SLIP, for a vertex slower than that),
  // so it never reverses the slip and holds what sticks; otherwise as the force itself,
  // linearised at the slip (constant along it, turning it across). In the solve, the neighbours of
  // a vertex it holds are held with it (applied after the solve, it stopped a tablecloth's rim
  // vertices while the springs to the hanging side had been solved for them sliding: the
  // springs stretched).
  const Scalar mu = m.scene.friction;
  struct Friction {
    int vertex;
    Mat3 block;    // its term of the matrix
    Vec3 pushed;   // and of the right-hand side: its impulse is pushed - block dv
    Vec3 surface;  // the obstacle's velocity
  };
  std::vector<Friction> frictions;  // on moving obstacles, for the work they do
  if (mu > 0 && !w.contacts.empty()) {
    const std::vector<int> strongest = strongest_contacts(w.contacts, n);
    for (int v = 0; v < n; ++v) {
      const int k = strongest[std::size_t(v)];
      if (k < 0 || !(w.normal_force[std::size_t(v)] > 0)) continue;
      const SolveContact& c = w.contacts[std::size_t(k)];
      const Mat3 across = Mat3::Identity() - c.normal * c.normal.transpose();
      const Vec3 slip = across * (state.velocities[v] - c.surface_velocity);
      const Scalar force = mu * w.normal_force[std::size_t(v)], speed = slip.norm();
      const int a = w.free_index[v];
      Mat3 block;
      Vec3 pushed;
      if (h * force >= m.masses[v] * speed) {  // it can stop the slip within the step: a drag
        const Scalar drag = force / std::max(speed, FRICTION_SLIP);
        block = h * drag * across;
        pushed = -h * drag * slip;
      } else {
        const Vec3 direction = slip / speed;
        block = h * force / speed * (across - direction * direction.transpose());
        pushed = -h * force * direction;
      }
      w.add_block(w.diagonal[a], block);
      w.rhs.segment<3>(3 * a) += pushed;
      if (c.surface_velocity != Vec3::Zero()) frictions.push_back({v, block, pushed, c.surface_velocity});
    }
  }

  w.contact_holds.assign(w.contacts.size(), 0);
  for (std::size_t k = 0; k < w.contacts.size(); ++k) {
    Scalar scale = 0;
    for (int i = 0; i < w.contacts[k].count; ++i)
      scale = std::max(scale, w.scale[std::size_t(w.free_index[std::size_t(w.contacts[k].vertex[i])])]);
    w.contact_holds[k] = RESPONSE_HOLD * scale;
  }
  std::vector<char> held(w.contacts.size(), 1);
  hold_contacts(1, held);
  w.contact_impulses.assign(w.contacts.size(), 0);
  for (int attempt = 0;; ++attempt) {
    if (!solve(report, "the linear solver failed: ")) return false;
    std::vector<char> pulling(w.contacts.size(), 0);
    bool any = false;
    for (std::size_t k = 0; k < w.contacts.size(); ++k) {
      if (!held[k]) continue;
      w.contact_impulses[k] = w.contact_holds[k] * (w.contacts[k].target - normal_velocity(w.contacts[k], &w.solution));
      if (!(w.contact_impulses[k] < 0)) continue;
      // A pull too weak to move its vertices by a negligible distance within the step stays
      // held (not worth solving again); a stronger one is released.
      const SolveContact& c = w.contacts[k];
      Scalar mass = 0;
      for (int i = 0; i < c.count; ++i) mass = std::max(mass, m.masses[std::size_t(c.vertex[i])]);
      if (-w.contact_impulses[k] * h > mass * NEGLIGIBLE_MOTION * m.scene.collisions.thickness)
        pulling[k] = 1, held[k] = 0, any = true;
      w.contact_impulses[k] = 0;
    }
    if (!any || attempt == 1) break;
    hold_contacts(-1, pulling);
  }
  // The work the held contacts did on the cloth at moving obstacles' velocities (their normal
  // impulses and their friction), for the step's energy ledger: zero on still obstacles.
  w.contact_work = 0;
  for (std::size_t k = 0; k < w.contacts.size(); ++k)
    w.contact_work += w.contact_impulses[k] * w.contacts[k].normal.dot(w.contacts[k].surface_velocity);
  for (const Friction& f : frictions)
    w.contact_work += (f.pushed - f.block * w.solution.segment<3>(3 * w.free_index[std::size_t(f.vertex)])).dot(f.surface);
  w.contact_work = std::max<Scalar>(0, w.contact_work);
  // The normal forces, for the next step's friction.
  w.normal_force.assign(std::size_t(n), 0);
  for (std::size_t k = 0; k < w.contacts.size(); ++k)
    for (int i = 0; i < w.contacts[k].count; ++i)
      w.normal_force[std::size_t(w.contacts[k].vertex[i])] += w.contacts[k].weight[i] * w.contact_impulses[k] / h;

  // Velocities; the motion of the step starts as the same velocities.
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    state.velocities[v] += a >= 0 ? Vec3(w.solution.segment<3>(3 * a)) : pinned_dv[v];
  }
  return true;
}

bool Integrator::solve_projective(State& state, const std::vector<Vec3>& pinned_dv, StepReport& report) {
  const Model& m = model_;
  Workspace& w = *work_;
  const Scalar h = h_;
  const std::size_t n = m.vertex_count();
  // The explicit forces: gravity and the wind's drag; the air's damping is in the system.
  const Vec3 air_velocity = m.scene.wind ? m.scene.wind->velocity : Vec3::Zero();
  w.explicit_forces = w.forces;
  for (std::size_t v = 0; v < n; ++v)
    w.explicit_forces[v] += m.air_damping[v] * m.masses[v] * (state.velocities[v] - air_velocity);
  w.start_velocities = state.velocities;
  // The springs' forces at the step's start on the pinned vertices, for the ledger (source_work).
  if (!m.pins.empty())
    for (const Spring& s : m.springs) {
      if (m.pin_of_vertex[std::size_t(s.i)] < 0 && m.pin_of_vertex[std::size_t(s.j)] < 0) continue;
      const SpringEvaluation e = evaluate_spring(state.positions[s.i], state.positions[s.j], state.velocities[s.i],
                                                 state.velocities[s.j], s.rest_length, s.stiffness, s.damping);
      w.forces[s.i] += e.force;
      w.forces[s.j] -= e.force;
    }
  if (!m.pins.empty())
    for (const Hinge& hinge : m.hinges) {
      for (std::size_t i = 0; i < 4; ++i)
        if (m.pin_of_vertex[std::size_t(hinge.v[i])] >= 0)
          w.forces[std::size_t(hinge.v[i])] += hinge_force(hinge, i, state.positions, state.velocities);
    }
  // First guess: the inertial prediction y (the free vertices), the prescribed end (the pinned
  // ones); in free fall it is the answer, which the acceleration then keeps.
  std::vector<Vec3> positions(n);
  for (std::size_t v = 0; v < n; ++v)
    positions[v] = state.positions[v] + h * (state.velocities[v] + pinned_dv[v]) +
                   (w.free_index[v] >= 0 ? Vec3(h * h / m.masses[v] * w.explicit_forces[v]) : Vec3::Zero());
  // The contacts held in the solve (L-BFGS only): the analytic obstacles at the step's end,
  // the mesh contacts of its start, and friction from the normal forces of the step before.
  ProjectiveContacts& contacts = w.projective_contacts;
  contacts = {};
  contacts.slip = FRICTION_SLIP;
  if (m.scene.solver.history > 0 && m.scene.collisions.obstacles) {
    contacts.analytic = std::any_of(m.obstacles.begin(), m.obstacles.end(),
                                    [](const Obstacle& o) { return o.spec.kind != ObstacleSpec::Kind::Mesh; });
    contacts.t_end = state.time + h;
    contacts.margin = HELD_GAP * m.scene.collisions.thickness;
    for (const SolveContact& c : w.contacts)
      if (!c.analytic) contacts.mesh.push_back(c);
    if (m.scene.friction > 0) {
      const std::vector<int> strongest = strongest_contacts(w.contacts, int(n));
      for (std::size_t v = 0; v < n; ++v)
        if (strongest[v] >= 0 && w.normal_force[v] > 0) {
          const SolveContact& c = w.contacts[std::size_t(strongest[v])];
          contacts.friction.push_back({int(v), c.normal, c.surface_velocity, m.scene.friction * w.normal_force[v]});
        }
    }
  }
  if (!iterate_projective(state.positions, positions, report, "the projective solver failed: ", nullptr, &contacts))
    return false;
  // The normal forces, for the next step's friction; the contacts' work, for the ledger.
  w.normal_force.resize(n);
  for (std::size_t v = 0; v < n; ++v) w.normal_force[v] = projective_->contact_impulses()[v] / h;
  w.contact_work = projective_->contact_work();
  for (std::size_t v = 0; v < n; ++v)
    state.velocities[v] = w.free_index[v] >= 0 ? Vec3((positions[v] - state.positions[v]) / h)
                                               : Vec3(state.velocities[v] + pinned_dv[v]);
  return true;
}

StepReport Integrator::step(State& state) {
  const Model& m = model_;
  const Scalar h = m.scene.timestep();
  if (m.scene.solver.max_halvings == 0) {  // a scene pays only for what it asks for
    h_ = h;
    return advance(state);
  }
  const State before = state;
  const Scalar energy_before = kinetic_energy(m, state) + potential_energy(m, state);
  // The friction of every attempt starts from the normal forces the step before left; the
  // kept attempt's are the next step's.
  const std::vector<Scalar> normal_force_before = work_->normal_force;
  std::vector<Scalar> kept_normal_force;
  // The step's energy beyond its start and its sources' work, once taken as `parts` equal parts.
  const auto take = [&](State& s, int parts) {
    h_ = h / parts;
    work_->normal_force = normal_force_before;
    StepReport report = advance(s);
    for (int k = 1; k < parts && report.ok; ++k) report.add(advance(s));
    const Scalar excess = kinetic_energy(m, s) + potential_energy(m, s) - energy_before - report.external_work;
    return std::make_pair(report, excess);
  };
  auto [report, excess] = take(state, 1);
  kept_normal_force = work_->normal_force;
  // The step made energy no source put in (an impact whose response the step's size could not
  // spread: a stopped vertex strains its neighbours' springs in one step): taken again in 2,
  // 4, ... parts while that excess keeps falling by half at least (strain from one step's
  // motion falls with the step's size); the attempt with the least excess is kept, and the
  // rejected attempts' work stays in the counters.
  StepReport spent;
  for (int parts = 2; report.ok && excess > energy_tolerance_ && parts <= (1 << m.scene.solver.max_halvings); parts *= 2) {
    State again = before;
    auto [finer, finer_excess] = take(again, parts);
    if (!finer.ok) {  // keep the coarser result; the finer one's failure is not the step's
      spent.add(finer);
      break;
    }
    const bool converging = finer_excess <= 0.5 * excess;
    if (finer_excess < excess) {
      spent.add(report);
      report = finer, excess = finer_excess, state = std::move(again);
      kept_normal_force = work_->normal_force;
      report.step_halvings = 0;
      ++spent.step_halvings;
    } else {
      spent.add(finer);
    }
    if (!converging) break;
  }
  work_->normal_force = std::move(kept_normal_force);
  // Counted once: the halvings of the kept attempt (log2 of its parts) and the work of all.
  const int halvings = spent.step_halvings;
  report.solve_ms += spent.solve_ms;
  report.solver_iterations += spent.solver_iterations;
  report.collisions.add(spent.collisions);
  report.step_halvings = halvings;
  return report;
}

void StepReport::add(const StepReport& other) {
  if (ok && !other.ok) ok = false, failure = other.failure;
  solver_iterations += other.solver_iterations;
  solver_converged = solver_converged && other.solver_converged;
  solve_ms += other.solve_ms;
  obstacle_contacts += other.obstacle_contacts;
  collisions.add(other.collisions);
  external_work += other.external_work;
  step_halvings += other.step_halvings;
}

Scalar Integrator::source_work(const std::vector<Vec3>& pinned_dv, const std::vector<Vec3>& air_forces,
                               const std::vector<Vec3>& velocities) const {
  const Model& m = model_;
  const Workspace& w = *work_;
  const Scalar h = h_;
  // A handle's force on its vertex: what moves the vertex's mass as scripted less what the
  // other forces (springs, gravity, air) already do, at the step's start; times the step's
  // displacement h v.
  Scalar handles = 0;
  for (const Pin& pin : m.pins) {
    const int v = pin.vertex;
    const Vec3 force = m.masses[std::size_t(v)] * pinned_dv[std::size_t(v)] / h - w.forces[std::size_t(v)];
    handles += force.dot(h * velocities[std::size_t(v)]);
  }
  Scalar air = 0;
  for (std::size_t v = 0; v < air_forces.size(); ++v)
    if (w.free_index[v] >= 0) air += air_forces[v].dot(h * velocities[v]);
  return std::max<Scalar>(0, handles) + std::max<Scalar>(0, air);
}

void Integrator::respond(State& state, std::vector<Vec3>& motion, StepReport& report) {
  const Model& m = model_;
  const Scalar h = h_;
  if (m.scene.collisions.obstacles)
    report.obstacle_contacts += respond_to_analytic_obstacles(m, state.positions, state.time + h, h, state.velocities, motion);
  if (!collisions_) return;
  // The collision impulses are velocity changes: the state's velocities get them too.
  const std::vector<Vec3> before = motion;
  report.collisions.add(collisions_->resolve(state.positions, state.time, h, motion));
  for (std::size_t v = 0; v < motion.size(); ++v) state.velocities[v] += motion[v] - before[v];
}

bool Integrator::solve(StepReport& report, const std::string& failure, const VectorX* again) {
  Workspace& w = *work_;
  const auto begin = std::chrono::steady_clock::now();
  const SolveReport solved = again ? solver_->solve_again(*again, w.solution) : solver_->solve(w.matrix, w.rhs, w.solution);
  report.solve_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  report.solver_iterations += solved.iterations;
  report.solver_converged = report.solver_converged && solved.converged;
  if (!solved.ok) {
    report.ok = false;
    report.failure = failure + solved.error;
  }
  return solved.ok;
}

void Integrator::spread_response(const std::vector<Vec3>& solved, const std::vector<char>& held, std::vector<Vec3>& motion, std::vector<Vec3>& velocities,
                                 StepReport& report) {
  const Model& m = model_;
  Workspace& w = *work_;
  const int n = int(m.vertex_count());
  // The step's system as the solve assembled it, without its contacts and friction (the held
  // vertices are what the response made of them), and the held vertices' changes as penalties:
  // linear in those changes, motion and velocities apart.
  if (!w.contacts.empty()) std::copy(w.assembled.begin(), w.assembled.end(), w.matrix.valuePtr());
  VectorX velocity_rhs = VectorX::Zero(w.rhs.size());
  w.rhs.setZero();
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    if (a < 0 || !held[std::size_t(v)]) continue;
    const Scalar hold = RESPONSE_HOLD * w.scale[std::size_t(a)];
    w.add_block(w.diagonal[a], hold * Mat3::Identity());
    w.rhs.segment<3>(3 * a) = hold * (motion[v] - solved[v]);
    velocity_rhs.segment<3>(3 * a) = hold * (velocities[v] - solved[v]);
  }
  if (!solve(report, "the linear solver failed spreading the collision response: ")) return;
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    if (a >= 0 && !held[std::size_t(v)]) motion[v] = solved[v] + Vec3(w.solution.segment<3>(3 * a));
  }
  if (!solve(report, "the linear solver failed spreading the collision response: ", &velocity_rhs)) return;
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    if (a >= 0 && !held[std::size_t(v)]) velocities[v] = solved[v] + Vec3(w.solution.segment<3>(3 * a));
  }
}

bool Integrator::iterate_projective(const std::vector<Vec3>& start, std::vector<Vec3>& positions, StepReport& report,
                                    const std::string& failure, const HeldVertices* held,
                                    const ProjectiveContacts* contacts) {
  const Workspace& w = *work_;
  const auto begin = std::chrono::steady_clock::now();
  std::string error;
  const bool ok = projective_->solve({h_, &start, &w.start_velocities, &w.explicit_forces, contacts}, positions, error,
                                     held, RESPONSE_HOLD);
  report.solve_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  report.solver_iterations += projective_->iterations_done();
  if (!ok) {
    report.ok = false;
    report.failure = failure + error;
  }
  return ok;
}

void Integrator::spread_projective(const std::vector<Vec3>& start, const std::vector<Vec3>& solved,
                                   std::vector<Vec3>& motion, std::vector<Vec3>& velocities, StepReport& report) {
  const Model& m = model_;
  const Workspace& w = *work_;
  const Scalar h = h_;
  const std::size_t n = m.vertex_count();
  HeldVertices held;
  for (std::size_t v = 0; v < n; ++v)
    if (w.free_index[v] >= 0 && (motion[v] != solved[v] || velocities[v] != solved[v])) held.vertices.push_back(int(v));
  // The same step (its start, velocities and forces as the first solve had them), from the
  // responded positions, with the contact vertices held; once for each of motion and velocity.
  const auto spread = [&](std::vector<Vec3>& result) {
    std::vector<Vec3> positions(n);
    for (std::size_t v = 0; v < n; ++v) positions[v] = start[v] + h * result[v];
    held.targets.clear();
    for (int v : held.vertices) held.targets.push_back(positions[std::size_t(v)]);
    if (!iterate_projective(start, positions, report, "the projective solver failed spreading the collision response: ",
                            &held, model_.scene.solver.history > 0 ? &w.projective_contacts : nullptr))
      return false;
    for (std::size_t v = 0; v < n; ++v)
      if (w.free_index[v] >= 0) result[v] = (positions[v] - start[v]) / h;
    return true;
  };
  if (spread(motion)) spread(velocities);
}

Scalar kinetic_energy(const Model& model, const State& state) {
  Scalar e = 0;
  for (std::size_t v = 0; v < state.velocities.size(); ++v) e += 0.5 * model.masses[v] * state.velocities[v].squaredNorm();
  return e;
}

Scalar potential_energy(const Model& model, const State& state) {
  Scalar e = 0;
  for (const Spring& s : model.springs) {
    const Scalar stretch = (state.positions[s.i] - state.positions[s.j]).norm() - s.rest_length;
    e += 0.5 * s.stiffness * stretch * stretch;
  }
  for (const Hinge& hinge : model.hinges) e += 0.5 * hinge_vector(hinge, state.positions).squaredNorm();
  for (std::size_t v = 0; v < state.positions.size(); ++v) e -= model.masses[v] * model.scene.gravity.dot(state.positions[v]);
  return e;
}

Scalar max_stretch(const Model& model, const State& state) {
  Scalar worst = 1;
  for (const Spring& s : model.springs)
    if (s.kind == SpringKind::Stretch)
      worst = std::max(worst, (state.positions[s.i] - state.positions[s.j]).norm() / s.rest_length);
  return worst;
}

}  // namespace drape
