#pragma once
/// \file
/// The projective solver for mass-spring cloth (Liu, Bargteil, O'Brien and Kavan, "Fast
/// simulation of mass-spring systems", SIGGRAPH Asia 2013, section 4; Bouaziz, Martin, Liu,
/// Kavan and Pauly, "Projective dynamics", SIGGRAPH 2014). Backward Euler over a step h is the
/// minimum over the end positions x of
///     1/2 |x - y|^2_M  +  h^2 sum_s k_s/2 |x_i - x_j - p_s|^2  +  h sum_s c_s/2 |x_i - x_j - q_s|^2
///     +  h sum_v a_v m_v/2 |x_v - x0_v - h w|^2,
/// y = x0 + h v0 + h^2 M^-1 f (gravity, wind drag), where p_s is the spring's rest length along
/// its current direction (its elastic energy, exactly), q_s is x_i - x_j with its change along
/// the spring's direction at the step's start removed (the spring's damping c_s along that
/// direction as a dissipation potential, as the linearised solver evaluates it), and the last term the air's damping a_v towards the wind's velocity
/// w. The solver alternates a local step (every spring's p_s and q_s from the current x) and a
/// global step, the linear system
///     (M (1 + h a) + sum_s (h^2 k_s + h c_s) A_s^T A_s) x = M y + h a M (x0 + h w) + sum_s A_s^T (h^2 k_s p_s + h c_s q_s)
/// whose n x n matrix (one for x, y and z alike) does not depend on the state: it is factorised
/// once per step size for the whole run and each iteration is one pass over the springs and
/// one back-substitution with three right-hand sides. Pinned and scripted vertices are
/// eliminated (their end positions are given). Converged, it is backward Euler with the
/// springs' exact energy and damping; a fixed number of iterations leaves the stiffest springs
/// softer than that (their stretch is what sweep measures against the reference); Chebyshev
/// acceleration (solver.chebyshev) brings it closer in the same iterations.

#include <array>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <tbb/task_arena.h>

#include "drape/core/collision.h"
#include "drape/core/linear_solver.h"
#include "drape/core/obstacle.h"
#include "drape/core/model.h"

namespace drape {

/// Lagged Coulomb friction on one contact vertex: the normal force its contacts made the step
/// before, times the friction coefficient, against its slip across the contact's normal
/// relative to the obstacle's surface.
struct FrictionContact {
  int vertex = 0;
  Vec3 normal = Vec3::UnitZ();
  Vec3 surface_velocity = Vec3::Zero();
  Scalar force = 0;  ///< N: friction coefficient times the normal force
};

/// The contacts held in the solve: the scene's spheres and planes as constraints (each free
/// vertex kept at the step's end as far from each as it was at the step's start, at most the
/// margin: outside the thickness, where the response has nothing to do); the mesh obstacles'
/// contacts of the step's start, whose cloth points may not approach their obstacle faster
/// than its surface (a constraint, its face's plane, for a vertex with one such contact; a
/// penalty for the others); friction.
struct ProjectiveContacts {
  bool analytic = false;  ///< hold the spheres and planes
  Scalar t_end = 0;       ///< s: where they are
  Scalar margin = 0;      ///< m, at least the thickness
  std::vector<SolveContact> mesh;  ///< mesh contacts only (SolveContact::analytic false)
  std::vector<FrictionContact> friction;
  Scalar slip = 1e-4;  ///< m/s: slower than this a vertex sticks (friction's smoothing)
};

/// What one step starts from.
struct ProjectiveStep {
  Scalar h = 0;                           ///< s
  const std::vector<Vec3>* start = nullptr;       ///< x0, every vertex
  const std::vector<Vec3>* velocities = nullptr;  ///< v0, every vertex
  const std::vector<Vec3>* forces = nullptr;      ///< explicit forces f (gravity, wind drag), every vertex
  const ProjectiveContacts* contacts = nullptr;   ///< held in the solve (L-BFGS only), or none
};

/// Free vertices held (a penalty) to target end positions: the collision response spread
/// through the step.
struct HeldVertices {
  std::vector<int> vertices;  ///< global indices, free vertices only
  std::vector<Vec3> targets;  ///< end positions
};

class ProjectiveSolver {
 public:
  /// free_index: vertex -> index among the free vertices, or -1 for a pinned one; threads:
  /// for L-BFGS's passes over the springs and vertices (results do not depend on it).
  ProjectiveSolver(const Model& model, std::vector<int> free_index, int free_count, int threads = 1);
  ~ProjectiveSolver();
  /// Runs the scene's iterations from positions (every vertex: the first guess for the free
  /// ones, the end positions of the pinned ones) and leaves the end of the step there. With
  /// held, the held vertices keep to their targets: exactly with L-BFGS (left out of its
  /// steps); with local-global by a penalty of hold times their diagonal entry (to about 1 /
  /// hold of their change), the held system factorised once for a given step size and held set.
  /// False, with error set, when a factorisation or solve fails.
  bool solve(const ProjectiveStep& step, std::vector<Vec3>& positions, std::string& error,
             const HeldVertices* held = nullptr, Scalar hold = 0);
  /// Symbolic analyses run: one per distinct system (step sizes, held solves share one).
  int analyses() const;
  /// Back-substitutions the last solve made (its iterations), and the step's objective at
  /// its result.
  int iterations_done() const { return iterations_done_; }
  Scalar objective() const { return objective_; }
  /// After a solve with contacts: each vertex's normal impulse from its held contacts (N s,
  /// every vertex), and their work on the cloth at moving obstacles' velocities (J, normal
  /// impulses and friction).
  const std::vector<Scalar>& contact_impulses() const { return contact_impulse_; }
  Scalar contact_work() const { return contact_work_; }

