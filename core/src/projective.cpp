#include "projective.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "spring_pulls.h"

namespace drape {
namespace {

// The mean rest length of the stretch springs (the cloth's edges), m; 0 without any.
Scalar mean_edge(const Model& model) {
  Scalar sum = 0;
  int count = 0;
  for (const Spring& s : model.springs)
    if (s.kind == SpringKind::Stretch) sum += s.rest_length, ++count;
  return count > 0 ? sum / count : 0;
}

}  // namespace

ProjectiveSolver::ProjectiveSolver(const Model& model, std::vector<int> free_index, int free_count, int threads)
    : model_(model),
      free_index_(std::move(free_index)),
      free_count_(free_count),
      iterations_(model.scene.solver.iterations),
      history_(model.scene.solver.history),
      rho_(model.scene.solver.chebyshev),
      converged_move_(std::max(model.scene.solver.tolerance, ROUNDING_MOVE) * mean_edge(model)),
      arena_(std::make_unique<tbb::task_arena>(std::max(1, threads))) {
  for (std::size_t v = 0; v < model.masses.size(); ++v)
    if (free_index_[v] >= 0) least_mass_ = std::min(least_mass_, model.masses[v]);
  base_.assign(std::size_t(free_count_), Vec3::Zero());
  sums_ = base_;
  predicted_ = base_;
  rhs_.setZero(free_count_, 3);
  solution_.setZero(free_count_, 3);
  // Each free vertex's springs, in the model's order, with the sign of its end (+1 for i).
  incidence_start_.assign(std::size_t(free_count_) + 1, 0);
  for (const Spring& s : model.springs)
    for (int end : {s.i, s.j})
      if (const int a = free_index_[std::size_t(end)]; a >= 0) ++incidence_start_[std::size_t(a) + 1];
  for (int a = 0; a < free_count_; ++a) incidence_start_[std::size_t(a) + 1] += incidence_start_[std::size_t(a)];
  // The springs' ends, and their arrays (the padding a spring along x of unit length, at rest,
  // with no weight).
  for (const Spring& s : model.springs)
    spring_ends_.push_back({s.i, s.j, free_index_[std::size_t(s.i)], free_index_[std::size_t(s.j)]});
  const std::size_t padded = padded_springs();
  SpringArrays& arrays = spring_arrays_;
  for (std::vector<double>* v : {&arrays.rest, &arrays.sy, &arrays.sz, &arrays.d0y, &arrays.d0z}) v->assign(padded, 0);
  for (std::vector<double>* v : {&arrays.sx, &arrays.d0x}) v->assign(padded, 1);
  for (std::size_t k = 0; k < model.springs.size(); ++k) arrays.rest[k] = model.springs[k].rest_length;
  spring_chunk_ = std::make_unique<SpringChunk>();
  incidence_.resize(std::size_t(incidence_start_.back()));
  std::vector<int> filled(incidence_start_.begin(), incidence_start_.end() - 1);
  for (std::size_t k = 0; k < model.springs.size(); ++k) {
    const Spring& s = model.springs[k];
    if (const int a = free_index_[std::size_t(s.i)]; a >= 0) incidence_[std::size_t(filled[std::size_t(a)]++)] = int(2 * k);
    if (const int b = free_index_[std::size_t(s.j)]; b >= 0) incidence_[std::size_t(filled[std::size_t(b)]++)] = int(2 * k + 1);
  }
}

ProjectiveSolver::~ProjectiveSolver() = default;

ProjectiveSolver::System* ProjectiveSolver::system(Scalar h, std::string& error) {
  if (auto found = systems_.find(h); found != systems_.end()) return &found->second;
  const Model& m = model_;
  std::vector<Eigen::Triplet<Scalar>> entries;
  entries.reserve(std::size_t(free_count_) + 4 * m.springs.size() + 16 * m.hinges.size());
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
  // The bending hinges' energy is quadratic already: (h^2 + h c) k k^T, exactly.
  for (const Hinge& hinge : m.hinges) {
    const Scalar weight = h * h + h * hinge.damping;
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = 0; j < 4; ++j) {
        const int a = free_index_[std::size_t(hinge.v[i])], b = free_index_[std::size_t(hinge.v[j])];
        if (a >= 0 && b >= 0 && hinge.k[i] != 0 && hinge.k[j] != 0) entries.emplace_back(a, b, weight * hinge.k[i] * hinge.k[j]);
      }
  }
  System sys;
  sys.elastic.assign(padded_springs(), 0), sys.viscous.assign(padded_springs(), 0);
  for (std::size_t k = 0; k < m.springs.size(); ++k)
    sys.elastic[k] = h * h * m.springs[k].stiffness, sys.viscous[k] = h * m.springs[k].damping;
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
  iterations_done_ = 0;
  System* sys = system(h, error);
  if (!sys) return false;
  const CholmodFactor* factor = &sys->factor;
  SpringArrays& arrays = spring_arrays_;
  for (std::size_t k = 0; k < spring_ends_.size(); ++k) {
    const Vec3 z0 = x0[std::size_t(spring_ends_[k].i)] - x0[std::size_t(spring_ends_[k].j)];
    const Vec3 d0 = z0.norm() > 0 ? Vec3(z0.normalized()) : Vec3::UnitX();
    arrays.sx[k] = z0.x(), arrays.sy[k] = z0.y(), arrays.sz[k] = z0.z();
    arrays.d0x[k] = d0.x(), arrays.d0y[k] = d0.y(), arrays.d0z[k] = d0.z();
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
  // L-BFGS keeps the held vertices at their targets (its steps leave them out: no new
  // factorisation); local-global holds them by a penalty in a system factorised for them.
  fixed_.assign(std::size_t(free_count_), 0);
  if (held && history_ > 0) {
    for (std::size_t k = 0; k < held->vertices.size(); ++k) {
      const std::size_t v = std::size_t(held->vertices[k]);
      fixed_[std::size_t(free_index_[v])] = 1;
      positions[v] = held->targets[k];
    }
    held = nullptr;
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

  step_ = {sys, factor, &step, held};
  contact_impulse_.assign(positions.size(), 0);
  contact_work_ = 0;
  shapes_.clear();
  planes_.clear();
  active_.clear();
  if (step.contacts && history_ > 0) prepare_contacts(*step.contacts);
  const bool ok = history_ > 0 ? quasi_newton(positions, error) : local_global(positions, error);
  if (ok && step.contacts && history_ > 0) {
    active_reactions(positions, raw_gradient_);
    contact_terms(positions, nullptr, true);
  }
  step_ = {};
  return ok;
}

Scalar ProjectiveSolver::evaluate(const std::vector<Vec3>& x, Block* gradient) {
  const Model& m = model_;
  const System& sys = *step_.system;
  const Scalar h = step_.step->h;
  const std::vector<Vec3>& x0 = *step_.step->start;
  const Vec3 wind = m.scene.wind ? m.scene.wind->velocity : Vec3::Zero();
  // Each spring's elastic energy of its length's change and its damping along its direction
  // at the step's start, with the pull on its end i (the gradient's part; -pull on j) and the
  // local step's weighted target (rest length along the current direction d, p = r d; z less
  // its change along d0, q = z - ((z - z0) . d0) d0).
  const SpringArrays& arrays = spring_arrays_;
  const auto spring = [&](std::size_t k, Vec3& pull, Vec3& target) {
    const SpringEnds& e = spring_ends_[k];
    const Scalar elastic = sys.elastic[k], viscous = sys.viscous[k], rest = arrays.rest[k];
    const Vec3 z = x[std::size_t(e.i)] - x[std::size_t(e.j)];
    const Scalar length = z.norm();
    // The damping acts along the spring's direction at the step's start (as the reference
    // solver's does): q is z's projection onto a fixed plane, so the iteration never raises
    // the objective.
    const Vec3 d0(arrays.d0x[k], arrays.d0y[k], arrays.d0z[k]), z0(arrays.sx[k], arrays.sy[k], arrays.sz[k]);
    // A spring of zero length has no direction: its start's, or any. (One division, not
    // three: the loop waited on them.)
    const Vec3 d = length > 0 ? Vec3(z * (1 / length)) : d0;
    const Scalar along = (z - z0).dot(d0);
    pull = elastic * (length - rest) * d + viscous * along * d0;
    target = (elastic * rest) * d + viscous * (z - along * d0);
    return 0.5 * elastic * (length - rest) * (length - rest) + 0.5 * viscous * along * along;
  };
  // The vertices' part of the objective: inertia, the air's damping.
  const auto vertex = [&](std::size_t v, int a, Vec3& grad) {
    const Scalar mass = m.masses[v], air = h * m.air_damping[v] * mass;
    const Vec3 inertia = x[v] - predicted_[std::size_t(a)], drag = x[v] - x0[v] - h * wind;
    grad = mass * inertia + air * drag;
    return 0.5 * mass * inertia.squaredNorm() + 0.5 * air * drag.squaredNorm();
  };
  Scalar total = 0;
  if (gradient) {
    // L-BFGS: the springs' pulls and energies many at a time (spring_pulls, the formula
    // above's bits), then each free vertex's term and its springs' pulls in the model's order,
    // and the energies summed by fixed blocks in order: the same bits for any thread count.
    const std::size_t springs = spring_ends_.size(), vertices = x.size();
    // The springs [begin, end) of one chunk (begin a multiple of SPRING_CHUNK): z gathered into
    // the chunk's arrays (the padding a spring along x of unit length), their pulls and
    // energies out into them.
    const auto chunk_pulls = [&](std::size_t begin, std::size_t end, SpringChunk& c) {
      const std::size_t count = end - begin, padded = (count + SPRING_LANES - 1) / SPRING_LANES * SPRING_LANES;
      for (std::size_t k = 0; k < count; ++k) {
        const SpringEnds& e = spring_ends_[begin + k];
        const Vec3 z = x[std::size_t(e.i)] - x[std::size_t(e.j)];
        c.zx[k] = z.x(), c.zy[k] = z.y(), c.zz[k] = z.z();
      }
      for (std::size_t k = count; k < padded; ++k) c.zx[k] = 1, c.zy[k] = 0, c.zz[k] = 0;
      spring_pulls({c.zx.data(), c.zy.data(), c.zz.data(), arrays.sx.data() + begin, arrays.sy.data() + begin,
                    arrays.sz.data() + begin, arrays.d0x.data() + begin, arrays.d0y.data() + begin,
                    arrays.d0z.data() + begin, arrays.rest.data() + begin, sys.elastic.data() + begin,
                    sys.viscous.data() + begin, padded},
                   {c.px.data(), c.py.data(), c.pz.data(), c.energy.data()});
    };
    std::vector<Vec3>& g = gradient_rows_;
    g.resize(std::size_t(free_count_));
    if (arena_->max_concurrency() == 1) {
      // One thread: the same sums in the same order, without tasks or stored pulls (each
      // chunk's pulls go straight to their vertices).
      Scalar vertex_total = 0, spring_total = 0, block = 0;
      for (std::size_t v = 0; v < vertices; ++v) {
        if (v > 0 && v % PARALLEL_GRAIN == 0) vertex_total += block, block = 0;
        const int f = free_index_[v];
        block += f < 0 ? Scalar(0) : vertex(v, f, g[std::size_t(f)]);
      }
      if (vertices > 0) vertex_total += block;
      block = 0;
      SpringChunk& c = *spring_chunk_;
      for (std::size_t begin = 0; begin < springs; begin += SPRING_CHUNK) {
        const std::size_t end = std::min(springs, begin + SPRING_CHUNK);
        chunk_pulls(begin, end, c);
        if (begin > 0 && begin % PARALLEL_GRAIN == 0) spring_total += block, block = 0;
        for (std::size_t k = begin; k < end; ++k) {
          const SpringEnds& e = spring_ends_[k];
          const Vec3 pull(c.px[k - begin], c.py[k - begin], c.pz[k - begin]);
          if (e.a >= 0) g[std::size_t(e.a)] += pull;
          if (e.b >= 0) g[std::size_t(e.b)] -= pull;
          block += c.energy[k - begin];
        }
      }
      if (springs > 0) spring_total += block;
      total = vertex_total + spring_total;
    } else {
      // In parallel: blocks of springs (each block's energy summed in order), then the vertices.
      vertex_energy_.assign(vertices, 0);
      pulls_.resize(springs);
      const std::size_t blocks = (springs + PARALLEL_GRAIN - 1) / PARALLEL_GRAIN;
      block_sums_.assign(blocks, 0);
      arena_->execute([&] {
        tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
          SpringChunk c;
          Scalar sum = 0;
          for (std::size_t begin = b * PARALLEL_GRAIN; begin < std::min(springs, (b + 1) * PARALLEL_GRAIN); begin += SPRING_CHUNK) {
            const std::size_t end = std::min(springs, begin + SPRING_CHUNK);
            chunk_pulls(begin, end, c);
            for (std::size_t k = begin; k < end; ++k) {
              pulls_[k] = Vec3(c.px[k - begin], c.py[k - begin], c.pz[k - begin]);
              sum += c.energy[k - begin];
            }
          }
          block_sums_[b] = sum;
        });
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices, PARALLEL_GRAIN), [&](const auto& r) {
          for (std::size_t v = r.begin(); v < r.end(); ++v) {
            const int f = free_index_[v];
            if (f < 0) continue;
            Vec3 grad;
            vertex_energy_[v] = vertex(v, f, grad);
            for (int e = incidence_start_[std::size_t(f)]; e < incidence_start_[std::size_t(f) + 1]; ++e) {
              const int end = incidence_[std::size_t(e)];
              grad += (end % 2 == 0 ? 1.0 : -1.0) * pulls_[std::size_t(end / 2)];
            }
            g[std::size_t(f)] = grad;
          }
        });
      });
      Scalar spring_total = 0;
      for (Scalar sum : block_sums_) spring_total += sum;
      total = ordered_sum(vertex_energy_.data(), vertices) + spring_total;
    }
  } else {
    // Local-global: the local step's right-hand side, summed serially.
    sums_ = base_;
    for (std::size_t v = 0; v < x.size(); ++v)
      if (const int a = free_index_[v]; a >= 0) {
        Vec3 grad;
        total += vertex(v, a, grad);
      }
    for (std::size_t k = 0; k < spring_ends_.size(); ++k) {
      const SpringEnds& s = spring_ends_[k];
      Vec3 pull, target;
      total += spring(k, pull, target);
      const Scalar weight = sys.elastic[k] + sys.viscous[k];
      if (s.a >= 0) sums_[std::size_t(s.a)] += s.b >= 0 ? target : Vec3(target + weight * x[std::size_t(s.j)]);
      if (s.b >= 0) sums_[std::size_t(s.b)] += s.a >= 0 ? Vec3(-target) : Vec3(weight * x[std::size_t(s.i)] - target);
    }
  }
  // The bending hinges (Hinge): h^2 |u|^2 / 2 and the damping's (h c / 2) |u - u0|^2, in the
  // model's order (the same bits for any thread count); local-global's right-hand side gets
  // what the matrix's part of them does not hold: the pinned corners and the damping's u0.
  for (const Hinge& hinge : m.hinges) {
    const Vec3 u = hinge_vector(hinge, x), u0 = hinge_vector(hinge, x0);
    const Scalar elastic = h * h, viscous = h * hinge.damping;
    total += 0.5 * elastic * u.squaredNorm() + 0.5 * viscous * (u - u0).squaredNorm();
    const Vec3 pull = elastic * u + viscous * (u - u0);
    Vec3 held_part = Vec3::Zero();  // the pinned corners' share of u
    for (std::size_t i = 0; i < 4; ++i)
      if (free_index_[std::size_t(hinge.v[i])] < 0) held_part += hinge.k[i] * x[std::size_t(hinge.v[i])];
    for (std::size_t i = 0; i < 4; ++i) {
      const int a = free_index_[std::size_t(hinge.v[i])];
      if (a < 0) continue;
      if (gradient) gradient_rows_[std::size_t(a)] += hinge.k[i] * pull;
      else sums_[std::size_t(a)] += hinge.k[i] * (viscous * u0 - (elastic + viscous) * held_part);
    }
  }
  // The held vertices' penalty (local-global's spread).
  if (const HeldVertices* held = step_.held)
    for (std::size_t k = 0; k < held->vertices.size(); ++k) {
      const Vec3 off = x[std::size_t(held->vertices[k])] - held->targets[k];
      total += 0.5 * held_penalty_[k] * off.squaredNorm();
      if (gradient) gradient_rows_[std::size_t(free_index_[std::size_t(held->vertices[k])])] += held_penalty_[k] * off;
    }
  total += contact_terms(x, gradient ? &gradient_rows_ : nullptr, false);
  if (gradient) {
    gradient->resize(free_count_, 3);
    for (int a = 0; a < free_count_; ++a) gradient->row(a) = gradient_rows_[std::size_t(a)].transpose();
  }
  return total;
}

