// The projective solver's contacts held in its objective (projective.h, ProjectiveContacts):
// their weights, the spheres and planes posed, the gaps kept, the mesh contacts' bounds, and
// their terms of the objective with their gradient, impulses and work.
#include "projective.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "drape/core/obstacle.h"

namespace drape {

void ProjectiveSolver::prepare_contacts(const ProjectiveContacts& c) {
  const Model& m = model_;
  const Scalar h = step_.step->h;
  const std::vector<Vec3>& x0 = *step_.step->start;
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
  active_.clear();
  is_active_.assign(shapes_.size() * std::size_t(free_count_), 0);
  contact_bound_.resize(c.mesh.size());
  contact_stiffness_.resize(c.mesh.size());
  planes_.clear();
  as_plane_.assign(c.mesh.size(), 0);
  // Mesh contacts per free vertex: a vertex with several (near an obstacle's edge or corner)
  // keeps their penalties, since their planes' intersection would hold it out of the region
  // around a convex edge that it may enter.
  std::vector<int> contacts_of(x0.size(), 0);
  for (const SolveContact& contact : c.mesh)
    for (int i = 0; i < contact.count; ++i) ++contacts_of[std::size_t(contact.vertex[i])];
  // Each mesh contact's weight, from its heaviest free vertex's mass, and its bound: its
  // cloth points' normal position at the start plus what the surface moves in the step.
  for (std::size_t k = 0; k < c.mesh.size(); ++k) {
    const SolveContact& contact = c.mesh[k];
    Scalar bound = h * contact.target, stiffness = 0;
    for (int i = 0; i < contact.count; ++i) {
      const std::size_t v = std::size_t(contact.vertex[i]);
      bound += contact.weight[i] * contact.normal.dot(x0[v]);
      if (free_index_[v] >= 0) stiffness = std::max(stiffness, CONTACT_HOLD * m.masses[v]);
    }
    contact_bound_[k] = bound;
    contact_stiffness_[k] = stiffness;
    // One free cloth vertex: a plane constraint on it, as the spheres and planes are held,
    // which it may approach down to the margin (the penalty keeps the start's distance).
    if (contact.count == 1 && contact.weight[0] > 0 && free_index_[std::size_t(contact.vertex[0])] >= 0 &&
        contacts_of[std::size_t(contact.vertex[0])] == 1) {
      const Scalar approach = std::max<Scalar>(0, contact.distance - c.margin);
      planes_.push_back({contact.vertex[0], contact.normal, (bound - approach) / contact.weight[0], k});
      as_plane_[k] = 1;
    }
  }
  plane_active_.assign(planes_.size(), 0);
}

std::pair<Scalar, Vec3> ProjectiveSolver::surface(int constraint, int a, const Vec3& x) const {
  const auto k = std::size_t(constraint);
  if (k < shapes_.size()) {
    const auto [distance, normal] = shapes_[k].distance(x);
    return {distance - kept_gap_[k * std::size_t(free_count_) + std::size_t(a)], normal};
  }
  const VertexPlane& plane = planes_[k - shapes_.size()];
  return {plane.normal.dot(x) - plane.offset, plane.normal};
}

char& ProjectiveSolver::active_flag(int constraint, int a) {
  const auto k = std::size_t(constraint);
  return k < shapes_.size() ? is_active_[k * std::size_t(free_count_) + std::size_t(a)] : plane_active_[k - shapes_.size()];
}

Scalar ProjectiveSolver::contact_terms(const std::vector<Vec3>& x, std::vector<Vec3>* gradient, bool impulses) {
  const ProjectiveContacts* c = step_.step->contacts;
  if (!c || history_ == 0) return 0;
  const Scalar h = step_.step->h;
  const std::vector<Vec3>& x0 = *step_.step->start;
  Scalar total = 0;
  // The mesh contacts: a one-sided quadratic on how far their cloth points fall short of
  // their bound (continuous in its gradient, as L-BFGS needs).
  for (std::size_t k = 0; k < c->mesh.size(); ++k) {
    if (as_plane_[k]) continue;  // held as a constraint (keep_out)
    const SolveContact& contact = c->mesh[k];
    Scalar reached = 0;
    for (int i = 0; i < contact.count; ++i) reached += contact.weight[i] * contact.normal.dot(x[std::size_t(contact.vertex[i])]);
    const Scalar depth = contact_bound_[k] - reached;
    if (!(depth > 0)) continue;
    const Scalar stiffness = contact_stiffness_[k];
    total += 0.5 * stiffness * depth * depth;
    Scalar free_share = 0;  // of the push that reaches free vertices (a mesh contact may have pinned corners)
    bool pinned = false;
    for (int i = 0; i < contact.count; ++i) {
      const std::size_t v = std::size_t(contact.vertex[i]);
      const int a = free_index_[v];
      if (gradient && a >= 0) (*gradient)[std::size_t(a)] -= contact.weight[i] * stiffness * depth * contact.normal;
      if (impulses) contact_impulse_[v] += contact.weight[i] * stiffness * depth / h;
      if (a >= 0) free_share += contact.weight[i];
      else pinned = true;
    }
    if (!pinned) free_share = 1;  // the whole push, as the weights sum to 1 up to rounding
    if (impulses) contact_work_ += free_share * stiffness * depth / h * contact.normal.dot(contact.surface_velocity);
  }
  // Friction: Coulomb's force against the slip u over the step, smoothed below the sticking
  // speed (the lagged friction potential of Li et al., "Incremental potential contact", 2020,
  // section 5): h^2 F f0(|u|) with f0(y) = y beyond eps h and -y^3 / (3 eps^2 h^2) + y^2 /
  // (eps h) + eps h / 3 below it. Its stiffness while sticking, 2 h F / eps, is kept within
  // FRICTION_HOLD times the vertex's mass (a larger eps h: a creep of at most 2 h^2 F over
  // that a step), or L-BFGS, whose first inverse Hessian lacks it, would stall.
  for (const FrictionContact& f : c->friction) {
    const std::size_t v = std::size_t(f.vertex);
    const int a = free_index_[v];
    if (a < 0) continue;
    const Scalar eps_h = std::max(c->slip * h, 2 * h * h * f.force / (FRICTION_HOLD * model_.masses[v]));
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

void ProjectiveSolver::keep_out(std::vector<Vec3>& x) {
  entered_.clear();
  // An active vertex is put back on its surface at its gap (a step along a sphere's tangent
  // leaves it); any other closer than its gap is moved out to it. A second pass over the
  // vertices the first moved when there are several constraints: moving out of one can move a
  // vertex into another (a ball on the ground, a table's edge); a vertex the first pass left
  // where it was is left again.
  const auto hold = [&](int constraint, std::size_t v) {
    const int a = free_index_[v];
    if (a < 0 || fixed_[std::size_t(a)]) return false;
    const bool active = active_flag(constraint, a);
    if (!active && clear_of(constraint, a, x[v])) return false;
    const auto [beyond, normal] = surface(constraint, a, x[v]);
    if (!(beyond < 0) && !active) return false;
    x[v] -= beyond * normal;
    if (!active) entered_.emplace_back(int(v), constraint);
    return true;
  };
  const bool second_pass = shapes_.size() + planes_.size() > 1;
  moved_.clear();
  if (second_pass) moved_mark_.assign(x.size(), 0);
  const auto held = [&](int constraint, std::size_t v) {
    if (hold(constraint, v) && second_pass && !moved_mark_[v]) moved_mark_[v] = 1, moved_.push_back(int(v));
  };
  for (std::size_t k = 0; k < shapes_.size(); ++k)
    for (std::size_t v = 0; v < x.size(); ++v) held(int(k), v);
  for (std::size_t p = 0; p < planes_.size(); ++p) held(int(shapes_.size() + p), std::size_t(planes_[p].vertex));
  if (!second_pass) return;
  std::sort(moved_.begin(), moved_.end());  // the order a pass over every vertex would take
  for (std::size_t k = 0; k < shapes_.size(); ++k)
    for (int v : moved_) hold(int(k), std::size_t(v));
  for (std::size_t p = 0; p < planes_.size(); ++p)
    if (moved_mark_[std::size_t(planes_[p].vertex)]) hold(int(shapes_.size() + p), std::size_t(planes_[p].vertex));
}

bool ProjectiveSolver::clear_of(int constraint, int a, const Vec3& x) const {
  // Only a sphere's distance needs a root; its square is compared with a margin far above
  // the rounding of the distance itself, so that a vertex it calls clear is clear by surface.
  const auto k = std::size_t(constraint);
  if (k >= shapes_.size() || !shapes_[k].sphere) return false;
  const Scalar reach = shapes_[k].radius + kept_gap_[k * std::size_t(free_count_) + std::size_t(a)];
  return reach > 0 && (x - shapes_[k].point).squaredNorm() > reach * reach * (1 + CLEAR_MARGIN);
}

bool ProjectiveSolver::activate() {
  bool changed = false;
  for (const auto& [v, k] : entered_) {
    char& flag = active_flag(k, free_index_[std::size_t(v)]);
    if (flag) continue;
    flag = 1;
    active_.push_back({v, k});
    changed = true;
  }
  if (changed)
    std::sort(active_.begin(), active_.end(),
              [](const ActiveContact& a, const ActiveContact& b) { return std::tie(a.vertex, a.shape) < std::tie(b.vertex, b.shape); });
  return changed;
}

void ProjectiveSolver::refresh_active(const std::vector<Vec3>& x) {
  for (std::size_t e = 0; e < active_.size(); ++e) {
    ActiveContact& c = active_[e];
    c.normal = surface(c.shape, free_index_[std::size_t(c.vertex)], x[std::size_t(c.vertex)]).second;
    // A vertex against two or three surfaces at once (a sphere resting on a plane's corner):
    // its later normals less the earlier ones.
    c.basis = c.normal;
    for (std::size_t f = e; f > 0 && active_[f - 1].vertex == c.vertex; --f) c.basis -= c.basis.dot(active_[f - 1].basis) * active_[f - 1].basis;
    const Scalar length = c.basis.norm();
    c.basis = length > 1e-9 ? Vec3(c.basis / length) : Vec3::Zero();
  }
}

ProjectiveSolver::VertexConstraints ProjectiveSolver::constraints_at(std::size_t first, const Block& gradient) const {
  VertexConstraints c;
  c.first = first;
  c.last = first + 1;
  while (c.last < active_.size() && active_[c.last].vertex == active_[first].vertex) ++c.last;
  c.count = std::min(c.last - first, c.lambda.size());
  // The gradient is sum lambda_i n_i at a constrained stationary point: least squares over the
  // vertex's normals (one normal: lambda = g . n).
  const Vec3 g = gradient.row(free_index_[std::size_t(active_[first].vertex)]).transpose();
  if (c.count == 1) {
    c.lambda[0] = g.dot(active_[first].normal);
    return c;
  }
  Eigen::Matrix<Scalar, 3, Eigen::Dynamic> normals(3, Eigen::Index(c.count));
  for (std::size_t i = 0; i < c.count; ++i) normals.col(Eigen::Index(i)) = active_[first + i].normal;
  const Eigen::Matrix<Scalar, Eigen::Dynamic, 1> solution = normals.completeOrthogonalDecomposition().solve(g);
  for (std::size_t i = 0; i < c.count; ++i) c.lambda[i] = solution(Eigen::Index(i));
  return c;
}

bool ProjectiveSolver::release(const Block& gradient) {
  // The vertices whose descent (-gradient) leads off a surface: the constraint's reaction, its
  // multiplier, would be a pull. Per vertex the most negative of its multipliers is freed.
  std::vector<ActiveContact> kept;
  kept.reserve(active_.size());
  bool changed = false;
  for (std::size_t first = 0; first < active_.size();) {
    const VertexConstraints c = constraints_at(first, gradient);
    const std::size_t weakest = std::size_t(std::min_element(c.lambda.begin(), c.lambda.begin() + long(c.count)) - c.lambda.begin());
    for (std::size_t e = c.first; e < c.last; ++e) {
      if (e - c.first == weakest && c.lambda[weakest] < 0) {
        active_flag(active_[e].shape, free_index_[std::size_t(active_[e].vertex)]) = 0;
        changed = true;
      } else {
        kept.push_back(active_[e]);
      }
    }
    first = c.last;
  }
  active_.swap(kept);
  return changed;
}

bool ProjectiveSolver::settle(const std::vector<Vec3>& x, Block& gradient) {
  bool changed = activate();
  refresh_active(x);  // the entered vertices' normals, for their multipliers
  if (release(gradient)) changed = true, refresh_active(x);  // the bases without the freed
  raw_gradient_ = gradient;
  project(gradient);
  return changed;
}

void ProjectiveSolver::project(Block& rows) const {
  for (int a = 0; a < free_count_; ++a)
    if (fixed_[std::size_t(a)]) rows.row(a).setZero();
  for (const ActiveContact& c : active_) {
    const int a = free_index_[std::size_t(c.vertex)];
    rows.row(a) -= rows.row(a).dot(c.basis.transpose()) * c.basis.transpose();
  }
}

void ProjectiveSolver::active_reactions(const std::vector<Vec3>& x, const Block& gradient) {
  const Scalar h = step_.step->h;
  const ProjectiveContacts& contacts = *step_.step->contacts;
  for (std::size_t first = 0; first < active_.size();) {
    // Each constraint balances its multiplier's share of the gradient (the objective's force is
    // minus its gradient over h^2; an impulse is h times a force).
    const VertexConstraints c = constraints_at(first, gradient);
    const int v = active_[first].vertex;
    for (std::size_t i = 0; i < c.count; ++i) {
      if (!(c.lambda[i] > 0)) continue;
      const Scalar impulse = c.lambda[i] / h;
      const ActiveContact& contact = active_[first + i];
      contact_impulse_[std::size_t(v)] += impulse;
      if (std::size_t(contact.shape) >= shapes_.size()) {  // a mesh contact's plane
        const SolveContact& mesh = contacts.mesh[planes_[std::size_t(contact.shape) - shapes_.size()].contact];
        contact_work_ += impulse * mesh.normal.dot(mesh.surface_velocity);
        continue;
      }
      const PosedShape& shape = shapes_[std::size_t(contact.shape)];
      if (shape.obstacle->spec.motion.moves())
        contact_work_ += impulse * contact.normal.dot(analytic_contact(shape, contacts.t_end, x[std::size_t(v)]).surface_velocity);
    }
    first = c.last;
  }
}

}  // namespace drape