 private:
  using Block = Eigen::Matrix<Scalar, Eigen::Dynamic, 3>;
  struct System {
    SparseMatrix matrix;
    CholmodFactor factor{CholmodFactor::Use::ManySolves};
    // The springs' weights in the objective for this step size, h^2 k and h c, padded with
    // zeros (spring_pulls.h).
    std::vector<double> elastic, viscous;
  };
  // The system of step size h, built and factorised on first use.
  System* system(Scalar h, std::string& error);
  // The step's objective at x (every vertex), the local step's right-hand side into sums_,
  // and when asked its gradient over the free vertices.
  Scalar evaluate(const std::vector<Vec3>& x, Block* gradient);
  // The step's contacts made ready: weights, the shapes posed, the gaps kept, the mesh
  // contacts' bounds (projective_contacts.cpp).
  void prepare_contacts(const ProjectiveContacts& contacts);
  // The mesh contacts' and friction's part of the objective at x, their gradient added to
  // gradient when given; with impulses, each vertex's normal impulse into contact_impulse_ and
  // the work into contact_work_.
  Scalar contact_terms(const std::vector<Vec3>& x, std::vector<Vec3>* gradient, bool impulses);
  // The spheres and planes (and the single mesh contacts' planes) as constraints on L-BFGS's
  // iterates (an active set): every free vertex kept at its gap from each, an active vertex's
  // steps along the surface only. keep_out puts the active vertices of x back at their gap and
  // moves the others that are closer than it out to it, listing those in entered_; activate
  // makes those active; refresh_active takes the active vertices' normals at x; release frees
  // the active vertices whose gradient (raw, not yet projected) pulls them off a surface (a
  // negative multiplier); project removes from rows (per free vertex) what the held and active
  // vertices may not do. activate and release say whether the set changed. settle does what
  // an iterate x needs after keep_out and its evaluation: activate, release, gradient kept raw
  // in raw_gradient_ and projected; whether the set changed.
  void keep_out(std::vector<Vec3>& x);
  // Whether x is surely farther than its gap from a sphere constraint, without a root (false:
  // not known, ask surface).
  bool clear_of(int constraint, int a, const Vec3& x) const;
  static constexpr Scalar CLEAR_MARGIN = 1e-9;  // relative, on the squared distance
  bool activate();
  void refresh_active(const std::vector<Vec3>& x);
  bool release(const Block& gradient);
  bool settle(const std::vector<Vec3>& x, Block& gradient);
  // One vertex's active constraints, active_[first, last), and their multipliers for its row
  // of gradient (least squares over its normals; at most 8 of them weighed).
  struct VertexConstraints {
    std::size_t first = 0, last = 0, count = 0;
    std::array<Scalar, 8> lambda{};
  };
  VertexConstraints constraints_at(std::size_t first, const Block& gradient) const;
  void project(Block& rows) const;
  // After the solve: the active vertices' normal impulses (their reaction, from the raw
  // gradient at the result) and their work at moving obstacles' velocities.
  void active_reactions(const std::vector<Vec3>& x, const Block& gradient);
  // The step's iterations from positions (first guess in, result out): plain local-global
  // with Chebyshev acceleration, or L-BFGS.
  bool local_global(std::vector<Vec3>& positions, std::string& error);
  bool quasi_newton(std::vector<Vec3>& positions, std::string& error);
  // A mesh contact's penalty weight in the objective, per kilogram of its vertex (the heaviest
  // of its vertices): stiff against the vertex's inertia (a resting vertex yields g h^2 / 10 a
  // step, within the margin), soft against its springs. The run's matrix knows a cloth's
  // collective motions (a whole sheet pressed onto a plane) only by their masses; a weight of
  // the springs' order there made L-BFGS's first steps thousands of times too long and its
  // normal forces, hence friction, wrong.
  static constexpr Scalar CONTACT_HOLD = 10;
  // Friction's stiffness while sticking, per kilogram of its vertex, at most: a cloth held
  // on a 20 degree incline by friction 0.5 creeps 0.52 mm in a second at 30 (1.5 mm at 10,
  // the mesh contacts' weight, which was enough while the response's friction stopped what
  // the solve's penalty let sink), within 0.5 mm from 100 on, with the same iterations.
  static constexpr Scalar FRICTION_HOLD = 100;
  static constexpr Scalar ARMIJO = 1e-4;            // sufficient decrease, a fraction of the slope
  static constexpr int MAX_LINE_SEARCH_STEPS = 10;
  // What the step being solved uses (set by solve for its iterations).
  struct Current {
    const System* system = nullptr;
    const CholmodFactor* factor = nullptr;  // the system's, or the held system's
    const ProjectiveStep* step = nullptr;
    const HeldVertices* held = nullptr;
  } step_;
  const Model& model_;
  std::vector<int> free_index_;
  int free_count_ = 0;
  int iterations_ = 0;
  int history_ = 0;                    // L-BFGS memory, 0: local-global
  Scalar rho_ = 0;                     // Chebyshev's spectral radius estimate, 0: no acceleration
  Scalar converged_move_ = 0;          // m: L-BFGS stops after a whole step that moved no vertex farther
  Scalar least_mass_ = std::numeric_limits<Scalar>::infinity();  // kg, of the free vertices
  // The share of an edge below which no vertex's move matters, whatever the tolerance: L-BFGS
  // stops there (16 nm on a 128 x 128 cloth of 2 m; a free fall's first guess is exact to
  // about 4 nm there, by the bound below).
  static constexpr Scalar ROUNDING_MOVE = 1e-6;
  // g^T M^-1 g over the free vertices' rows.
  Scalar inverse_mass_norm(const Block& rows) const;
  int iterations_done_ = 0;
  Scalar objective_ = 0;
  std::vector<Vec3> previous_, current_;  // the last two iterates
  std::vector<Vec3> best_;                // the iterate with the least objective so far
  std::map<Scalar, System> systems_;  // by step size: the scene's and its halvings
  CholmodFactor held_factor_;  // the step's system with the held vertices' penalty (factorised every step with contacts)
  SparseMatrix held_matrix_;
  struct HeldKey {
    Scalar h = 0, hold = 0;
    std::vector<int> vertices;
    bool operator==(const HeldKey&) const = default;
  } held_key_;                         // what held_factor_ factorised
  std::vector<Scalar> held_penalty_;   // per held vertex
  std::vector<int> diagonal_offset_;   // free vertex -> offset of its diagonal entry in a system's values
  std::vector<Vec3> base_, sums_;  // per free vertex: the constant right-hand side, and each pass's
  std::vector<Vec3> predicted_;    // per free vertex: the inertial prediction y
  Block rhs_, solution_;
  Block gradient_, trial_gradient_, direction_;  // L-BFGS, over the free vertices (gradients projected)
  Block raw_gradient_;                           // the last iterate's gradient before projecting
  std::vector<Vec3> gradient_rows_;
  // Each spring's ends (global and free indices); its rest length, and x_i - x_j at the step's
  // start and its direction there (any, for a spring of zero length), as arrays (spring_pulls.h;
  // padded with a spring along x of unit length at rest). L-BFGS's evaluation takes a chunk of
  // springs at a time through spring_pulls (z gathered, pulls and energies out; small enough
  // to stay in the first-level cache); on several threads each spring's pull; each vertex's
  // energy, and each free vertex's springs (2 k for spring k's end i, 2 k + 1 for j).
  struct SpringEnds {
    int i = 0, j = 0, a = -1, b = -1;
  };
  std::vector<SpringEnds> spring_ends_;
  struct SpringArrays {
    std::vector<double> rest, sx, sy, sz, d0x, d0y, d0z;
  } spring_arrays_;
  static constexpr std::size_t SPRING_CHUNK = 256;  // divides PARALLEL_GRAIN, a multiple of SPRING_LANES
  struct SpringChunk {
    std::array<double, SPRING_CHUNK> zx, zy, zz, px, py, pz, energy;
  };
  std::unique_ptr<SpringChunk> spring_chunk_;
  std::vector<Vec3> pulls_;
  std::vector<Scalar> vertex_energy_, block_sums_;
  std::vector<int> incidence_start_, incidence_;
  std::unique_ptr<tbb::task_arena> arena_;
  static constexpr std::size_t PARALLEL_GRAIN = 2048;  // springs or vertices a task, and a sum's block
  // values summed by blocks of PARALLEL_GRAIN, the blocks in order.
  Scalar ordered_sum(const Scalar* values, std::size_t count);
  // The model's springs rounded up to whole vectors of spring_pulls.
  std::size_t padded_springs() const;
  std::vector<char> fixed_;  // per free vertex: held at its target (L-BFGS leaves it out)
  std::vector<Block> history_s_, history_t_;              // its steps and gradient changes (a ring)
  Block step_s_, step_t_;                                 // the last step's pair, before it is kept
  std::vector<Scalar> history_rho_;
  std::vector<Vec3> trial_;                               // every vertex: the line search's point
  std::vector<Scalar> contact_bound_, contact_stiffness_;  // per mesh contact: n . sum w x at least this; its weight
  std::vector<Scalar> contact_impulse_;                    // per vertex, N s
  std::vector<PosedShape> shapes_;  // empty unless the step holds analytic contacts
  std::vector<Scalar> kept_gap_;    // per shape and free vertex (shape-major): the gap the solve keeps
  // The mesh contacts of a single free cloth vertex (a cloth vertex against an obstacle's
  // face), held as constraints too: normal . x >= offset for that vertex.
  struct VertexPlane {
    int vertex = 0;
    Vec3 normal = Vec3::UnitZ();
    Scalar offset = 0;
    std::size_t contact = 0;  // in ProjectiveContacts::mesh
  };
  std::vector<VertexPlane> planes_;
  std::vector<char> plane_active_, as_plane_;  // per plane; per mesh contact: held as a plane
  // A constraint (a shape, or shapes_.size() + a plane) at x: its distance beyond the gap it
  // keeps, and its normal; and its active flag for free vertex a.
  std::pair<Scalar, Vec3> surface(int constraint, int a, const Vec3& x) const;
  char& active_flag(int constraint, int a);
  struct ActiveContact {
    int vertex = 0;  // global index (a free vertex)
    int shape = 0;   // in shapes_, or shapes_.size() + a plane
    Vec3 normal = Vec3::UnitZ();  // the surface's at the vertex
    Vec3 basis = Vec3::UnitZ();   // normal less the vertex's earlier active normals (Gram-Schmidt), unit or zero
  };
  std::vector<ActiveContact> active_;  // by vertex
  std::vector<char> is_active_;        // per shape and free vertex (shape-major)
  std::vector<std::pair<int, int>> entered_;  // (vertex, shape) moved out by the last keep_out
  std::vector<int> moved_;                    // keep_out's first pass: the vertices it moved
  std::vector<char> moved_mark_;              // per vertex: in moved_
  Scalar contact_work_ = 0;
};

}  // namespace drape
