#include "projective.h"

#include <algorithm>

namespace drape {

ProjectiveSolver::ProjectiveSolver(const Model& model, std::vector<int> free_index, int free_count)
    : model_(model),
      free_index_(std::move(free_index)),
      free_count_(free_count),
      iterations_(model.scene.solver.iterations),
      rho_(model.scene.solver.chebyshev) {
  base_.setZero(free_count_, 3);
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
  ++factorisations_;
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

  // The right-hand side's constant part: M y + h a M (x0 + h w) and the held vertices' pull.
  const Vec3 wind = m.scene.wind ? m.scene.wind->velocity : Vec3::Zero();
  for (std::size_t v = 0; v < m.masses.size(); ++v) {
    const int a = free_index_[v];
    if (a < 0) continue;
    const Scalar mass = m.masses[v];
    const Vec3 inertial = mass * (x0[v] + h * (*step.velocities)[v]) + h * h * (*step.forces)[v];
    base_.row(a) = (inertial + h * m.air_damping[v] * mass * (x0[v] + h * wind)).transpose();
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
      ++factorisations_;
      held_key_ = std::move(key);
    }
    for (std::size_t k = 0; k < held->vertices.size(); ++k)
      base_.row(free_index_[std::size_t(held->vertices[k])]) += held_penalty_[k] * held->targets[k].transpose();
    factor = &held_factor_;
  }

  // Chebyshev semi-iterative acceleration (Wang, "A Chebyshev semi-iterative approach for
  // accelerating projective and position-based dynamics", SIGGRAPH Asia 2015, eq. 11) with
  // the iteration's spectral radius estimate rho (an overestimate diverges).
  const Scalar rho = rho_;
  previous_ = positions;
  current_ = positions;
  Scalar omega = 1;
  for (int iteration = 0; iteration < iterations_; ++iteration) {
    // Local step: each spring's rest-length target p and damping target q, weighted.
    rhs_ = base_;
    for (const Spring& s : m.springs) {
      const Vec3 z = positions[std::size_t(s.i)] - positions[std::size_t(s.j)];
      const Vec3 z0 = x0[std::size_t(s.i)] - x0[std::size_t(s.j)];
      const Scalar length = z.norm();
      // A spring of zero length has no direction: its start's, or any.
      const Vec3 d = length > 0 ? Vec3(z / length) : z0.norm() > 0 ? Vec3(z0.normalized()) : Vec3::UnitX();
      const Vec3 p = s.rest_length * d;
      const Vec3 q = z - (z - z0).dot(d) * d;
      const Vec3 target = h * h * s.stiffness * p + h * s.damping * q;
      const Scalar weight = h * h * s.stiffness + h * s.damping;
      const int a = free_index_[std::size_t(s.i)], b = free_index_[std::size_t(s.j)];
      if (a >= 0) rhs_.row(a) += (b >= 0 ? target : Vec3(target + weight * positions[std::size_t(s.j)])).transpose();
      if (b >= 0) rhs_.row(b) += (a >= 0 ? Vec3(-target) : Vec3(weight * positions[std::size_t(s.i)] - target)).transpose();
    }
    // Global step: the run's factorisation.
    if (!factor->solve(rhs_, solution_)) {
      error = "CHOLMOD's solve of the projective system failed";
      return false;
    }
    omega = rho <= 0 || iteration == 0 ? 1 : iteration == 1 ? 2 / (2 - rho * rho) : 4 / (4 - rho * rho * omega);
    for (std::size_t v = 0; v < positions.size(); ++v) {
      const int a = free_index_[v];
      if (a < 0) continue;
      const Vec3 next = solution_.row(a).transpose();
      positions[v] = omega * (next - previous_[v]) + previous_[v];
      previous_[v] = current_[v];
      current_[v] = positions[v];
    }
  }
  return true;
}

int ProjectiveSolver::analyses() const {
  int total = held_factor_.analyses();
  for (const auto& [h, sys] : systems_) total += sys.factor.analyses();
  return total;
}

}  // namespace drape
