// The projective solver's contacts held in its objective (projective.h, ProjectiveContacts):
// their weights, the spheres and planes posed, the gaps kept, the mesh contacts' bounds, and
// their terms of the objective with their gradient, impulses and work.
#include "projective.h"

#include <algorithm>
#include <cmath>

#include "drape/core/obstacle.h"

namespace drape {

void ProjectiveSolver::prepare_contacts(const ProjectiveContacts& c) {
  const Model& m = model_;
  const Scalar h = step_.step->h;
  const std::vector<Vec3>& x0 = *step_.step->start;
  // Each held contact's weight, from its vertices' masses; a mesh contact's bound:
  // its cloth points' normal position at the start plus what the surface moves in the step.
  vertex_stiffness_.resize(std::size_t(free_count_));
  for (std::size_t v = 0; v < x0.size(); ++v)
    if (const int a = free_index_[v]; a >= 0) vertex_stiffness_[std::size_t(a)] = CONTACT_HOLD * m.masses[v];
  shapes_.clear();
  // Each sphere and plane posed at the step's end, and at its start for the gaps below.
  if (c.analytic)
    for (const Obstacle& obstacle : m.obstacles)
      if (obstacle.spec.kind != ObstacleSpec::Kind::Mesh) shapes_.push_back(pose_shape(obstacle, c.t_end));
  // The gap each free vertex keeps from each: its distance at the step's start, at most the
  // margin (one that starts within the thickness is pushed out by the response, which moves
  // it without giving it speed).
  kept_gap_.resize(shapes_.size() * std::size_t(free_count_));
  for (std::size_t k = 0; k < shapes_.size(); ++k) {
    const PosedShape at_start = pose_shape(*shapes_[k].obstacle, c.t_end - h);
    for (std::size_t v = 0; v < x0.size(); ++v)
      if (const int a = free_index_[v]; a >= 0)
        kept_gap_[k * std::size_t(free_count_) + std::size_t(a)] = std::min(at_start.distance(x0[v]).first, c.margin);
  }
  contact_bound_.resize(c.mesh.size());
  contact_stiffness_.resize(c.mesh.size());
  for (std::size_t k = 0; k < c.mesh.size(); ++k) {
    const SolveContact& contact = c.mesh[k];
    Scalar bound = h * contact.target, stiffness = 0;
    for (int i = 0; i < contact.count; ++i) {
      const std::size_t v = std::size_t(contact.vertex[i]);
      bound += contact.weight[i] * contact.normal.dot(x0[v]);
      if (free_index_[v] >= 0) stiffness = std::max(stiffness, vertex_stiffness_[std::size_t(free_index_[v])]);
    }
    contact_bound_[k] = bound;
    contact_stiffness_[k] = stiffness;
  }
}

Scalar ProjectiveSolver::contact_terms(const std::vector<Vec3>& x, std::vector<Vec3>* gradient, bool impulses) {
  const ProjectiveContacts* c = step_.step->contacts;
  if (!c || history_ == 0) return 0;
  const Scalar h = step_.step->h;
  const std::vector<Vec3>& x0 = *step_.step->start;
  Scalar total = 0;
  // The spheres and planes (posed at the step's end): a one-sided quadratic on each free
  // vertex's depth within the thickness (continuous in its gradient, as L-BFGS needs).
  for (std::size_t k = 0; k < shapes_.size(); ++k) {
    const PosedShape& shape = shapes_[k];
    const Scalar* kept_gap = kept_gap_.data() + k * std::size_t(free_count_);
    for (std::size_t v = 0; v < x.size(); ++v) {
      const int a = free_index_[v];
      if (a < 0) continue;
      const auto [distance, normal] = shape.distance(x[v]);
      const Scalar depth = kept_gap[a] - distance;
      if (!(depth > 0)) continue;
      const Scalar stiffness = vertex_stiffness_[std::size_t(a)];
      total += 0.5 * stiffness * depth * depth;
      if (gradient) (*gradient)[std::size_t(a)] -= stiffness * depth * normal;
      if (impulses) {
        const Scalar impulse = stiffness * depth / h;  // the term's force is its gradient over h^2
        contact_impulse_[v] += impulse;
        if (shape.obstacle->spec.motion.moves())
          contact_work_ += impulse * normal.dot(analytic_contact(shape, c->t_end, x[v]).surface_velocity);
      }
    }
  }
  // The mesh contacts: the same on how far their cloth points fall short of their bound.
  for (std::size_t k = 0; k < c->mesh.size(); ++k) {
    const SolveContact& contact = c->mesh[k];
    Scalar reached = 0;
    for (int i = 0; i < contact.count; ++i) reached += contact.weight[i] * contact.normal.dot(x[std::size_t(contact.vertex[i])]);
    const Scalar depth = contact_bound_[k] - reached;
    if (!(depth > 0)) continue;
    const Scalar stiffness = contact_stiffness_[k];
    total += 0.5 * stiffness * depth * depth;
    for (int i = 0; i < contact.count; ++i) {
      const std::size_t v = std::size_t(contact.vertex[i]);
      const int a = free_index_[v];
      if (gradient && a >= 0) (*gradient)[std::size_t(a)] -= contact.weight[i] * stiffness * depth * contact.normal;
      if (impulses) contact_impulse_[v] += contact.weight[i] * stiffness * depth / h;
    }
    if (impulses) contact_work_ += stiffness * depth / h * contact.normal.dot(contact.surface_velocity);
  }
  // Friction: Coulomb's force against the slip u over the step, smoothed below the sticking
  // speed (the lagged friction potential of Li et al., "Incremental potential contact", 2020,
  // section 5): h^2 F f0(|u|) with f0(y) = y beyond eps h and -y^3 / (3 eps^2 h^2) + y^2 /
  // (eps h) + eps h / 3 below it. Its stiffness while sticking, 2 h F / eps, is kept within
  // the vertex's contact weight (a larger eps h: a creep of at most 2 h^2 F over that weight
  // a step), or L-BFGS, whose first inverse Hessian lacks it, would stall.
  for (const FrictionContact& f : c->friction) {
    const std::size_t v = std::size_t(f.vertex);
    const int a = free_index_[v];
    if (a < 0) continue;
    const Scalar eps_h = std::max(c->slip * h, 2 * h * h * f.force / vertex_stiffness_[std::size_t(a)]);
    const Vec3 moved = x[v] - x0[v] - h * f.surface_velocity;
    const Vec3 u = moved - moved.dot(f.normal) * f.normal;
    const Scalar y = u.norm();
    const Scalar f0 = y >= eps_h ? y : -y * y * y / (3 * eps_h * eps_h) + y * y / eps_h + eps_h / 3;
    const Scalar f1_over_y = y >= eps_h ? 1 / y : -y / (eps_h * eps_h) + 2 / eps_h;  // f0'(y) / y
    total += h * h * f.force * f0;
    if (gradient) (*gradient)[std::size_t(a)] += (h * h * f.force * f1_over_y) * u;
    if (impulses) contact_work_ -= h * f.force * f1_over_y * u.dot(f.surface_velocity);
  }
  if (impulses) contact_work_ = std::max<Scalar>(0, contact_work_);
  return total;
}

}  // namespace drape
