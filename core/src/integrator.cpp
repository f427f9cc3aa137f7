#include "drape/core/integrator.h"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <optional>
#include <tuple>

#include "drape/ccd/distance.h"
#include "drape/core/obstacle.h"
#include "integrator_workspace.h"
#include "projective.h"

namespace drape {

State initial_state(const Model& model) {
  State s;
  s.positions = model.initial_positions;
  s.velocities = model.initial_velocities;
  return s;
}

Integrator::Integrator(const Model& model, int threads)
    : model_(model), work_(std::make_unique<Workspace>()), friction_(model.scene.friction) {
  if (CollisionPipeline::needed(model)) {
    CollisionSettings settings;
    settings.threads = threads;
    collisions_ = std::make_unique<CollisionPipeline>(model, settings);
  }
  Workspace& w = *work_;
  const int n = int(model.vertex_count());
  w.free_index.assign(n, -1);
  w.lagged.normal_force.assign(std::size_t(n), 0);
  for (int v = 0; v < n; ++v)
    if (model.pin_of_vertex[v] < 0) w.free_index[v] = w.free_count++;
  const Scalar scale = energy_scale(model);
  energy_tolerance_ = STEP_ENERGY_TOLERANCE * scale;
  energy_warning_ = model.scene.limits.energy_warn * scale;
  for (std::size_t k = 0; k < model.springs.size(); ++k)
    if (model.springs[k].limit > 0) w.limited_springs.push_back(int(k));
  if (!w.limited_springs.empty()) {  // strain limiting's inverse masses, 0 at pinned vertices
    w.inverse_mass.assign(std::size_t(n), 0);
    for (int v = 0; v < n; ++v)
      if (w.free_index[v] >= 0) w.inverse_mass[std::size_t(v)] = 1 / model.masses[std::size_t(v)];
  }
  if (model.scene.solver.kind == SolverKind::Projective) {  // a scene pays only for what it asks for
    projective_ = std::make_unique<ProjectiveSolver>(model, w.free_index, w.free_count, threads);
    return;
  }
  solver_ = make_linear_solver(model.scene.solver);
  build_pattern({});
  w.rhs.setZero(3 * w.free_count);
  w.solution.setZero(3 * w.free_count);
}

namespace {

// The scalar pattern of a matrix of blocks x blocks 3 x 3 blocks whose block column b holds the
// sorted block rows rows_of(b), written directly (three rows of each block in each of its three
// columns; a triplet list of nine entries a block took 6 % of a folding cloth's step when the
// pattern changed every step), every value zero.
template <class RowsOf>
SparseMatrix block_pattern(int blocks, RowsOf&& rows_of) {
  std::vector<SparseMatrix::StorageIndex> outer(std::size_t(3 * blocks + 1), 0), inner;
  for (int b = 0; b < blocks; ++b) {
    const std::vector<int>& rows = rows_of(b);
    for (int c = 0; c < 3; ++c) {
      for (const int a : rows)
        for (int r = 0; r < 3; ++r) inner.push_back(SparseMatrix::StorageIndex(3 * a + r));
      outer[std::size_t(3 * b + c + 1)] = SparseMatrix::StorageIndex(inner.size());
    }
  }
  SparseMatrix matrix(3 * blocks, 3 * blocks);
  matrix.resizeNonZeros(Eigen::Index(inner.size()));
  std::copy(outer.begin(), outer.end(), matrix.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), matrix.innerIndexPtr());
  std::fill(matrix.valuePtr(), matrix.valuePtr() + inner.size(), 0.0);
  return matrix;
}

}  // namespace

