#include <algorithm>
#include <chrono>
#include <cmath>

#include "drape/core/integrator.h"
#include "drape/core/obstacle.h"
#include "integrator_workspace.h"

namespace drape {

namespace {

// A contact's weights summing to within this of 1 are a whole contact's (edge and triangle
// weights are 1 - s + s and 1 - b - c + b + c, rounded).
constexpr Scalar WHOLE_SHARE = 1e-12;

// Lagged Coulomb friction's terms in the solve, for a slip (speed its length) across a contact
// (across: the projection off its normal) under a normal force: where it could stop the slip
// within the step (stops), an implicit drag reaching the force at the slip speed (or at
// FRICTION_SLIP, for a slower slip), so it never reverses the slip and holds what sticks;
// otherwise the force itself, linearised at the slip (constant along it, turning it across).
// The matrix's block and the right-hand side's part: the impulse is pushed - block dv.
std::pair<Mat3, Vec3> friction_terms(Scalar h, Scalar force, const Mat3& across, const Vec3& slip, Scalar speed, bool stops) {
  if (stops) {
    const Scalar drag = force / std::max(speed, FRICTION_SLIP);
    return {h * drag * across, -h * drag * slip};
  }
  const Vec3 direction = slip / speed;
  return {h * force / speed * (across - direction * direction.transpose()), -h * force * direction};
}

}  // namespace

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
    const SpringEvaluation e = evaluate_spring(x[s.i], x[s.j], v[s.i], v[s.j], s.rest_length, s.stiffness, s.damping, s.compression);
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
  // The membrane's triangles (evaluate_membrane): A's (i, j) block -h dF_i/dv_j - h^2 dF_i/dx_j.
  for (std::size_t k = 0; k < m.membranes.size(); ++k) {
    const Membrane& membrane = m.membranes[k];
    const std::array<Vec3, 3> xs = corners(membrane, x), vs = corners(membrane, v);
    const MembraneEvaluation e = evaluate_membrane(membrane.material, xs, vs);
    for (std::size_t i = 0; i < 3; ++i) {
      const std::size_t vi = std::size_t(membrane.v[i]);
      forces[vi] += e.force[i];
      if (stiffness_times_v)
        for (std::size_t j = 0; j < 3; ++j) (*stiffness_times_v)[vi] += e.d_force_d_x[i][j] * vs[j];
      if (w.free_index[vi] < 0) continue;
      for (std::size_t j = 0; j < 3; ++j) {
        const Mat3 block = -h * e.d_force_d_v[i][j] - h * h * e.d_force_d_x[i][j];
        if (w.free_index[std::size_t(membrane.v[j])] >= 0) w.add_block(w.membrane_blocks[k][i][j], block);
        else if (coupling) (*coupling)[vi] += block * (*pinned_dv)[std::size_t(membrane.v[j])];
      }
    }
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
  // them towards the obstacle (its impulse negative) is released (below, "A contact whose force
  // pulls"): one still held when the solves end is counted as no force.
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
      const Scalar missing = c.target - normal_velocity(c, nullptr);
      w.add_contact_hold(k, hold);
      for (int i = 0; i < c.count; ++i)
        w.rhs.segment<3>(3 * w.free_index[std::size_t(c.vertex[i])]) += hold * c.weight[i] * missing * c.normal;
    }
  };
  // Coulomb friction of the contacts, in the solve, from the normal force each vertex's
  // contacts made the step before (lagged, as in Baraff and Witkin 1998, section 5.3): a vertex
  // slipping across its contact's normal at the step's start feels friction times that force
  // against its slip (friction_terms: a drag where it could stop the slip, else the force
  // itself). In the solve, the neighbours of
  // a vertex it holds are held with it (applied after the solve, it stopped a tablecloth's rim
  // vertices while the springs to the hanging side had been solved for them sliding: the
  // springs stretched).
  const Scalar mu = friction_;
  struct Friction {
    int vertex;
    Mat3 block;    // its term of the matrix
    Vec3 pushed;   // and of the right-hand side: its impulse is pushed - block dv
    Vec3 surface;  // the obstacle's velocity
  };
  std::vector<Friction> frictions;  // on moving obstacles, for the work they do
  w.friction_blocks.clear();
  if (mu > 0 && !w.contacts.empty()) {
    const std::vector<int> strongest = strongest_contacts(w.contacts, n);
    for (int v = 0; v < n; ++v) {
      const int k = strongest[std::size_t(v)];
      if (k < 0 || !(w.lagged.normal_force[std::size_t(v)] > 0)) continue;
      const SolveContact& c = w.contacts[std::size_t(k)];
      const Mat3 across = Mat3::Identity() - c.normal * c.normal.transpose();
      const Vec3 slip = across * (state.velocities[v] - c.surface_velocity);
      const Scalar force = mu * w.lagged.normal_force[std::size_t(v)], speed = slip.norm();
      const int a = w.free_index[v];
      const auto [block, pushed] = friction_terms(h, force, across, slip, speed, h * force >= m.masses[v] * speed);
      w.add_block(w.diagonal[a], block);
      w.friction_blocks.push_back({v, block, c.analytic});
      w.rhs.segment<3>(3 * a) += pushed;
      if (c.surface_velocity != Vec3::Zero()) frictions.push_back({v, block, pushed, c.surface_velocity});
    }
  }

  // The same friction between the cloth's layers, on the two sides' relative slip across a
  // contact's normal, from the normal force the same contact (its vertices) made the step
  // before (its impulse over that step's length, which a halving changes): its terms join the
  // contact's vertices as its penalty does (equal and opposite).
  if (mu > 0 && !w.lagged.self_impulses.empty())
    for (std::size_t k = 0; k < w.contacts.size(); ++k) {
      const SolveContact& c = w.contacts[k];
      if (!c.self) continue;
      const auto before = w.lagged.self_impulses.find(contact_key(c));
      if (before == w.lagged.self_impulses.end()) continue;
      const Mat3 across = Mat3::Identity() - c.normal * c.normal.transpose();
      Vec3 relative = Vec3::Zero();
      Scalar inverse_mass = 0;  // of the relative motion, sum w_i^2 / m_i
      for (int i = 0; i < c.count; ++i) {
        relative += c.weight[i] * state.velocities[std::size_t(c.vertex[i])];
        inverse_mass += c.weight[i] * c.weight[i] / m.masses[std::size_t(c.vertex[i])];
      }
      const Vec3 slip = across * relative;
      const Scalar force = mu * before->second.first / before->second.second, speed = slip.norm();
      const auto [block, pushed] = friction_terms(h, force, across, slip, speed, h * force * inverse_mass >= speed);
      for (int i = 0; i < c.count; ++i) {
        w.rhs.segment<3>(3 * w.free_index[std::size_t(c.vertex[i])]) += c.weight[i] * pushed;
        for (int j = 0; j < c.count; ++j) w.add_block(w.contact_blocks[k][i][j], c.weight[i] * c.weight[j] * block);
      }
    }

  w.contact_holds.assign(w.contacts.size(), 0);
  for (std::size_t k = 0; k < w.contacts.size(); ++k) {
    Scalar scale = 0;
    for (int i = 0; i < w.contacts[k].count; ++i)
      scale = std::max(scale, w.scale[std::size_t(w.free_index[std::size_t(w.contacts[k].vertex[i])])]);
    w.contact_holds[k] = (w.contacts[k].self ? SELF_CONTACT_HOLD : RESPONSE_HOLD) * scale;
  }
  // A contact whose force pulls its vertices (towards an obstacle, or the layers together) is
  // released. The layers' and a moving obstacle's are released at once: the step is solved
  // again without them, at most solver.release_solves times (1 by default), while any pulls
  // or a released pair closes; a moving obstacle's pulling after that are released and the step
  // solved once more, the layers' at the next step. Held
  // for the step, a pull between layers moves both sides with one velocity (a cloth lifted off
  // another by its edge takes some of the one under it up with it: more solves, less of it,
  // docs/collisions.md), and a moving obstacle's drags the cloth with it (a sphere leaving a
  // struck curtain stretched it past its strain limit). A still obstacle's pulls alone are
  // released at the next step's solve, as Baraff and Witkin (1998, section 5.3) release a
  // constraint: held in this one, a pull keeps its vertices' normal speed at zero, does no
  // work and gives them no momentum; it stays released while its vertices do not approach.
  // Solved again for the ground's pulls, the pile's heaped frames factorised the system twice
  // a step.
  std::vector<char> held(w.contacts.size(), 1);
  std::vector<char> released_before(w.contacts.size(), 0);  // released for an earlier step's pull
  for (std::size_t k = 0; k < w.contacts.size(); ++k)
    if (w.lagged.is_released(w.contacts[k]) && !(normal_velocity(w.contacts[k], nullptr) < w.contacts[k].target))
      held[k] = 0, released_before[k] = 1;
  w.lagged.released.clear();
  hold_contacts(1, held);
  w.contact_impulses.assign(w.contacts.size(), 0);
  std::vector<Vec3> layers_push(static_cast<std::size_t>(n));  // per vertex: the held layers' contacts' push
  std::vector<char> released_now(w.contacts.size(), 0);         // released by a solve again of this step
  bool last_release = false;  // the moving obstacles' pulls left by the solves again, released
  // Whether the last solve closes contact k's sides by more than a negligible distance.
  const auto closes = [&](std::size_t k) {
    return h * (w.contacts[k].target - normal_velocity(w.contacts[k], &w.solution)) >
           NEGLIGIBLE_MOTION * m.scene.collisions.thickness;
  };
  for (int attempt = 0;; ++attempt) {
    if (!solve(report, "the linear solver failed: ")) return false;
    for (std::size_t k = 0; k < w.contacts.size(); ++k)
      if (held[k]) w.contact_impulses[k] = w.contact_holds[k] * (w.contacts[k].target - normal_velocity(w.contacts[k], &w.solution));
    // The contacts between layers over-determine their vertices' motion (a vertex over a
    // face, that face's vertices under faces around it, edges crossing between), and their
    // penalties share the load unevenly: two layers driven together had a third of their held
    // contacts pulling in a step where all stop the approach. Such a contact is not pulling
    // while the held contacts together push its sides apart: only where their sum, along its
    // normal, brings its sides together (its vertices' pushes over their masses, by its
    // weights) is its pull one.
    std::fill(layers_push.begin(), layers_push.end(), Vec3::Zero());
    for (std::size_t k = 0; k < w.contacts.size(); ++k)
      if (held[k] && w.contacts[k].self)
        for (int i = 0; i < w.contacts[k].count; ++i)
          layers_push[std::size_t(w.contacts[k].vertex[i])] += w.contacts[k].weight[i] * w.contact_impulses[k] * w.contacts[k].normal;
    std::vector<char> pulling(w.contacts.size(), 0);
    bool again = false;  // a pull to release at once
    for (std::size_t k = 0; k < w.contacts.size(); ++k) {
      if (!held[k] || !(w.contact_impulses[k] < 0)) continue;
      const SolveContact& c = w.contacts[k];
      Scalar together = 0;  // m/s: what the held layers' contacts do to its sides' normal speed apart
      for (int i = 0; i < c.count && c.self; ++i)
        together += c.weight[i] * layers_push[std::size_t(c.vertex[i])].dot(c.normal) / m.masses[std::size_t(c.vertex[i])];
      // A pull too weak to move its vertices by a negligible distance within the step stays
      // held (not worth releasing); a stronger one is released.
      Scalar mass = 0;
      for (int i = 0; i < c.count; ++i) mass = std::max(mass, m.masses[std::size_t(c.vertex[i])]);
      if ((!c.self || together < 0) && -w.contact_impulses[k] * h > mass * NEGLIGIBLE_MOTION * m.scene.collisions.thickness) {
        pulling[k] = 1;
        if (c.self || c.target != 0) again = true;
      }
      w.contact_impulses[k] = 0;  // a pull: counted as no force
    }
    // A contact released at once whose sides now close is held again (an active set: releasing
    // some pulls moves the load onto others, and a pair let go may then close).
    std::vector<char> closing(w.contacts.size(), 0);
    for (std::size_t k = 0; k < w.contacts.size(); ++k)
      if (released_now[k] && closes(k)) closing[k] = 1, again = true;
    // Pulling, they are not held by the response's spread either (contact_held).
    for (std::size_t k = 0; k < w.contacts.size(); ++k)
      if (pulling[k]) held[k] = 0, released_now[k] = 1;
    if (!again || attempt >= m.scene.solver.release_solves) {
      // A moving obstacle's pull still held after the solves again would move its vertices with
      // the obstacle's surface: a curtain wrapped around a mesh ball that went on through it was
      // dragged along by its contacts behind the ball, to 1.55 times its rest length at 6 m/s
      // and to 1.71 at 8 m/s with a limit of 1.1
      // (Integrator.StrainLimitingHoldsACurtainStruckByAMovingMeshBall; the analytic sphere's
      // cloth slid off). So those are released and the step solved once more; the pulls that
      // solve finds are released at the next step's, and the pairs it lets close are not held
      // again: the response stops any approach. Every pull is also released at the next step's
      // solve, as before.
      std::vector<char> dragging(w.contacts.size(), 0);
      bool drags = false;
      for (std::size_t k = 0; k < w.contacts.size() && !last_release; ++k)
        if (pulling[k] && !w.contacts[k].self && w.contacts[k].target != 0) dragging[k] = 1, drags = true;
      for (std::size_t k = 0; k < w.contacts.size(); ++k)
        if (pulling[k]) w.lagged.released.emplace_back(contact_key(w.contacts[k]), w.contacts[k].normal);
      if (!drags) break;
      last_release = true;
      hold_contacts(-1, dragging);
      continue;
    }
    hold_contacts(-1, pulling);
    hold_contacts(1, closing);
    for (std::size_t k = 0; k < w.contacts.size(); ++k)
      if (closing[k]) held[k] = 1, released_now[k] = 0;
  }
  // A contact released for an earlier pull stays released while the solve does not move its
  // vertices in: their speed at the step's start is no test of that once the response has
  // stopped them. A ribbon's vertex resting on the ground, released for one step's pull, fell
  // in every later solve (nothing held it), the response stopped it, and every step of the
  // pile's frames 6-24 spread that stop through a second factorisation.
  for (std::size_t k = 0; k < w.contacts.size(); ++k)
    if (released_before[k] && !held[k] && !closes(k)) w.lagged.released.emplace_back(contact_key(w.contacts[k]), w.contacts[k].normal);
  std::sort(w.lagged.released.begin(), w.lagged.released.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  w.contact_held = held;
  // The work the held contacts did on the cloth at moving obstacles' velocities (their normal
  // impulses and their friction), for the step's energy ledger: zero on still obstacles.
  w.contact_work = 0;
  for (std::size_t k = 0; k < w.contacts.size(); ++k) {
    // The impulse reaches the cloth by its vertices' weights: all of it, but for a mesh
    // contact whose pinned corners were folded out (find_contacts), whose share they take.
    Scalar share = 0;
    for (int i = 0; i < w.contacts[k].count; ++i) share += w.contacts[k].weight[i];
    if (std::abs(share - 1) < WHOLE_SHARE) share = 1;  // a whole contact's weights, summed with rounding
    w.contact_work += share * w.contact_impulses[k] * w.contacts[k].normal.dot(w.contacts[k].surface_velocity);
  }
  for (const Friction& f : frictions)
    w.contact_work += (f.pushed - f.block * w.solution.segment<3>(3 * w.free_index[std::size_t(f.vertex)])).dot(f.surface);
  w.contact_work = std::max<Scalar>(0, w.contact_work);
  // The normal impulses of the cloth's contacts with itself, for the next step's friction.
  w.lagged.self_impulses.clear();
  for (std::size_t k = 0; k < w.contacts.size(); ++k)
    if (w.contacts[k].self && w.contact_impulses[k] > 0)
      w.lagged.self_impulses.emplace(contact_key(w.contacts[k]), std::make_pair(w.contact_impulses[k], h));
  // The normal forces of the obstacles' contacts, for the next step's friction.
  w.lagged.normal_force.assign(std::size_t(n), 0);
  for (std::size_t k = 0; k < w.contacts.size(); ++k)
    for (int i = 0; i < w.contacts[k].count && !w.contacts[k].self; ++i)
      w.lagged.normal_force[std::size_t(w.contacts[k].vertex[i])] += w.contacts[k].weight[i] * w.contact_impulses[k] / h;

  // Velocities; the motion of the step starts as the same velocities.
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    state.velocities[v] += a >= 0 ? Vec3(w.solution.segment<3>(3 * a)) : pinned_dv[v];
  }
  return true;
}

