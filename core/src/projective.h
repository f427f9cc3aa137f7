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

#include <map>
#include <string>
#include <vector>

#include "drape/core/linear_solver.h"
#include "drape/core/model.h"

namespace drape {

/// What one step starts from.
struct ProjectiveStep {
  Scalar h = 0;                           ///< s
  const std::vector<Vec3>* start = nullptr;       ///< x0, every vertex
  const std::vector<Vec3>* velocities = nullptr;  ///< v0, every vertex
  const std::vector<Vec3>* forces = nullptr;      ///< explicit forces f (gravity, wind drag), every vertex
};

/// Free vertices held (a penalty) to target end positions: the collision response spread
/// through the step.
struct HeldVertices {
  std::vector<int> vertices;  ///< global indices, free vertices only
  std::vector<Vec3> targets;  ///< end positions
};

class ProjectiveSolver {
 public:
  /// free_index: vertex -> index among the free vertices, or -1 for a pinned one.
  ProjectiveSolver(const Model& model, std::vector<int> free_index, int free_count);
  /// Runs the scene's iterations from positions (every vertex: the first guess for the free
  /// ones, the end positions of the pinned ones) and leaves the end of the step there. With
  /// held, the held vertices keep to their targets (a penalty of hold times their diagonal
  /// entry: to about 1 / hold of their change); the held system is factorised once for a given
  /// step size and held set.
  /// False, with error set, when a factorisation or solve fails.
  bool solve(const ProjectiveStep& step, std::vector<Vec3>& positions, std::string& error,
             const HeldVertices* held = nullptr, Scalar hold = 0);
  /// Symbolic analyses run: one per distinct system (step sizes, held solves share one).
  int analyses() const;

 private:
  using Block = Eigen::Matrix<Scalar, Eigen::Dynamic, 3>;
  // A spring's constants for one step size: its weights in the objective.
  struct SpringTerm {
    int i = 0, j = 0;        // vertices
    int a = -1, b = -1;      // their free indices, or -1
    Scalar rest = 0;         // rest length
    Scalar elastic = 0;      // h^2 k
    Scalar viscous = 0;      // h c
  };
  struct System {
    SparseMatrix matrix;
    CholmodFactor factor{CholmodFactor::Use::ManySolves};
    std::vector<SpringTerm> springs;
  };
  // The system of step size h, built and factorised on first use.
  System* system(Scalar h, std::string& error);
  const Model& model_;
  std::vector<int> free_index_;
  int free_count_ = 0;
  int iterations_ = 0;
  Scalar rho_ = 0;                     // Chebyshev's spectral radius estimate, 0: no acceleration
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
  std::vector<Vec3> spring_start_;      // per spring: x_i - x_j at the step's start
  std::vector<Vec3> spring_direction_;  // and its direction (any, for a spring of zero length)
  Block rhs_, solution_;
};

}  // namespace drape
