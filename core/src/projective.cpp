#include "projective.h"

#include <algorithm>
#include <limits>

namespace drape {

ProjectiveSolver::ProjectiveSolver(const Model& model, std::vector<int> free_index, int free_count)
    : model_(model),
      free_index_(std::move(free_index)),
      free_count_(free_count),
      iterations_(model.scene.solver.iterations),
      rho_(model.scene.solver.chebyshev) {
  base_.assign(std::size_t(free_count_), Vec3::Zero());
  sums_ = base_;
  predicted_ = base_;
  rhs_.setZero(free_count_, 3);
  solution_.setZero(free_count_, 3);
}

ProjectiveSolver::System* ProjectiveSolver::system(Scalar h, std::string& error) {
  if (auto found = systems_.find(h); found != systems_.end()) return &found->second;
  const Model& m = model_;
  std::vector<Eigen::Triplet<Scalar>> entries;
  entries.reserve(std::size_t(free_count_) + 4 * m.springs.size());
  for (std::size_t v = 0; v < m.masses.size(); ++v) {
    const int a = free_index_[v];
    if (a >= 0) entries.emplace_back(a, a, m.masses[v] * (1 + h * m.air_damping[v]));
  }
  for (const Spring& s : m.springs) {
    const Scalar weight = h * h * s.stiffness + h * s.damping;
    const int a = free_index_[std::size_t(s.i)], b = free_index_[std::size_t(s.j)];
    if (a >= 0) entries.emplace_back(a, a, weight);
    if (b >= 0) entries.emplace_back(b, b, weight);
    if (a >= 0 && b >= 0) entries.emplace_back(a, b, -weight), entries.emplace_back(b, a, -weight);
  }
  System sys;
  sys.springs.reserve(m.springs.size());
  for (const Spring& s : m.springs)
    sys.springs.push_back({s.i, s.j, free_index_[std::size_t(s.i)], free_index_[std::size_t(s.j)], s.rest_length,
                           h * h * s.stiffness, h * s.damping});
  sys.matrix.resize(free_count_, free_count_);
  sys.matrix.setFromTriplets(entries.begin(), entries.end());  // duplicates summed
  sys.matrix.makeCompressed();
  if (diagonal_offset_.empty()) {
    diagonal_offset_.resize(std::size_t(free_count_));
    for (int a = 0; a < free_count_; ++a) {
      const auto* begin = sys.matrix.innerIndexPtr() + sys.matrix.outerIndexPtr()[a];
      const auto* end = sys.matrix.innerIndexPtr() + sys.matrix.outerIndexPtr()[a + 1];
      diagonal_offset_[std::size_t(a)] = int(std::lower_bound(begin, end, a) - sys.matrix.innerIndexPtr());
    }
  }
  if (!sys.factor.factorise(sys.matrix)) {
    error = "CHOLMOD could not factorise the projective system (not positive definite)";
    return nullptr;
  }
  return &systems_.emplace(h, std::move(sys)).first->second;
}

bool ProjectiveSolver::solve(const ProjectiveStep& step, std::vector<Vec3>& positions, std::string& error,
                             const HeldVertices* held, Scalar hold) {
  const Model& m = model_;
  const Scalar h = step.h;
  const std::vector<Vec3>& x0 = *step.start;
  System* sys = system(h, error);
  if (!sys) return false;
  const CholmodFactor* factor = &sys->factor;
  spring_start_.resize(sys->springs.size());
  spring_direction_.resize(sys->springs.size());
  for (std::size_t k = 0; k < sys->springs.size(); ++k) {
    const Vec3 z0 = x0[std::size_t(sys->springs[k].i)] - x0[std::size_t(sys->springs[k].j)];
    spring_start_[k] = z0;
    spring_direction_[k] = z0.norm() > 0 ? Vec3(z0.normalized()) : Vec3::UnitX();
  }

  // The right-hand side's constant part: M y + h a M (x0 + h w) and the held vertices' pull.
  const Vec3 wind = m.scene.wind ? m.scene.wind->velocity : Vec3::Zero();
  for (std::size_t v = 0; v < m.masses.size(); ++v) {
    const int a = free_index_[v];
    if (a < 0) continue;
    const Scalar mass = m.masses[v];
    const Vec3 inertial = mass * (x0[v] + h * (*step.velocities)[v]) + h * h * (*step.forces)[v];
    base_[std::size_t(a)] = inertial + h * m.air_damping[v] * mass * (x0[v] + h * wind);
    predicted_[std::size_t(a)] = x0[v] + h * (*step.velocities)[v] + h * h / mass * (*step.forces)[v];
  }
  if (held && !held->vertices.empty()) {
    HeldKey key{h, hold, held->vertices};
    if (!(key == held_key_)) {
      held_key_ = HeldKey{};
      held_matrix_ = sys->matrix;
      Scalar* values = held_matrix_.valuePtr();
      held_penalty_.resize(held->vertices.size());
      for (std::size_t k = 0; k < held->vertices.size(); ++k) {
        const int offset = diagonal_offset_[std::size_t(free_index_[std::size_t(held->vertices[k])])];
        held_penalty_[k] = hold * values[offset];
        values[offset] += held_penalty_[k];
      }
      if (!held_factor_.factorise(held_matrix_)) {
        error = "CHOLMOD could not factorise the projective system with the collision response held";
        return false;
      }
      held_key_ = std::move(key);
    }
    for (std::size_t k = 0; k < held->vertices.size(); ++k)
      base_[std::size_t(free_index_[std::size_t(held->vertices[k])])] += held_penalty_[k] * held->targets[k];
    factor = &held_factor_;
  }

  // The objective being minimised, at the current positions: its vertices' part here, the
  // springs' in the local step's pass.
  const auto vertex_objective = [&](const std::vector<Vec3>& x) {
    Scalar total = 0;
    for (std::size_t v = 0; v < x.size(); ++v) {
      const int a = free_index_[v];
      if (a < 0) continue;
      const Scalar mass = m.masses[v];
      total += 0.5 * mass * (x[v] - predicted_[std::size_t(a)]).squaredNorm() +
               0.5 * h * m.air_damping[v] * mass * (x[v] - x0[v] - h * wind).squaredNorm();
    }
    if (held)
      for (std::size_t k = 0; k < held->vertices.size(); ++k)
        total += 0.5 * held_penalty_[k] * (x[std::size_t(held->vertices[k])] - held->targets[k]).squaredNorm();
    return total;
  };

  // Chebyshev semi-iterative acceleration (Wang, "A Chebyshev semi-iterative approach for
  // accelerating projective and position-based dynamics", SIGGRAPH Asia 2015, eq. 11) with
  // the iteration's spectral radius estimate rho. The plain iteration never raises the
  // objective; an accelerated one that does (rho too high for this step, or the springs'
  // directions turning under the extrapolation) is undone and the acceleration restarts from
  // the best iterate. The best iterate is the result.
  const Scalar rho = rho_;
  previous_ = positions;
  current_ = positions;
  best_ = positions;
  Scalar omega = 1, best_objective = std::numeric_limits<Scalar>::infinity();
  int accelerated = 0;  // global steps since the acceleration (re)started
  for (int pass = 0; pass <= iterations_; ++pass) {
    // Local step: each spring's rest-length target p = r d and damping target q = z - ((z -
    // z0) . d) d, weighted; and the objective at the current positions.
    sums_ = base_;
    Scalar objective = vertex_objective(positions);
    for (std::size_t k = 0; k < sys->springs.size(); ++k) {
      const SpringTerm& s = sys->springs[k];
      const Vec3 z = positions[std::size_t(s.i)] - positions[std::size_t(s.j)];
      const Scalar length = z.norm();
      // A spring of zero length has no direction: its start's, or any.
      const Vec3 d = length > 0 ? Vec3(z / length) : spring_direction_[k];
      // The damping acts along the spring's direction at the step's start (as the reference
      // solver's does): q is z's projection onto a fixed plane, so the iteration never raises
      // the objective.
      const Vec3& d0 = spring_direction_[k];
      const Scalar along = (z - spring_start_[k]).dot(d0);
      objective += 0.5 * s.elastic * (length - s.rest) * (length - s.rest) + 0.5 * s.viscous * along * along;
      // The weighted targets: rest length along d (elastic), z less its change along d0 (viscous).
      const Vec3 target = (s.elastic * s.rest) * d + s.viscous * (z - along * d0);
      const Scalar weight = s.elastic + s.viscous;
      if (s.a >= 0) sums_[std::size_t(s.a)] += s.b >= 0 ? target : Vec3(target + weight * positions[std::size_t(s.j)]);
      if (s.b >= 0) sums_[std::size_t(s.b)] += s.a >= 0 ? Vec3(-target) : Vec3(weight * positions[std::size_t(s.i)] - target);
    }
    if (objective < best_objective) {
      best_objective = objective;
      best_ = positions;
    } else if (rho > 0 && accelerated > 1) {
      positions = best_;
      previous_ = positions;
      current_ = positions;
      accelerated = 0;
      continue;  // the local step again, at the best iterate
    }
    if (pass == iterations_) break;  // the last pass only weighs the last iterate
    // Global step: the run's factorisation.
    for (int a = 0; a < free_count_; ++a) rhs_.row(a) = sums_[std::size_t(a)].transpose();
    if (!factor->solve(rhs_, solution_)) {
      error = "CHOLMOD's solve of the projective system failed";
      return false;
    }
    omega = rho <= 0 || accelerated == 0 ? 1 : accelerated == 1 ? 2 / (2 - rho * rho) : 4 / (4 - rho * rho * omega);
    ++accelerated;
    for (std::size_t v = 0; v < positions.size(); ++v) {
      const int a = free_index_[v];
      if (a < 0) continue;
      const Vec3 next = solution_.row(a).transpose();
      positions[v] = omega * (next - previous_[v]) + previous_[v];
      previous_[v] = current_[v];
      current_[v] = positions[v];
    }
  }
  positions = best_;
  return true;
}

int ProjectiveSolver::analyses() const {
  int total = held_factor_.analyses();
  for (const auto& [h, sys] : systems_) total += sys.factor.analyses();
  return total;
}

}  // namespace drape