bool Integrator::solve(StepReport& report, const std::string& failure, const VectorX* again, bool spread) {
  Workspace& w = *work_;
  const auto begin = std::chrono::steady_clock::now();
  LinearSolver& solver = spread ? *spread_solver_ : *solver_;
  const SolveReport solved = again ? solver.solve_again(*again, w.solution)
                                   : solver.solve(spread ? w.spread_matrix : w.matrix, w.rhs, w.solution);
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
  // The step's system as assembled, the held vertices' changes as penalties: linear in those
  // changes, motion and velocities apart. The solve's contacts with spheres and planes and their
  // friction are added back on the vertices the response did not change: without them the
  // spread slid and sank a pile's ground contacts, the analytic response after it stopped them
  // again, and the stretch springs between them and the vertices the collision response had
  // changed ended the step compressed by 14 % (a ribbon piling on the ground, frame 24: 0.44 J
  // above its bound). A held vertex is what the response made of it, and a mesh obstacle's
  // contacts are the collision pipeline's to answer again after the spread (kept, a tablecloth
  // on a table mesh made 10 J): their terms stay out.
  if (!w.contacts.empty()) std::copy(w.assembled.begin(), w.assembled.end(), w.matrix.valuePtr());
  for (std::size_t k = 0; k < w.contacts.size(); ++k) {
    const SolveContact& c = w.contacts[k];
    bool kept = c.analytic && w.contact_held[k];
    for (int i = 0; i < c.count; ++i) kept = kept && !held[std::size_t(c.vertex[i])];
    if (kept) w.add_contact_hold(k, w.contact_holds[k]);
  }
  for (const auto& f : w.friction_blocks)
    if (f.analytic && !held[std::size_t(f.vertex)]) w.add_block(w.diagonal[w.free_index[std::size_t(f.vertex)]], f.block);
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
  // With the self contacts' blocks in the pattern (all zero here), the system is solved over
  // the springs', hinges' and membranes' pattern alone: the same matrix without the fill the
  // layers' coupling makes (a stack of three cloths at rest: 0.16 against 1.6 GFlop a
  // factorisation). An entry outside it that is not zero keeps the whole pattern.
  bool apart = !w.spread_source.empty();
  for (std::size_t k = 0; k < w.in_base.size() && apart; ++k) apart = w.in_base[k] || w.matrix.valuePtr()[k] == 0;
  if (apart) {
    if (!spread_solver_) spread_solver_ = make_linear_solver(m.scene.solver);
    const Scalar* values = w.matrix.valuePtr();
    Scalar* spread_values = w.spread_matrix.valuePtr();
    for (std::size_t e = 0; e < w.spread_source.size(); ++e) spread_values[e] = values[w.spread_source[e]];
  }
  if (!solve(report, "the linear solver failed spreading the collision response: ", nullptr, apart)) return;
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    if (a >= 0 && !held[std::size_t(v)]) motion[v] = solved[v] + Vec3(w.solution.segment<3>(3 * a));
  }
  if (!solve(report, "the linear solver failed spreading the collision response: ", &velocity_rhs, apart)) return;
  for (int v = 0; v < n; ++v) {
    const int a = w.free_index[v];
    if (a >= 0 && !held[std::size_t(v)]) velocities[v] = solved[v] + Vec3(w.solution.segment<3>(3 * a));
  }
}

}  // namespace drape