std::size_t ProjectiveSolver::padded_springs() const {
  static_assert(PARALLEL_GRAIN % SPRING_CHUNK == 0 && SPRING_CHUNK % SPRING_LANES == 0,
                "a block of springs is whole chunks, a chunk whole vectors");
  return (model_.springs.size() + SPRING_LANES - 1) / SPRING_LANES * SPRING_LANES;
}

Scalar ProjectiveSolver::ordered_sum(const Scalar* values, std::size_t count) {
  // Blocks of PARALLEL_GRAIN summed in parallel, then the blocks' sums in order.
  const std::size_t blocks = (count + PARALLEL_GRAIN - 1) / PARALLEL_GRAIN;
  block_sums_.assign(blocks, 0);
  arena_->execute([&] {
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
      Scalar sum = 0;
      for (std::size_t i = b * PARALLEL_GRAIN; i < std::min(count, (b + 1) * PARALLEL_GRAIN); ++i) sum += values[i];
      block_sums_[b] = sum;
    });
  });
  Scalar total = 0;
  for (Scalar sum : block_sums_) total += sum;
  return total;
}

bool ProjectiveSolver::local_global(std::vector<Vec3>& positions, std::string& error) {
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
    const Scalar objective = evaluate(positions, nullptr);
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
    if (!step_.factor->solve(rhs_, solution_)) {
      error = "CHOLMOD's solve of the projective system failed";
      return false;
    }
    ++iterations_done_;
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
  objective_ = best_objective;
  return true;
}

