#include "drape/core/linear_solver.h"

#include <cholmod.h>
#include <Eigen/IterativeLinearSolvers>
#include <omp.h>

#include <algorithm>
#include <limits>
#include <type_traits>
#include <vector>
#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace drape {
namespace {


class CholmodSolver final : public LinearSolver {
 public:
  explicit CholmodSolver(int stale_iterations) : stale_iterations_(stale_iterations) {}
  SolveReport solve(const SparseMatrix& A, const VectorX& b, VectorX& x) override {
    SolveReport report;
    matrix_ = &A;
    const bool skip = skip_ > 0;
    if (skip) --skip_;
    if (stale_iterations_ > 0 && fresh_ && factor_.same_pattern(A) && !skip) {
      // The factorisation of an earlier matrix as the preconditioner of a conjugate gradient:
      // refactorised only when that takes more than stale_iterations_. After a failure the
      // next 1, 2, 4, 4, ... solves factorise at once (the matrix is changing fast: a swing,
      // contacts coming and going), so failures cost at most a fraction of the work.
      if (preconditioned(A, b, x, report)) {
        backoff_ = 0;
        return report;
      }
      backoff_ = std::min(std::max(1, 2 * backoff_), MAX_BACKOFF);
      skip_ = backoff_;
    }
    fresh_ = factorise(A, report);
    if (!fresh_) return report;
    return solve_again(b, x);
  }
  SolveReport solve_again(const VectorX& b, VectorX& x) override {
    SolveReport report;
    if (stale_) {
      if (preconditioned(*matrix_, b, x, report)) return report;
      if (!factorise(*matrix_, report)) return report;
    }
    report.iterations = 1;
    if (!factor_.solve(b, x)) {
      report.ok = false;
      report.error = "CHOLMOD's solve failed";
    }
    return report;
  }
  int analyses() const override { return factor_.analyses(); }
  int factorisations() const override { return factor_.factorisations(); }

