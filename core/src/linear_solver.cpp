#include "drape/core/linear_solver.h"

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>
#include <omp.h>

namespace drape {
namespace {

// Systems with fewer rows use CHOLMOD's simplicial factorisation, larger ones the supernodal
// one (dense BLAS kernels). Measured with OpenBLAS (serial): a 625-vertex cloth (1,869 rows)
// 11 vs 15 ms a solve, 1,681 vertices 44 vs 45 ms, 10,201 vertices 1,110 vs 510 ms.
constexpr Eigen::Index SUPERNODAL_MIN_ROWS = 15000;

class CholmodSolver final : public LinearSolver {
 public:
  CholmodSolver() {
    // CHOLMOD parallelises parts of its work with OpenMP; one thread keeps runs bit-for-bit
    // reproducible and leaves the cores to the collision pipeline.
    omp_set_num_threads(1);
  }
  SolveReport solve(const SparseMatrix& A, const VectorX& b, VectorX& x) override {
    SolveReport report;
    if (!same_pattern(A)) {
      llt_.setMode(A.rows() < SUPERNODAL_MIN_ROWS ? Eigen::CholmodSimplicialLLt : Eigen::CholmodSupernodalLLt);
      llt_.analyzePattern(A);
      ++analyses_;
      remember_pattern(A);
    }
    llt_.factorize(A);
    if (llt_.info() != Eigen::Success) {
      report.ok = false;
      report.error = "CHOLMOD could not factorise the system matrix (not positive definite)";
      return report;
    }
    return solve_again(b, x);
  }
  SolveReport solve_again(const VectorX& b, VectorX& x) override {
    SolveReport report;
    x = llt_.solve(b);
    report.iterations = 1;
    if (llt_.info() != Eigen::Success || !x.allFinite()) {
      report.ok = false;
      report.error = "CHOLMOD's solve failed";
    }
    return report;
  }
  int analyses() const override { return analyses_; }

 private:
  bool same_pattern(const SparseMatrix& A) const {
    return analyses_ > 0 && A.rows() == rows_ && A.nonZeros() == nonzeros_ &&
           std::equal(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1, outer_.begin()) &&
           std::equal(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros(), inner_.begin());
  }
  void remember_pattern(const SparseMatrix& A) {
    rows_ = A.rows();
    nonzeros_ = A.nonZeros();
    outer_.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
    inner_.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  }
  Eigen::CholmodDecomposition<SparseMatrix, Eigen::Lower> llt_;
  int analyses_ = 0;
  Eigen::Index rows_ = 0, nonzeros_ = 0;
  std::vector<SparseMatrix::StorageIndex> outer_, inner_;
};

class ConjugateGradientSolver final : public LinearSolver {
 public:
  explicit ConjugateGradientSolver(const SolverSpec& spec) {
    cg_.setTolerance(spec.tolerance);
    cg_.setMaxIterations(spec.max_iterations);
  }
  SolveReport solve(const SparseMatrix& A, const VectorX& b, VectorX& x) override {
    cg_.compute(A);
    return solve_again(b, x);
  }
  SolveReport solve_again(const VectorX& b, VectorX& x) override {
    SolveReport report;
    x = cg_.solveWithGuess(b, x);
    report.iterations = int(cg_.iterations());
    report.residual = cg_.error();
    if (cg_.info() == Eigen::NumericalIssue || !x.allFinite()) {
      report.ok = false;
      report.error = "the conjugate gradient broke down (the system matrix is not positive definite)";
    } else if (cg_.info() == Eigen::NoConvergence) {
      report.converged = false;
    }
    return report;
  }

 private:
  Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<Scalar>> cg_;
};

}  // namespace

std::unique_ptr<LinearSolver> make_linear_solver(const SolverSpec& spec) {
  if (spec.kind == SolverKind::ConjugateGradient) return std::make_unique<ConjugateGradientSolver>(spec);
  return std::make_unique<CholmodSolver>();
}

}  // namespace drape