bool ProjectiveSolver::quasi_newton(std::vector<Vec3>& positions, std::string& error) {
  // L-BFGS on the step's objective with the global step's matrix P as the first inverse
  // Hessian (Liu, Bouaziz and Kavan, "Quasi-Newton methods for real-time simulation of
  // hyperelastic materials", ACM TOG 2017): with no history its step -P^-1 g is exactly one
  // local-global iteration; the history of steps s and gradient changes t bends it towards
  // the springs' true curvature, which the constant P lacks (slack and compressed springs,
  // the cloth's soft modes). A step is taken whole when it lowers the objective enough
  // (Armijo), else shortened; a direction that does not descend restarts the history.
  // The spheres and planes are constraints (an active set, as in projected gradient
  // methods): every iterate keeps each free vertex at its gap (keep_out), and the active
  // vertices' gradients and steps lose their part along the surface's normal, so a resting
  // cloth's weight is held exactly, not by a penalty that lets it sink (which the response
  // then undid every step, and its change had to be spread by two more solves).
  const auto dot = [](const Block& a, const Block& b) { return (a.array() * b.array()).sum(); };
  const int memory = history_;
  history_s_.resize(std::size_t(memory));
  history_t_.resize(std::size_t(memory));
  history_rho_.assign(std::size_t(memory), 0);
  std::vector<Scalar> alpha(static_cast<std::size_t>(memory), 0.0);
  int stored = 0, newest = -1;  // the history is a ring
  keep_out(positions);
  Scalar objective = evaluate(positions, &gradient_);
  settle(positions, gradient_);
  trial_ = positions;
  for (int iteration = 0; iteration < iterations_; ++iteration) {
    // Converged before the back-substitution when no vertex could move farther than the
    // tolerance: P >= M, so the step d = P^-1 g has |d|_M^2 <= g^T P^-1 g <= g^T M^-1 g, and
    // no vertex moves farther than sqrt(g^T M^-1 g / least mass) (a free fall's first guess
    // is its answer: no back-substitution at all).
    // (Only without history: L-BFGS's H may move farther than P^-1 along the soft modes.)
    if (stored == 0 && inverse_mass_norm(gradient_) <= converged_move_ * converged_move_ * least_mass_) break;
    // The two-loop recursion: direction = -H g.
    direction_ = gradient_;
    for (int k = 0; k < stored; ++k) {
      const std::size_t i = std::size_t((newest - k + memory) % memory);
      alpha[i] = history_rho_[i] * dot(history_s_[i], direction_);
      direction_ -= alpha[i] * history_t_[i];
    }
    if (!step_.factor->solve(direction_, solution_)) {
      error = "CHOLMOD's solve of the projective system failed";
      return false;
    }
    ++iterations_done_;
    direction_ = solution_;
    project(direction_);
    for (int k = stored - 1; k >= 0; --k) {
      const std::size_t i = std::size_t((newest - k + memory) % memory);
      const Scalar beta = history_rho_[i] * dot(history_t_[i], direction_);
      direction_ += (alpha[i] - beta) * history_s_[i];
    }
    project(direction_);  // the history's steps may hold parts the active set now takes
    direction_ = -direction_;
    Scalar slope = dot(gradient_, direction_);
    if (!(slope < 0)) {  // not a descent direction: start the history again (the next iteration)
      if (stored == 0) break;  // at a stationary point already
      stored = 0;
      continue;
    }
    // Backtracking from the whole step, each shorter step the minimum of the quadratic through
    // the objective, its slope and the last trial (kept within a hundredth and a half of the
    // last step): the first steps after many contacts begin at once can be far too long along
    // the few directions the run's matrix knows only by their masses.
    Scalar step = 1, taken = 0, tried = objective;  // taken: the step trial_ was evaluated at
    for (int shortening = 0; shortening < MAX_LINE_SEARCH_STEPS; ++shortening) {
      for (std::size_t v = 0; v < positions.size(); ++v)
        if (const int a = free_index_[v]; a >= 0) trial_[v] = positions[v] + step * Vec3(direction_.row(a).transpose());
      keep_out(trial_);
      tried = evaluate(trial_, &trial_gradient_);
      taken = step;
      if (tried <= objective + ARMIJO * step * slope) break;
      const Scalar curvature = tried - objective - slope * step;  // of the quadratic, times step^2
      const Scalar minimum = curvature > 0 ? -slope * step * step / (2 * curvature) : 0.5 * step;
      step = std::clamp(minimum, 0.01 * step, 0.5 * step);
    }
    if (!(tried < objective)) break;  // no progress along it: as good as this iteration gets
    // The active set at the new iterate: the vertices the trial reached a surface with, less
    // those its gradient pulls off one.
    const bool changed = settle(trial_, trial_gradient_);
    // s = the step, t = the gradient's change; kept (over the oldest pair once the history is
    // full) only when the curvature along s is positive. The pairs are kept when the active
    // set changes (the direction they make is projected again):
    // restarting there, as vertices come and go along a contact's rim, made the solve at
    // rest little better than local-global (a cloth at rest on a sphere, 2 steps a frame:
    // 133 energy halvings in 240 steps against 66).
    step_s_.resize(free_count_, 3);  // the move made: keep_out may have changed the trial's
    for (std::size_t v = 0; v < positions.size(); ++v)
      if (const int a = free_index_[v]; a >= 0) step_s_.row(a) = (trial_[v] - positions[v]).transpose();
    const Scalar moved = std::sqrt(step_s_.rowwise().squaredNorm().maxCoeff());  // one root, not one a row
    step_t_ = trial_gradient_ - gradient_;
    const Scalar curvature = dot(step_s_, step_t_);
    if (curvature > std::numeric_limits<Scalar>::epsilon() * std::sqrt(dot(step_s_, step_s_) * dot(step_t_, step_t_))) {
      newest = (newest + 1) % memory;
      history_s_[std::size_t(newest)].swap(step_s_);
      history_t_[std::size_t(newest)].swap(step_t_);
      history_rho_[std::size_t(newest)] = 1 / curvature;
      stored = std::min(stored + 1, memory);
    }
    positions.swap(trial_);  // trial_'s free rows are written afresh; its others are the same
    gradient_.swap(trial_gradient_);
    objective = tried;
    // Converged when a whole step moved no vertex by more than the tolerance's share of an
    // edge (a shortened one says nothing about the distance left).
    if (taken == 1 && !changed && moved <= converged_move_) break;
  }
  objective_ = objective;
  return true;
}

Scalar ProjectiveSolver::inverse_mass_norm(const Block& rows) const {
  Scalar sum = 0;
  for (std::size_t v = 0; v < free_index_.size(); ++v)
    if (const int a = free_index_[v]; a >= 0) sum += rows.row(a).squaredNorm() / model_.masses[v];
  return sum;
}

int ProjectiveSolver::analyses() const {
  int total = held_factor_.analyses();
  for (const auto& [h, sys] : systems_) total += sys.factor.analyses();
  return total;
}

}  // namespace drape