void Integrator::build_pattern(const std::vector<std::pair<int, int>>& extra) {
  const Model& model = model_;
  Workspace& w = *work_;
  // The blocks of each block column: the springs', hinges' and membranes' (found once), and the extra
  // pairs' both ways; then the scalar pattern (block_pattern).
  if (w.base_columns.empty()) {
    w.base_columns.resize(std::size_t(w.free_count));
    const auto join = [&](int a, int b) { w.base_columns[std::size_t(b)].push_back(a); };
    for (int a = 0; a < w.free_count; ++a) join(a, a);
    for (const Spring& s : model.springs) {
      const int a = w.free_index[s.i], b = w.free_index[s.j];
      if (a >= 0 && b >= 0) join(a, b), join(b, a);
    }
    for (const Hinge& hinge : model.hinges)
      for (std::size_t i = 0; i < 4; ++i)
        for (std::size_t j = 0; j < 4; ++j) {
          const int a = w.free_index[std::size_t(hinge.v[i])], b = w.free_index[std::size_t(hinge.v[j])];
          if (a >= 0 && b >= 0 && hinge.k[i] != 0 && hinge.k[j] != 0) join(a, b);
        }
    for (const Membrane& membrane : model.membranes)
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j) {
          const int a = w.free_index[std::size_t(membrane.v[i])], b = w.free_index[std::size_t(membrane.v[j])];
          if (a >= 0 && b >= 0) join(a, b);
        }
    for (auto& column : w.base_columns) {
      std::sort(column.begin(), column.end());
      column.erase(std::unique(column.begin(), column.end()), column.end());
    }
  }
  std::vector<std::vector<int>> added(std::size_t(w.free_count));
  for (const auto& [a, b] : extra) added[std::size_t(b)].push_back(a), added[std::size_t(a)].push_back(b);
  std::vector<int> column;
  w.matrix = block_pattern(w.free_count, [&](int b) -> const std::vector<int>& {
    const auto& base = w.base_columns[std::size_t(b)];
    auto& more = added[std::size_t(b)];
    std::sort(more.begin(), more.end());
    column.clear();
    std::set_union(base.begin(), base.end(), more.begin(), more.end(), std::back_inserter(column));  // both unique
    return column;
  });
  // The spread's base pattern (made once) and where its entries lie in this one.
  w.spread_source.clear();
  w.in_base.clear();
  if (!extra.empty()) {
    if (w.spread_matrix.nonZeros() == 0)
      w.spread_matrix = block_pattern(w.free_count, [&](int b) -> const std::vector<int>& { return w.base_columns[std::size_t(b)]; });
    // Both patterns' columns are sorted and the base's rows are a subset of this one's.
    w.spread_source.resize(std::size_t(w.spread_matrix.nonZeros()));
    w.in_base.assign(std::size_t(w.matrix.nonZeros()), 0);
    const auto* outer = w.matrix.outerIndexPtr();
    const auto* inner = w.matrix.innerIndexPtr();
    const auto* base_outer = w.spread_matrix.outerIndexPtr();
    const auto* base_inner = w.spread_matrix.innerIndexPtr();
    for (int column_index = 0; column_index < 3 * w.free_count; ++column_index) {
      auto k = outer[column_index];
      for (auto e = base_outer[column_index]; e < base_outer[column_index + 1]; ++e) {
        while (inner[k] != base_inner[e]) ++k;
        w.spread_source[std::size_t(e)] = int(k);
        w.in_base[std::size_t(k)] = 1;
      }
    }
  }
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
  w.membrane_blocks.resize(model.membranes.size());
  for (std::size_t k = 0; k < model.membranes.size(); ++k)
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t j = 0; j < 3; ++j) {
        const int a = w.free_index[std::size_t(model.membranes[k].v[i])], b = w.free_index[std::size_t(model.membranes[k].v[j])];
        w.membrane_blocks[k][i][j] = a >= 0 && b >= 0 ? w.block(a, b) : std::array<int, 3>{-1, -1, -1};
      }
  w.extra_blocks = extra;
}