 private:
  // A factorised afresh (no longer stale); false, with report saying why, when it fails.
  bool factorise(const SparseMatrix& A, SolveReport& report) {
    stale_ = false;
    if (factor_.factorise(A)) return true;
    report.ok = false;
    report.error = "CHOLMOD could not factorise the system matrix (not positive definite)";
    return false;
  }
  // Conjugate gradient on A x = b preconditioned by the kept factorisation (of an earlier
  // matrix with the same pattern) until the preconditioned residual r' P^-1 r, which tracks
  // the error in A's norm, is STALE_TOLERANCE^2 of b' P^-1 b; false when that takes more than
  // stale_iterations_ iterations (x is then to be solved afresh).
  bool preconditioned(const SparseMatrix& A, const VectorX& b, VectorX& x, SolveReport& report) {
    if (!factor_.solve(b, x)) return false;
    const Scalar target = STALE_TOLERANCE * STALE_TOLERANCE * b.dot(x);
    r_ = b - A * x;
    for (int k = 1; k <= stale_iterations_; ++k) {
      if (!factor_.solve(r_, z_)) return false;
      const Scalar rz = r_.dot(z_);
      if (rz <= target) {
        report.iterations = k;
        stale_ = true;
        return true;
      }
      if (k == 1) p_ = z_;
      else p_ = z_ + (rz / rz_) * p_;
      rz_ = rz;
      q_ = A * p_;
      const Scalar alpha = rz / p_.dot(q_);
      if (!(alpha > 0)) return false;
      x += alpha * p_;
      r_ -= alpha * q_;
    }
    return false;
  }
  static constexpr Scalar STALE_TOLERANCE = 1e-10;
  static constexpr int MAX_BACKOFF = 4;
  int backoff_ = 0, skip_ = 0;  // solves to factorise at once after a failure
  CholmodFactor factor_;
  int stale_iterations_ = 0;
  bool fresh_ = false;   // a factorisation exists
  bool stale_ = false;   // the last solve's matrix is not the factorised one
  const SparseMatrix* matrix_ = nullptr;
  VectorX r_, z_, p_, q_;
  Scalar rz_ = 0;
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

void keep_freed_memory() {
#ifdef __GLIBC__
  // Allocations up to 32 MiB (glibc's largest threshold on 64-bit) from the heap, not mmap;
  // and the heap's free top never returned with brk.
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
#endif
}

// CHOLMOD (SuiteSparse 5) runs parts of its supernodal factorisation in OpenMP regions with
// a fixed num_threads(4) clause, which neither omp_set_num_threads nor OMP_NUM_THREADS can
// lower: on a machine with fewer cores its threads spun against each other and the rest of the
// step (the pile's first 12 frames took 18.1 s, 6.2 of them in the kernel; with the regions
// serial 7.6 s, the same results). No active parallel level makes every region run on the
// calling thread; set on each thread that calls CHOLMOD, before each call. Since drape's own
// GOMP_parallel (below) a region runs with no team at all; this stays as the fallback should
// the dynamic linker not take that definition.
namespace {
void serial_openmp() { omp_set_max_active_levels(0); }
}  // namespace

// Run serially, each of CHOLMOD's regions still went through a team of one thread, whose
// barrier at the region's end wakes the (absent) others with a futex system call: about 500
// calls a step on the default scene, 4-6 % of its samples in the kernel and 2 % in libgomp
// (perf). This definition takes the place of libgomp's entry point for a parallel region (the
// one libcholmod calls, GOMP_parallel@GOMP_4.0; the executable's definition comes first in
// the dynamic linker's lookup, as an LD_PRELOAD's would): the region's body runs on the calling
// thread with no team, as an orphaned construct does, where omp_get_num_threads() is 1 and
// omp_get_thread_num() 0, so CHOLMOD's static loops give it every iteration. Measured (20
// frames of the default scene, 8 of the pile, `drape run`, medians of 5 alternating runs by
// farm-bench): 0.872x and 0.885x the time without it, the same results to the bit.
// drape's own parallel work is TBB's; nothing else in the process runs OpenMP regions in its
// Debian build (OpenBLAS is the serial variant, tools/install-deps.sh).
extern "C" void GOMP_parallel(void (*body)(void*), void* data, unsigned /*num_threads*/, unsigned /*flags*/) {
  body(data);
}

namespace {
// A CHOLMOD view of a symmetric n x n matrix in compressed columns (sorted), of which CHOLMOD
// reads the lower triangle, no copy; without values, its pattern.
cholmod_sparse symmetric_view(std::size_t n, const int* outer, const int* inner, double* values) {
  cholmod_sparse v{};
  v.nrow = v.ncol = n;
  v.nzmax = size_t(outer[n]);
  v.p = const_cast<int*>(outer);
  v.i = const_cast<int*>(inner);
  v.x = values;
  v.stype = -1;
  v.itype = CHOLMOD_INT;
  v.xtype = values ? CHOLMOD_REAL : CHOLMOD_PATTERN;
  v.dtype = CHOLMOD_DOUBLE;
  v.sorted = 1;
  v.packed = 1;
  return v;
}

// A CHOLMOD view of A's lower triangle (A stores both; CHOLMOD reads the lower), no copy.
cholmod_sparse lower_view(const SparseMatrix& A, double* values) {
  static_assert(std::is_same_v<SparseMatrix::StorageIndex, int>, "CHOLMOD_INT indices");
  return symmetric_view(size_t(A.rows()), A.outerIndexPtr(), A.innerIndexPtr(), values);
}

cholmod_dense dense_view(const Scalar* values, Eigen::Index rows, Eigen::Index cols) {
  cholmod_dense v{};
  v.nrow = size_t(rows);
  v.ncol = size_t(cols);
  v.nzmax = size_t(rows) * size_t(cols);
  v.d = size_t(rows);
  v.x = const_cast<Scalar*>(values);
  v.xtype = CHOLMOD_REAL;
  v.dtype = CHOLMOD_DOUBLE;
  return v;
}
}  // namespace

// CHOLMOD's own factorise permutes the matrix into the supernodal kernel's form, tril(P A P'),
// by two sparse transposes of the lower triangle every call: 7.8 % of the pile's first 24
// frames (perf), about a sixth of what the factorisations cost. The permuted matrix's
// pattern depends on A's alone, so it is made once per analysis, the same two transposes run
// on A's entry numbers; each factorisation then only gathers A's values into it and runs the
// supernodal kernel (cholmod_super_numeric) on the same matrix, to the bit, as before.
struct CholmodFactor::Impl {
  Impl() { cholmod_start(&c); }
  ~Impl() {
    cholmod_free_sparse(&permuted, &c);
    cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

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
  // Sets CHOLMOD's mode as Eigen's CholmodDecomposition did: automatic (supernodal or
  // simplicial, the factor kept as the kernel made it) or simplicial LL'.
  void set_mode(bool simplicial) {
    c.final_asis = simplicial ? 0 : 1;
    c.supernodal = simplicial ? CHOLMOD_SIMPLICIAL : CHOLMOD_AUTO;
    if (simplicial) c.final_ll = 1;
  }
  // A matrix of 3 x 3 blocks (a vertex's three rows and columns: every column's rows in whole
  // blocks, a block's three columns alike) is ordered on its graph of blocks, a ninth of its
  // entries, each vertex's three rows then taken in turn (order_blocks). On the scalar pattern
  // CHOLMOD's choice (AMD, METIS too where AMD fills much) was nine tenths of an analysis: 34
  // of 38 ms on three cloths stacked at rest (9,801 rows), which analysed their changing
  // pattern in three steps of four. The blocks' orderings cost about as much: 1.64 against
  // 1.66 GFlop a factorisation there, the pile's heaped frames 0.72 against 0.81 (mean over its
  // first 30 frames' analyses), the default scene's the same; 0.86 to 1.16 times on synthetic
  // layers (tests/core/test_linear_solver.cpp).
  void analyse(const SparseMatrix& A) {
    cholmod_free_sparse(&permuted, &c);
    cholmod_free_factor(&L, &c);
    cholmod_sparse view = lower_view(A, const_cast<Scalar*>(A.valuePtr()));
    if (block_graph(A)) {
      cholmod_sparse graph = symmetric_view(block_outer.size() - 1, block_outer.data(), block_inner.data(), nullptr);
      cholmod_factor* blocks = order_blocks(graph);
      if (blocks) {
        const auto* order = static_cast<const int*>(blocks->Perm);
        std::vector<int> rows_order(size_t(A.rows()));
        for (size_t k = 0; k < blocks->n; ++k)
          for (int r = 0; r < 3; ++r) rows_order[3 * k + size_t(r)] = 3 * order[k] + r;
        cholmod_free_factor(&blocks, &c);
        L = analyse_with(view, CHOLMOD_GIVEN, rows_order.data());
        if (L) return;
      }
    }
    L = cholmod_analyze(&view, &c);
  }
  // CHOLMOD's analysis of A with one ordering method (and its permutation, for the given one).
  cholmod_factor* analyse_with(cholmod_sparse& A, int ordering, int* permutation = nullptr) {
    const int methods = c.nmethods, kept = c.method[0].ordering;
    c.nmethods = 1;
    c.method[0].ordering = ordering;
    cholmod_factor* F = cholmod_analyze_p(&A, permutation, nullptr, 0, &c);
    c.nmethods = methods;
    c.method[0].ordering = kept;
    return F;
  }
  // The graph of blocks' analysis whose ordering the matrix takes: AMD's, or METIS's where
  // that fills less and CHOLMOD's own rule would try it (its default analysis tries METIS when
  // AMD's factor takes 500 flops a nonzero and five times the matrix's nonzeros), the blocks'
  // counts scaled to the matrix's entries (a block of the factor is 9 of them, 6 on the
  // diagonal; its flops 27 times). Always tried, METIS cost the pile's first 30 frames more in
  // analyses (2.3 s against 1.4 s) than its orderings saved.
  cholmod_factor* order_blocks(cholmod_sparse& graph) {
    cholmod_factor* amd = analyse_with(graph, CHOLMOD_AMD);
    if (!amd) return nullptr;
    const double n = double(graph.ncol), lnz = 9 * c.lnz - 3 * n, fl = 27 * c.fl, anz = 9 * double(graph.nzmax) - 3 * n;
    if (!(fl >= METIS_FLOPS_PER_NONZERO * lnz && lnz >= METIS_FILL * anz)) return amd;
    const double amd_lnz = c.lnz;
    cholmod_factor* metis = analyse_with(graph, CHOLMOD_METIS);
    if (!metis || !(c.lnz < amd_lnz)) {
      cholmod_free_factor(&metis, &c);
      return amd;
    }
    cholmod_free_factor(&amd, &c);
    return metis;
  }
  // CHOLMOD's thresholds for trying METIS after AMD (cholmod_analyze, nmethods 0).
  static constexpr double METIS_FLOPS_PER_NONZERO = 500, METIS_FILL = 5;
  // Whether A is made of 3 x 3 blocks (above); if so, the lower triangle of its graph of
  // blocks into block_outer and block_inner.
  bool block_graph(const SparseMatrix& A) {
    const auto* p = A.outerIndexPtr();
    const auto* i = A.innerIndexPtr();
    if (A.rows() == 0 || A.rows() % 3 != 0) return false;
    const Eigen::Index n = A.rows() / 3;
    block_outer.assign(1, 0);
    block_inner.clear();
    for (Eigen::Index b = 0; b < n; ++b) {
      const auto first = p[3 * b], length = p[3 * b + 1] - first;
      if (length % 3 != 0 || p[3 * b + 2] - p[3 * b + 1] != length || p[3 * b + 3] - p[3 * b + 2] != length) return false;
      if (!std::equal(i + first, i + first + length, i + first + length) ||
          !std::equal(i + first, i + first + length, i + first + 2 * length))
        return false;
      for (auto k = first; k < first + length; k += 3) {
        const auto r = i[k];
        if (r % 3 != 0 || i[k + 1] != r + 1 || i[k + 2] != r + 2) return false;
        if (r / 3 >= b) block_inner.push_back(r / 3);
      }
      block_outer.push_back(int(block_inner.size()));
    }
    return true;
  }
  std::vector<int> block_outer, block_inner;
  // tril(P A P') with the number of A's entry in place of each value: CHOLMOD's factorise
  // makes it by these two transposes (triu(P A P') from the lower triangle, then its transpose).
  void number_permuted(const SparseMatrix& A) {
    std::vector<double> numbers(size_t(A.nonZeros()));
    for (size_t k = 0; k < numbers.size(); ++k) numbers[k] = double(k);
    cholmod_sparse view = lower_view(A, numbers.data());
    cholmod_sparse* upper = cholmod_ptranspose(&view, 2, static_cast<int*>(L->Perm), nullptr, 0, &c);
    permuted = upper ? cholmod_ptranspose(upper, 2, nullptr, nullptr, 0, &c) : nullptr;
    cholmod_free_sparse(&upper, &c);
    if (!permuted) return;
    const auto* x = static_cast<const double*>(permuted->x);
    const auto* p = static_cast<const int*>(permuted->p);
    source.resize(size_t(p[permuted->ncol]));
    for (size_t k = 0; k < source.size(); ++k) source[k] = SparseMatrix::StorageIndex(x[k]);
  }
  // Factorises A; false when it is not positive definite (or CHOLMOD failed).
  bool numeric(const SparseMatrix& A) {
    const double zero[2] = {0, 0};
    if (!L) return false;
    if (L->is_super && permuted) {
      auto* x = static_cast<double*>(permuted->x);
      const Scalar* a = A.valuePtr();
      for (size_t k = 0; k < source.size(); ++k) x[k] = a[source[k]];
      if (!cholmod_super_numeric(permuted, nullptr, const_cast<double*>(zero), L, &c)) return false;
    } else {
      cholmod_sparse view = lower_view(A, const_cast<Scalar*>(A.valuePtr()));
      if (!cholmod_factorize_p(&view, const_cast<double*>(zero), nullptr, 0, L, &c)) return false;
    }
    return L->minor == L->n;  // on failure, the column where it failed
  }
  bool solve(const Scalar* b, Scalar* x, Eigen::Index rows, Eigen::Index cols) {
    cholmod_dense bv = dense_view(b, rows, cols);
    cholmod_dense* xv = cholmod_solve(CHOLMOD_A, L, &bv, &c);
    if (!xv) return false;
    std::copy_n(static_cast<const double*>(xv->x), rows * cols, x);
    cholmod_free_dense(&xv, &c);
    return true;
  }

  cholmod_common c;
  cholmod_factor* L = nullptr;
  cholmod_sparse* permuted = nullptr;               // tril(P A P') for the supernodal kernel
  std::vector<SparseMatrix::StorageIndex> source;   // permuted's k-th value is A's source[k]-th
  int analyses = 0, factorisations = 0;
  double flops = 0;  // of the last analysis's factorisation
  bool empty = false;  // the last matrix had no rows
  bool factorised = false;
  Eigen::Index rows = 0, nonzeros = 0;
  std::vector<SparseMatrix::StorageIndex> outer, inner;
};

CholmodFactor::CholmodFactor(Use use) : impl_(std::make_unique<Impl>()), use_(use) {
  // Supernodes amalgamated more than CHOLMOD's defaults (columns 4, 16, 48 and zeros 0.8, 0.1,
  // 0.05) allow: the system's 3 x 3 blocks make many small supernodes, each a few OpenMP
  // regions (whose barrier, a team of one thread, cost a futex system call until GOMP_parallel
  // above) and small BLAS calls. Measured before that change, the solve of the default scene's
  // first 12 frames 1,156 -> 935 ms, of the pile's first 6 frames 2,555 -> 2,330 ms (medians of
  // 3 and 4 alternating runs); 8, 32, 96 and 32, 64, 128 did no better. Read by each supernodal
  // analysis.
  cholmod_common& c = impl_->c;
  c.nrelax[0] = 16, c.nrelax[1] = 64, c.nrelax[2] = 128;
  c.zrelax[0] = 0.8, c.zrelax[1] = 0.2, c.zrelax[2] = 0.1;
}
CholmodFactor::~CholmodFactor() = default;
CholmodFactor::CholmodFactor(CholmodFactor&&) noexcept = default;
CholmodFactor& CholmodFactor::operator=(CholmodFactor&&) noexcept = default;

bool CholmodFactor::same_pattern(const SparseMatrix& A) const { return impl_->same_pattern(A); }

bool CholmodFactor::factorise(const SparseMatrix& A) {
  Impl& f = *impl_;
  f.empty = A.rows() == 0;
  if (f.empty) return true;  // nothing free (every vertex pinned): CHOLMOD refuses an empty matrix
  serial_openmp();
  if (!f.same_pattern(A)) {
    // A system factorised every step takes CHOLMOD's own choice: the supernodal factorisation
    // (dense BLAS kernels) when the factor's flops per nonzero reach its supernodal_switch
    // (40), else the simplicial LL'. A row count threshold (simplicial below 15,000 rows) had
    // been measured while CHOLMOD's OpenMP threads spun on this 2-core machine: with them
    // serial, the supernodal factorisation took the default scene's first 20 frames' solve from
    // 8.26 to 2.17 s, the hanging cloth's (625 vertices) from 0.68 to 0.24 s. A factor reused
    // for many solves stays simplicial: its triangular solves with three right-hand sides are
    // the faster ones (docs/solvers.md). CHOLMOD's analysis in its automatic mode takes that
    // rule; a simplicial pick is analysed again as LL' (automatic mode would factorise LDL').
    f.set_mode(use_ == Use::ManySolves);
    f.analyse(A);
    if (use_ == Use::Refactorised && f.L && !f.L->is_super) {
      f.set_mode(true);
      f.analyse(A);
    }
    if (f.L && f.L->is_super) f.number_permuted(A);
    ++f.analyses;
    f.flops = f.L ? f.c.fl : 0;
    // A failed analysis (CHOLMOD out of memory) is not kept: the next matrix is analysed again.
    if (f.L && (!f.L->is_super || f.permuted)) f.remember_pattern(A);
    else f.rows = -1;
  }
  ++f.factorisations;
  f.factorised = f.numeric(A);
  return f.factorised;
}

bool CholmodFactor::solve(const Eigen::Matrix<Scalar, Eigen::Dynamic, 3>& B,
                          Eigen::Matrix<Scalar, Eigen::Dynamic, 3>& X) const {
  if (impl_->empty) {
    X.resize(0, 3);
    return true;
  }
  if (!impl_->factorised) return false;
  serial_openmp();
  X.resize(B.rows(), 3);
  return impl_->solve(B.data(), X.data(), B.rows(), 3) && X.allFinite();
}

bool CholmodFactor::solve(const VectorX& b, VectorX& x) const {
  if (impl_->empty) {
    x.resize(0);
    return true;
  }
  if (!impl_->factorised) return false;
  serial_openmp();
  x.resize(b.size());
  return impl_->solve(b.data(), x.data(), b.size(), 1) && x.allFinite();
}

int CholmodFactor::analyses() const { return impl_->analyses; }
int CholmodFactor::factorisations() const { return impl_->factorisations; }
double CholmodFactor::flops() const { return impl_->flops; }

std::unique_ptr<LinearSolver> make_linear_solver(const SolverSpec& spec) {
  if (spec.kind == SolverKind::ConjugateGradient) return std::make_unique<ConjugateGradientSolver>(spec);
  return std::make_unique<CholmodSolver>(spec.factor_reuse);
}

}  // namespace drape
