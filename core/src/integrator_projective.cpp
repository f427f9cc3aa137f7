#include <algorithm>
#include <chrono>

#include "drape/core/integrator.h"
#include "drape/core/obstacle.h"
#include "integrator_workspace.h"
#include "projective.h"

namespace drape {

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
  // First guess: each free vertex's end without its springs, the inertial prediction y slowed
  // by the air's damping towards the wind, (y + h a (x0 + h w)) / (1 + h a); the prescribed
  // end for the pinned ones. In free fall it is the answer, found before any back-substitution.
  std::vector<Vec3> positions(n);
  for (std::size_t v = 0; v < n; ++v) {
    positions[v] = state.positions[v] + h * (state.velocities[v] + pinned_dv[v]);
    if (w.free_index[v] < 0) continue;
    const Scalar air = h * m.air_damping[v];
    positions[v] = (positions[v] + h * h / m.masses[v] * w.explicit_forces[v] + air * (state.positions[v] + h * air_velocity)) / (1 + air);
  }
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
    if (friction_ > 0) {
      const std::vector<int> strongest = strongest_contacts(w.contacts, int(n));
      for (std::size_t v = 0; v < n; ++v)
        if (strongest[v] >= 0 && w.lagged.normal_force[v] > 0) {
          const SolveContact& c = w.contacts[std::size_t(strongest[v])];
          contacts.friction.push_back({int(v), c.normal, c.surface_velocity, friction_ * w.lagged.normal_force[v]});
        }
    }
  }
  if (!iterate_projective(state.positions, positions, report, "the projective solver failed: ", nullptr, &contacts))
    return false;
  // The normal forces, for the next step's friction; the contacts' work, for the ledger.
  w.lagged.normal_force.resize(n);
  for (std::size_t v = 0; v < n; ++v) w.lagged.normal_force[v] = projective_->contact_impulses()[v] / h;
  w.contact_work = projective_->contact_work();
  for (std::size_t v = 0; v < n; ++v)
    state.velocities[v] = w.free_index[v] >= 0 ? Vec3((positions[v] - state.positions[v]) / h)
                                               : Vec3(state.velocities[v] + pinned_dv[v]);
  return true;
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

}  // namespace drape