int Integrator::analyses() const {
  if (projective_) return projective_->analyses();
  return solver_->analyses() + (spread_solver_ ? spread_solver_->analyses() : 0);
}
int Integrator::factorisations() const {
  if (projective_) return 0;
  return solver_->factorisations() + (spread_solver_ ? spread_solver_->factorisations() : 0);
}

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
  if (m.scene.solver.kind == SolverKind::Cholmod || (projective_ && m.scene.solver.history > 0)) find_contacts(state, pinned_dv, report);
  else w.contacts.clear();
  if (!(projective_ ? solve_projective(state, pinned_dv, report) : solve_linearised(state, pinned_dv, report)))
    return report;
  const Scalar strain_work = w.limited_springs.empty() ? 0 : limit_strain(state.positions, state.velocities, nullptr, report);
  report.external_work = source_work(pinned_dv, air_forces, state.velocities) + w.contact_work + strain_work;
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
    // The spread solves the step again for the vertices it does not hold: the limit once more,
    // on the motion and the velocities alike (all vertices: with the held ones kept, a cloth
    // thrown at fast_drop's sphere tore to 3.7 as the rest was pulled to them).
    if (!w.limited_springs.empty())
      report.external_work += limit_strain(state.positions, motion, &state.velocities, report);
    respond_holding(state, motion, report, held);
  }
  // The response acts after the limit: where it drags contact vertices on (a ball's friction),
  // their neighbours are left past the limit. The limit and the response again, while so, the
  // vertices the response moved heavier in the limit (HELD_WEIGHT).
  for (int round = 0; round < STRAIN_RESPONSE_ROUNDS && past_limit(state.positions, motion); ++round) {
    report.external_work += limit_strain(state.positions, motion, &state.velocities, report, held);
    respond_holding(state, motion, report, held);
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

namespace {

// A cloth triangle's or edge's contact with a sphere that comes between its corners: where its
// point nearest the centre lies inside it (every weight above INNER_WEIGHT, or inside an edge)
// within FACE_DEPTH_FRACTION of reach of the surface, and not every corner has its own contact
// with the sphere in about that direction (then theirs hold it, and a face's would
// over-determine the solve).
// Each edge once, each contact the nearest point's (as a mesh obstacle's vertex under a cloth
// triangle is held, CollisionPipeline::mesh_contacts).
void add_sphere_face_contacts(const Model& m, const PosedShape& shape, Scalar t, const std::vector<Vec3>& x,
                              const std::vector<int>& free_index, Scalar reach, std::vector<SolveContact>& contacts) {
  const Scalar out_to = shape.radius + FACE_DEPTH_FRACTION * reach;
  const auto touching = [&](int v, const Vec3& normal) {
    const auto [distance, radial] = shape.distance(x[std::size_t(v)]);
    return distance < reach && radial.dot(normal) > SAME_DIRECTION;
  };
  std::vector<std::array<int, 2>> edges_done;
  for (const Triangle& tri : m.triangles) {
    if (free_index[std::size_t(tri[0])] < 0 || free_index[std::size_t(tri[1])] < 0 || free_index[std::size_t(tri[2])] < 0)
      continue;
    const Vec3 &a = x[std::size_t(tri[0])], &b = x[std::size_t(tri[1])], &c = x[std::size_t(tri[2])];
    const Scalar longest = std::max((b - a).norm(), (c - a).norm());
    if ((a - shape.point).norm() - longest >= out_to) continue;  // every point of it is farther
    const auto closest = ccd::closest_point_triangle<Scalar>(shape.point, a, b, c);
    if (!(closest.distance_squared < out_to * out_to) || !(closest.distance_squared > 0)) continue;
    const std::array<Scalar, 3> w{1 - closest.weight_b - closest.weight_c, closest.weight_b, closest.weight_c};
    int inner = 0, outer = -1;
    for (int k = 0; k < 3; ++k) {
      if (w[k] > INNER_WEIGHT) ++inner;
      else outer = k;
    }
    if (inner < 2) continue;  // a corner's: the vertex contacts
    SolveContact contact;
    contact.count = 0;
    for (int k = 0; k < 3; ++k)
      if (k != outer) {
        contact.vertex[std::size_t(contact.count)] = tri[k];
        contact.weight[std::size_t(contact.count)] = w[k];
        ++contact.count;
      }
    if (contact.count == 2) {
      std::array<int, 2> edge{std::min(contact.vertex[0], contact.vertex[1]), std::max(contact.vertex[0], contact.vertex[1])};
      if (std::find(edges_done.begin(), edges_done.end(), edge) != edges_done.end()) continue;
      edges_done.push_back(edge);
      const Scalar sum = contact.weight[0] + contact.weight[1];
      contact.weight[0] /= sum, contact.weight[1] /= sum;
    }
    const Vec3 offset = closest.point - shape.point;
    contact.distance = offset.norm() - shape.radius;
    contact.normal = offset.normalized();
    bool covered = true;
    for (int i = 0; i < contact.count && covered; ++i) covered = touching(contact.vertex[std::size_t(i)], contact.normal);
    if (covered) continue;
    contact.surface_velocity = body_velocity(shape.obstacle->spec.motion, shape.point + shape.radius * contact.normal, t);
    contact.target = contact.normal.dot(contact.surface_velocity);
    // Not `analytic`: like a mesh obstacle's contact with a cloth triangle, it is a penalty of the
    // projective solver (not one of its per-vertex constraints), and the response's spread does
    // not hold it again (the response answers such faces again after the spread).
    contacts.push_back(contact);
  }
}

}  // namespace

void Integrator::find_contacts(const State& state, const std::vector<Vec3>& pinned_dv, StepReport& report) {
  const Model& m = model_;
  Workspace& w = *work_;
  const Scalar h = h_;
  w.contacts.clear();
  const Scalar thickness = m.scene.collisions.thickness;
  const Scalar reach = CONTACT_REACH * thickness;
  for (const Obstacle& obstacle : m.obstacles) {
    if (!m.scene.collisions.obstacles) break;
    if (obstacle.spec.kind == ObstacleSpec::Kind::Mesh) continue;
    const PosedShape shape = pose_shape(obstacle, state.time);
    for (std::size_t v = 0; v < state.positions.size(); ++v) {
      if (w.free_index[v] < 0) continue;
      if (!(shape.distance(state.positions[v]).first < reach)) continue;
      const SurfaceContact c = analytic_contact(shape, state.time, state.positions[v]);
      SolveContact contact;
      contact.vertex = {int(v), -1, -1, -1};
      contact.weight = {1, 0, 0, 0};
      contact.normal = c.normal;
      contact.surface_velocity = c.surface_velocity;
      contact.target = c.normal.dot(c.surface_velocity);
      contact.analytic = true;
      w.contacts.push_back(contact);
    }
    if (shape.sphere) add_sphere_face_contacts(m, shape, state.time, state.positions, w.free_index, reach, w.contacts);
  }
  if (collisions_ && m.scene.collisions.obstacles) {
    auto mesh = collisions_->mesh_contacts(state.positions, state.time, h, reach, report.collisions);
    // A cloth edge's or triangle's contact may have pinned corners (a clamp's rim over a
    // support's edge). The linearised solve holds its free ones; the pinned ones' part of the
    // relative velocity, their velocity at the step's end, is known and moves the target. (The
    // projective solver keeps them: its iterate holds the pinned vertices where they go.)
    // Left to the response, the Cusick drape's ring of free vertices next to its clamp sank
    // over the support's rim in every solve and was stopped and spread every step.
    if (!projective_) {
      for (SolveContact& c : mesh) {
        int kept = 0;
        for (int i = 0; i < c.count; ++i) {
          const int v = c.vertex[i];
          if (w.free_index[std::size_t(v)] >= 0) {
            c.vertex[kept] = v, c.weight[kept] = c.weight[i], ++kept;
          } else {
            c.target -= c.weight[i] * c.normal.dot(state.velocities[std::size_t(v)] + pinned_dv[std::size_t(v)]);
          }
        }
        for (int i = kept; i < 4; ++i) c.vertex[i] = -1, c.weight[i] = 0;
        c.count = kept;
      }
    }
    w.contacts.insert(w.contacts.end(), mesh.begin(), mesh.end());
  }
  if (projective_) return;  // its contacts are terms of its objective, not blocks of a matrix
  // The cloth's contacts with itself, held as the obstacles' are: the two sides' relative
  // velocity along the normal may not close within the step (the response's proximity impulses
  // ask the same after the solve, where stopping one side strains its springs to neighbours the
  // solve moved on). Their blocks join vertices no spring joins: the matrix's pattern gains them.
  if (collisions_ && m.scene.collisions.self && m.scene.collisions.self_in_solve) {
    const std::size_t first = w.contacts.size();
    const auto self = collisions_->self_contacts(state.positions, CONTACT_REACH, report.collisions);
    report.collisions.held_self_contacts += long(self.size());
    w.contacts.insert(w.contacts.end(), self.begin(), self.end());
    // Each pair (a < b) of free vertices the self contacts join, with repeats.
    const auto each_pair = [&](auto&& visit) {
      for (std::size_t k = first; k < w.contacts.size(); ++k)
        for (int i = 0; i < 4; ++i)
          for (int j = i + 1; j < 4; ++j) {
            const int a = w.free_index[std::size_t(w.contacts[k].vertex[i])], b = w.free_index[std::size_t(w.contacts[k].vertex[j])];
            if (a != b) visit(std::min(a, b), std::max(a, b));
          }
    };
    std::vector<std::pair<int, int>> missing;
    std::size_t needed = 0;
    each_pair([&](int a, int b) {
      ++needed;
      if (!w.find_block(a, b)) missing.emplace_back(a, b);
    });
    if (!missing.empty()) {
      // The pairs of earlier contacts stay in the pattern (a cloth at rest keeps its contacts,
      // and each new pattern is analysed again) until they outnumber the current ones.
      std::sort(missing.begin(), missing.end());
      missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
      std::vector<std::pair<int, int>> extra;
      if (w.extra_blocks.size() <= EXTRA_BLOCKS_KEPT * needed) {
        std::merge(w.extra_blocks.begin(), w.extra_blocks.end(), missing.begin(), missing.end(), std::back_inserter(extra));
      } else {  // from the current contacts alone
        each_pair([&](int a, int b) { extra.emplace_back(a, b); });
        std::sort(extra.begin(), extra.end());
      }
      extra.erase(std::unique(extra.begin(), extra.end()), extra.end());
      build_pattern(extra);
    }
  }
  // Each contact's place in the matrix: the blocks joining its vertices. An obstacle's contact
  // whose vertices the matrix does not join (no spring between them) keeps its heaviest vertex
  // alone.
  w.contact_blocks.clear();
  for (SolveContact& c : w.contacts) {
    Workspace::ContactBlocks blocks{};
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
      c.vertex = {c.vertex[heaviest], -1, -1, -1};
      c.weight = {1, 0, 0, 0};
      c.count = 1;
      blocks[0][0] = w.diagonal[w.free_index[std::size_t(c.vertex[0])]];
    }
    w.contact_blocks.push_back(blocks);
  }
}

