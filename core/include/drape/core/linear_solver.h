#pragma once
/// \file
/// The sparse solve of the implicit step behind one interface (CHOLMOD, CG).
///
/// The sparse solve of the implicit step, behind one interface: SuiteSparse CHOLMOD (a sparse
/// Cholesky factorisation whose symbolic analysis is reused while the matrix's pattern stays
/// the same, and whose numeric factorisation preconditions a conjugate gradient on later
/// matrices until that stops paying) or Eigen's conjugate gradient with a Jacobi preconditioner.

#include <Eigen/SparseCore>
#include <memory>
#include <string>

#include "drape/core/scene.h"

namespace drape {

/// Keeps memory that the process frees for its next allocations (glibc's mallopt; nothing
/// elsewhere), for programs that factorise every step: CHOLMOD allocates its permuted copy of
/// the matrix and its workspace in each factorisation, and with glibc's defaults that memory
/// went back to the kernel and was faulted in again the next time (the pile's first 22 frames:
/// 377,000 page faults, 26.1 s; kept, 28,000 and 21.2 s, the same results). The resident
/// memory then stays at its peak. Call once, before the first step (the drape program and the
/// benchmarks that time it do).
void keep_freed_memory();

using SparseMatrix = Eigen::SparseMatrix<Scalar>;
using VectorX = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;

struct SolveReport {
  bool ok = true;
  bool converged = true;  ///< cg: reached its tolerance within the iteration cap
  int iterations = 0;     ///< cg iterations; 1 for a direct solve
  Scalar residual = 0;    ///< cg: relative residual reached
  std::string error;      ///< why the solve failed, when !ok
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  /// Solves A x = b for a symmetric positive definite A (both triangles stored). x holds a
  /// starting guess on entry (used by iterative solvers).
  virtual SolveReport solve(const SparseMatrix& A, const VectorX& b, VectorX& x) = 0;
  /// Solves with the matrix of the last solve() again, for another right-hand side (a direct
  /// solver reuses its factorisation). That matrix must still be alive and unchanged: CHOLMOD
  /// may have solved it by a conjugate gradient preconditioned by an older factorisation, and
  /// does so again with it.
  virtual SolveReport solve_again(const VectorX& b, VectorX& x) = 0;
  /// How many times the symbolic analysis ran (direct solvers); 0 for iterative ones.
  virtual int analyses() const { return 0; }
  /// How many numeric factorisations ran (direct solvers); 0 for iterative ones.
  virtual int factorisations() const { return 0; }
};

std::unique_ptr<LinearSolver> make_linear_solver(const SolverSpec& spec);

/// One CHOLMOD factorisation of a symmetric positive definite matrix, kept for many solves
/// (the projective solver's system, which does not change during a run). The symbolic analysis
/// is reused while the matrix keeps its sparsity pattern.
class CholmodFactor {
 public:
  /// What the factorisation is for: factorised every step (large systems use the supernodal
  /// factorisation, which factorises faster), or factorised once and solved many times (the
  /// simplicial one, whose triangular solves with few right-hand sides are faster).
  enum class Use { Refactorised, ManySolves };
  explicit CholmodFactor(Use use = Use::Refactorised);
  ~CholmodFactor();
  CholmodFactor(CholmodFactor&&) noexcept;
  CholmodFactor& operator=(CholmodFactor&&) noexcept;
  /// Factorises A (both triangles stored); false when A is not positive definite.
  bool factorise(const SparseMatrix& A);
  /// Whether A has the sparsity pattern of the last matrix analysed.
  bool same_pattern(const SparseMatrix& A) const;
  /// X = A^-1 B for every column of B; false when the solve failed or gave a non-finite X.
  bool solve(const Eigen::Matrix<Scalar, Eigen::Dynamic, 3>& B, Eigen::Matrix<Scalar, Eigen::Dynamic, 3>& X) const;
  /// X = A^-1 b.
  bool solve(const VectorX& b, VectorX& x) const;
  /// How many times the symbolic analysis ran, and the numeric factorisation.
  int analyses() const;
  int factorisations() const;
  /// The floating-point operations of one numeric factorisation after the last analysis
  /// (CHOLMOD's count; 0 before any): what its ordering costs.
  double flops() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Use use_ = Use::Refactorised;
};

}  // namespace drape
