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
  SolveReport solve(const SparseMatrix& A, const VectorX& b, VectorX& x) override {
    SolveReport report;
    if (!factor_.factorise(A)) {
      report.ok = false;
      report.error = "CHOLMOD could not factorise the system matrix (not positive definite)";
      return report;
    }
    return solve_again(b, x);
  }
  SolveReport solve_again(const VectorX& b, VectorX& x) override {
    SolveReport report;
    report.iterations = 1;
    if (!factor_.solve(b, x)) {
      report.ok = false;
      report.error = "CHOLMOD's solve failed";
    }
    return report;
  }
  int analyses() const override { return factor_.analyses(); }

 private:
  CholmodFactor factor_;
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

struct CholmodFactor::Impl {
  Impl() {
    // CHOLMOD parallelises parts of its work with OpenMP; one thread keeps runs bit-for-bit
    // reproducible and leaves the cores to the collision pipeline.
    omp_set_num_threads(1);
  }
  bool same_pattern(const SparseMatrix& A) const {
    return analyses > 0 && A.rows() == rows && A.nonZeros() == nonzeros &&
           std::equal(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1, outer.begin()) &&
           std::equal(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros(), inner.begin());
  }
  void remember_pattern(const SparseMatrix& A) {
    rows = A.rows();
    nonzeros = A.nonZeros();
    outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
    inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  }
  Eigen::CholmodDecomposition<SparseMatrix, Eigen::Lower> llt;
  int analyses = 0;
  bool empty = false;  // the last matrix had no rows
  Eigen::Index rows = 0, nonzeros = 0;
  std::vector<SparseMatrix::StorageIndex> outer, inner;
};

CholmodFactor::CholmodFactor(Use use) : impl_(std::make_unique<Impl>()), use_(use) {}
CholmodFactor::~CholmodFactor() = default;
CholmodFactor::CholmodFactor(CholmodFactor&&) noexcept = default;
CholmodFactor& CholmodFactor::operator=(CholmodFactor&&) noexcept = default;

bool CholmodFactor::factorise(const SparseMatrix& A) {
  Impl& f = *impl_;
  f.empty = A.rows() == 0;
  if (f.empty) return true;  // nothing free (every vertex pinned): CHOLMOD refuses an empty matrix
  if (!f.same_pattern(A)) {
    const bool supernodal = use_ == Use::Refactorised && A.rows() >= SUPERNODAL_MIN_ROWS;
    f.llt.setMode(supernodal ? Eigen::CholmodSupernodalLLt : Eigen::CholmodSimplicialLLt);
    f.llt.analyzePattern(A);
    ++f.analyses;
    f.remember_pattern(A);
  }
  f.llt.factorize(A);
  return f.llt.info() == Eigen::Success;
}

bool CholmodFactor::solve(const Eigen::Matrix<Scalar, Eigen::Dynamic, 3>& B,
                          Eigen::Matrix<Scalar, Eigen::Dynamic, 3>& X) const {
  if (impl_->empty) {
    X.resize(0, 3);
    return true;
  }
  X = impl_->llt.solve(B);
  return impl_->llt.info() == Eigen::Success && X.allFinite();
}

bool CholmodFactor::solve(const VectorX& b, VectorX& x) const {
  if (impl_->empty) {
    x.resize(0);
    return true;
  }
  x = impl_->llt.solve(b);
  return impl_->llt.info() == Eigen::Success && x.allFinite();
}

int CholmodFactor::analyses() const { return impl_->analyses; }

std::unique_ptr<LinearSolver> make_linear_solver(const SolverSpec& spec) {
  if (spec.kind == SolverKind::ConjugateGradient) return std::make_unique<ConjugateGradientSolver>(spec);
  return std::make_unique<CholmodSolver>();
}

}  // namespace drape