StepReport Integrator::step(State& state) {
  const Model& m = model_;
  const Scalar h = m.scene.timestep();
  if (m.scene.solver.max_halvings == 0) {  // a scene pays only for what it asks for
    h_ = h;
    return advance(state);
  }
  const State before = state;
  const Scalar potential_before = state.positions == ended_positions_ ? ended_potential_ : potential_energy(m, state);
  const Scalar energy_before = kinetic_energy(m, state) + potential_before;
  // The friction of every attempt starts from the normal forces the step before left; the
  // kept attempt's are the next step's.
  const Workspace::Lagged lagged_before = work_->lagged;
  Workspace::Lagged kept_lagged;
  // The step's energy beyond its start and its sources' work, once taken as `parts` equal parts.
  const auto take = [&](State& s, int parts) {
    h_ = h / parts;
    work_->lagged = lagged_before;
    StepReport report = advance(s);
    for (int k = 1; k < parts && report.ok; ++k) report.add(advance(s));
    const Scalar potential = potential_energy(m, s);
    ended_positions_ = s.positions, ended_potential_ = potential;  // the kept attempt's, if it was the last
    const Scalar excess = kinetic_energy(m, s) + potential - energy_before - report.external_work;
    return std::make_pair(report, excess);
  };
  // Named variables, not a structured binding: the lambdas below capture them, which C++17
  // (and clang 14, the fuzzers' compiler) does not allow of a binding.
  StepReport report;
  Scalar excess = 0;
  std::tie(report, excess) = take(state, 1);
  Scalar stretched = limit_excess(before.positions, state.positions);
  // A step that stretches the cloth past the warning limit from below it: a spike (a moving
  // mesh corner met at speed, whose faces' contacts stop the vertices on either side while the
  // spring across the corner takes the motion: 1.51 at 6 steps a frame, 1.20 at 12). A cloth
  // already past it (a soft knit under a load) does not make its steps retaken.
  const Scalar warn = m.scene.limits.stretch_warn;
  const bool below_warning = max_stretch(m, before) <= warn;
  const auto spike_of = [&](const State& s) { return below_warning ? max_stretch(m, s) : Scalar(1); };
  Scalar spike = spike_of(state);
  kept_lagged = work_->lagged;
  const auto too_much_energy = [&](Scalar e) { return e > energy_tolerance_; };
  StepReport spent;
  int kept_parts = 1;
  // An attempt from the step's start replaces the kept one when better: with less excess energy
  // while the kept one makes energy, else (or for_limit) with its limited springs less far past
  // what their limits allow and its energy within tolerance (or, for_limit, no further past it
  // than the kept one's). The rejected attempts' work stays in the counters. Returns whether it
  // ran (a finer attempt's failure is not the step's: the coarser is kept) and whether more
  // parts may still pay.
  const auto attempt = [&](int parts, bool for_limit) {
    State again = before;
    auto [finer, finer_excess] = take(again, parts);
    if (!finer.ok) {
      spent.add(finer);
      return std::make_pair(false, false);
    }
    const Scalar finer_stretched = limit_excess(before.positions, again.positions);
    const Scalar finer_spike = spike_of(again);
    const bool energy = too_much_energy(excess) && !for_limit;
    const bool limit = stretched > STRAIN_RETAKE || for_limit;
    const bool within = finer_excess <= std::max(excess, energy_tolerance_);
    // A spike's retake must at least halve its excess over the warning (not a rounding's
    // difference: a cloth near the warning under a steady load would be retaken to the last
    // part) and must not take a limited spring back past what its limit allows.
    const bool spike_halved = finer_spike - warn <= 0.5 * (spike - warn);
    const bool better = energy  ? finer_excess < excess
                        : limit ? finer_stretched < stretched && within
                                : spike_halved && within && finer_stretched <= std::max(stretched, STRAIN_RETAKE);
    // The energy's retakes go on while its excess keeps falling by half at least, or while it
    // stays past what would make the run warn: a cloth thrown at a ball with a strain limit
    // fell only from 478 to 278 J in 2 parts (without the limit, from 286,000 J, by 5 to 12
    // times a halving), and the run stopped where 32 parts would have kept it.
    const bool converging = energy  ? finer_excess <= 0.5 * excess || std::min(excess, finer_excess) > energy_warning_
                            : limit ? true
                                    : better;
    if (better) {
      spent.add(report);
      report = finer, excess = finer_excess, stretched = finer_stretched, spike = finer_spike, state = std::move(again);
      kept_lagged = work_->lagged;
      kept_parts = parts;
    } else {
      spent.add(finer);
    }
    return std::make_pair(true, converging);
  };
  const int most_parts = 1 << m.scene.solver.max_halvings;
  // The step made energy no source put in (an impact whose response the step's size could not
  // spread: a stopped vertex strains its neighbours' springs in one step): taken again in 2,
  // 4, ... parts while that excess keeps falling by half at least (strain from one step's
  // motion falls with the step's size), the attempt with the least excess kept. The same for a
  // step that ends with a limited spring past what its limit allows (STRAIN_RETAKE: the rounds
  // of limit and response ran out) once its energy is within tolerance, then in each number of
  // parts up to the most: each part asks the rounds to undo a shorter motion.
  // And a step that spiked the stretch past the warning limit, while its parts halve the excess.
  for (int parts = 2; report.ok && (too_much_energy(excess) || stretched > STRAIN_RETAKE || spike > warn) && parts <= most_parts;
       parts *= 2) {
    const auto [ran, converging] = attempt(parts, false);
    if (!ran || !converging) break;
  }
  // The limit is the fabric's: a step still past it is one where friction holds the cloth
  // against what its limit lets it do (a curtain wrapped over a ball that goes on through it
  // must slide over the ball; at friction 0.6 one step in 160 of such a curtain still ended
  // 12.7 % past the limit in 8 parts). It is taken again without friction, whole and in parts
  // until one keeps the limit, the attempt least past it kept (with no more excess energy than
  // the kept one), and the cloth slides there for that step (docs/collisions.md).
  if (report.ok && stretched > STRAIN_RETAKE && m.scene.friction > 0) {
    friction_ = 0;
    for (int parts = 1; parts <= most_parts && stretched > STRAIN_RETAKE; parts *= 2)
      if (!attempt(parts, true).first) break;
    friction_ = m.scene.friction;
  }
  work_->lagged = std::move(kept_lagged);
  // Counted once: the halvings of the kept attempt (log2 of its parts) and the work of all.
  int halvings = 0;
  while ((1 << halvings) < kept_parts) ++halvings;
  report.solve_ms += spent.solve_ms;
  report.solver_iterations += spent.solver_iterations;
  report.collisions.add(spent.collisions);
  report.strain_limited += spent.strain_limited;
  report.strain_ms += spent.strain_ms;
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
  strain_limited += other.strain_limited;
  strain_ms += other.strain_ms;
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
    report.obstacle_contacts += keep_out_of_analytic_obstacles(m, state.positions, state.time + h, h, m.scene.collisions.thickness,
                                                               friction_, motion, &state.velocities);
  if (!collisions_) return;
  // The collision impulses are velocity changes: the state's velocities get them too.
  const std::vector<Vec3> before = motion;
  report.collisions.add(collisions_->resolve(state.positions, state.time, h, motion, friction_));
  for (std::size_t v = 0; v < motion.size(); ++v) state.velocities[v] += motion[v] - before[v];
}

void Integrator::respond_holding(State& state, std::vector<Vec3>& motion, StepReport& report, std::vector<char>& held) {
  if (work_->limited_springs.empty()) return respond(state, motion, report);
  const std::vector<Vec3> before = motion;
  respond(state, motion, report);
  const Scalar negligible = NEGLIGIBLE_MOTION * model_.scene.collisions.thickness;
  for (std::size_t v = 0; v < motion.size(); ++v)
    if (work_->free_index[v] >= 0 && h_ * (motion[v] - before[v]).norm() > negligible) held[v] = 1;
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
    e += 0.5 * spring_constant(s.stiffness, stretch, s.compression) * stretch * stretch;
  }
  for (const Hinge& hinge : model.hinges) e += 0.5 * hinge_vector(hinge, state.positions).squaredNorm();
  for (const Membrane& membrane : model.membranes) e += membrane_energy(membrane.material, corners(membrane, state.positions));
  for (std::size_t v = 0; v < state.positions.size(); ++v) e -= model.masses[v] * model.scene.gravity.dot(state.positions[v]);
  return e;
}

Scalar max_stretch(const Model& model, const State& state) {
  Scalar worst = 1;
  for (const Spring& s : model.springs)
    if (s.kind == SpringKind::Stretch)
      worst = std::max(worst, (state.positions[s.i] - state.positions[s.j]).norm() / s.rest_length);
  for (const Membrane& membrane : model.membranes)  // its edges (shared ones twice), against the rest shape's
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t a = std::size_t(membrane.v[k]), b = std::size_t(membrane.v[(k + 1) % 3]);
      worst = std::max(worst, (state.positions[a] - state.positions[b]).norm() /
                                  (model.initial_positions[a] - model.initial_positions[b]).norm());
    }
  return worst;
}

}  // namespace drape
