#include "integrator/linear_solver.hpp"

#include <algorithm>

#include <Eigen/Dense>
#include <klu.h>

#include "integrator/block_tridiagonal.hpp"

namespace mfbd {

bool SparseAssembly::assign(int size, const std::vector<Eigen::Triplet<double>>& triplets) {
  if (matrix_.rows() == size && entries_.size() == triplets.size()) {
    // Add the values into their slots while checking the positions; a
    // mismatch (a different pattern) falls through to a new assembly.
    double* values = matrix_.valuePtr();
    std::fill(values, values + matrix_.nonZeros(), 0.0);
    std::size_t k = 0;
    for (; k < triplets.size(); ++k) {
      const Entry& e = entries_[k];
      if (e.row != triplets[k].row() || e.col != triplets[k].col()) break;
      values[e.slot] += triplets[k].value();
    }
    if (k == triplets.size()) return false;
  }
  matrix_.resize(size, size);
  matrix_.setFromTriplets(triplets.begin(), triplets.end());
  matrix_.makeCompressed();
  entries_.resize(triplets.size());
  const int* outer = matrix_.outerIndexPtr();
  const int* inner = matrix_.innerIndexPtr();
  for (std::size_t k = 0; k < triplets.size(); ++k) {
    const int row = triplets[k].row(), col = triplets[k].col();
    const int slot = int(std::lower_bound(inner + outer[col], inner + outer[col + 1], row) - inner);
    entries_[k] = {row, col, slot};
  }
  return true;
}

bool SparseAssembly::valid() const {
  for (const Entry& e : entries_)
    if (e.row < 0 || e.col < 0 || e.row >= matrix_.rows() || e.col >= matrix_.cols() || e.slot < 0 ||
        e.slot >= matrix_.nonZeros())
      return false;
  return true;
}

namespace {
// KLU's user ordering hook: keep the columns as given (pre-permuted).
int32_t keepOrder(int32_t n, int32_t*, int32_t*, int32_t* permutation, klu_common*) {
  for (int32_t i = 0; i < n; ++i) permutation[i] = i;
  return 1;
}
}  // namespace

// KLU through its C interface rather than Eigen's wrapper, for klu_refactor:
// a matrix of the analysed pattern is refactorised with the pivot order of
// the last full factorization (no pivot search, no depth-first search per
// column), about twice as fast; a full factorization is taken again when
// the pivots have degraded (reciprocal pivot ratio below 1e-3 of the full
// factorization's) or the refactorization fails.
struct KluFactors {
  klu_common common;
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  double fullPivotRatio = 0.0;  // klu_rcond of the last full factorization
  bool lastFull = false;  // the last factorize was a full factorization (not klu_refactor)
  KluFactors() { klu_defaults(&common); }
  ~KluFactors() { release(); }
  KluFactors(const KluFactors&) = delete;
  KluFactors& operator=(const KluFactors&) = delete;
  void release() {
    if (numeric) klu_free_numeric(&numeric, &common);
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
  // ordered: eliminate in the columns' given order (pre-permuted), one block.
  bool analyze(const SparseMatrix& A, bool ordered) {
    release();
    klu_defaults(&common);
    if (ordered) {
      common.ordering = 3;  // the user's: keepOrder
      common.user_order = keepOrder;
      common.btf = 0;  // one block, in the given order
    }
    symbolic = klu_analyze(int(A.rows()), const_cast<int*>(A.outerIndexPtr()), const_cast<int*>(A.innerIndexPtr()),
                           &common);
    return symbolic != nullptr;
  }
  bool factorize(const SparseMatrix& A) {
    if (!symbolic) return false;
    int* p = const_cast<int*>(A.outerIndexPtr());
    int* i = const_cast<int*>(A.innerIndexPtr());
    double* x = const_cast<double*>(A.valuePtr());
    lastFull = false;
    if (numeric) {
      if (klu_refactor(p, i, x, symbolic, numeric, &common) && klu_rcond(symbolic, numeric, &common) &&
          common.rcond >= 1e-3 * fullPivotRatio)
        return true;
      klu_free_numeric(&numeric, &common);
    }
    lastFull = true;
    numeric = klu_factor(p, i, x, symbolic, &common);
    if (!numeric || !klu_rcond(symbolic, numeric, &common)) return false;
    fullPivotRatio = common.rcond;
    return common.status == KLU_OK;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) {
    Eigen::VectorXd x = b;
    klu_solve(symbolic, numeric, int(x.size()), 1, x.data(), &common);
    return x;
  }
};
using SparseFactors = KluFactors;

struct LinearSolver::Impl {
  using Permutation = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;
  bool sparse = false;
  // A given pivot order: rows and columns permuted before KLU (position k
  // holds pivot k), which then keeps that order.
  bool ordered = false;
  std::vector<std::pair<int, int>> pivotOrder;
  Permutation rows, columns;
  SparseMatrix permuted;
  Eigen::PartialPivLU<Eigen::MatrixXd> dense;
  // KLU holds handles that are not copied; a copy of the solver (state
  // saving) re-analyses lazily.
  std::unique_ptr<SparseFactors> klu;
  bool analyzed = false;
  // A beam line's block-tridiagonal matrix: block LU (blockTridiagonal),
  // KLU for a factorization it refuses (factoredByBlocks false).
  BlockTridiagonal blocks;
  bool blockTridiagonal = false, factoredByBlocks = false;

  // What the factors were computed from: the pattern analysed, the matrix
  // of KLU's last full factorization (whose pivot order its
  // refactorizations keep, so their bits depend on it) and the last matrix
  // factorized. Replaying analyse, factorize(full), factorize(last)
  // recomputes the same factors bit for bit (state restore), where the
  // factors themselves (dense: n^2 numbers) would be larger to keep.
  struct Record {
    bool hasPattern = false, hasFull = false, hasLast = false, lastWasFull = false;
    SparseMatrix pattern, full, last;
    template <class Archive>
    void visitState(Archive& ar) {
      ar(hasPattern, hasFull, hasLast, lastWasFull, pattern, full, last);
    }
  } record;
  bool replayPending = false;
};

LinearSolver::LinearSolver() : impl_(std::make_unique<Impl>()) {}
LinearSolver::~LinearSolver() = default;
LinearSolver::LinearSolver(const LinearSolver& other) : impl_(std::make_unique<Impl>()) {
  impl_->sparse = other.impl_->sparse;
  impl_->dense = other.impl_->dense;
  impl_->pivotOrder = other.impl_->pivotOrder;
}
LinearSolver& LinearSolver::operator=(const LinearSolver& other) {
  if (this != &other) impl_ = std::move(LinearSolver(other).impl_);
  return *this;
}

bool LinearSolver::usesSparse() const { return impl_->sparse; }

void LinearSolver::saveState(StateWriter& ar) { ar(impl_->record, impl_->pivotOrder); }

void LinearSolver::loadState(StateReader& ar) {
  Impl::Record record;
  std::vector<std::pair<int, int>> pivotOrder;
  ar(record, pivotOrder);
  const auto square = [](const SparseMatrix& A) { return A.rows() == A.cols(); };
  if (!square(record.pattern) || !square(record.full) || !square(record.last))
    throw StateError("a saved Newton matrix is not square");
  for (const auto& [row, column] : pivotOrder)
    if (row < 0 || column < 0 || row >= record.pattern.rows() || column >= record.pattern.rows())
      throw StateError("a saved pivot lies outside its matrix");
  impl_ = std::make_unique<Impl>();
  impl_->record = std::move(record);
  impl_->pivotOrder = std::move(pivotOrder);
  impl_->replayPending = true;
}

// The factors of the saved record, recomputed by the same calls.
void LinearSolver::replay() const {
  impl_->replayPending = false;
  Impl::Record record = std::move(impl_->record);
  impl_->record = Impl::Record();
  LinearSolver& self = const_cast<LinearSolver&>(*this);
  if (!record.hasPattern) return;
  self.analyzePattern(record.pattern, impl_->pivotOrder);
  if (record.hasFull) self.factorize(record.full);
  if (record.hasLast && !(record.hasFull && record.lastWasFull)) self.factorize(record.last);
}

void LinearSolver::analyzePattern(const SparseMatrix& A, const std::vector<std::pair<int, int>>& pivotOrder) {
  // Block LU for a block-tridiagonal matrix of any size (a beam line; also
  // faster than dense LU on a short one). Dense LU for a small matrix and
  // for one that is dense anyway (joint coordinates of a long closed chain:
  // B^T M B and Phi_q B fill it), where KLU's sparse kernel is slower.
  const double size = double(A.rows());
  if (&pivotOrder != &impl_->pivotOrder) impl_->pivotOrder = pivotOrder;
  impl_->replayPending = false;
  Impl::Record& record = impl_->record;
  if (&A != &record.pattern) record.pattern = A;
  record.hasPattern = true;
  record.hasFull = record.hasLast = record.lastWasFull = false;
  impl_->ordered = !pivotOrder.empty();
  impl_->klu.reset();
  impl_->blockTridiagonal = !impl_->ordered && impl_->blocks.analyze(A);
  impl_->factoredByBlocks = false;
  impl_->sparse = impl_->ordered || impl_->blockTridiagonal ||
                  (A.rows() > kDenseThreshold && !(A.rows() <= kDenseMaximum && A.nonZeros() > 0.2 * size * size));
  if (!impl_->sparse) return;
  if (impl_->blockTridiagonal) {
    impl_->analyzed = true;
    return;
  }
  impl_->klu = std::make_unique<SparseFactors>();
  if (impl_->ordered) {
    const int n = int(A.rows());
    std::vector<int> rowAt(n, -1), columnAt(n, -1);  // new position of each row / column
    int k = 0;
    for (const auto& [row, column] : pivotOrder) {
      rowAt[row] = k;
      columnAt[column] = k++;
    }
    for (int i = 0, r = k, c = k; i < n; ++i) {
      if (rowAt[i] < 0) rowAt[i] = r++;
      if (columnAt[i] < 0) columnAt[i] = c++;
    }
    impl_->rows.indices() = Eigen::Map<Eigen::VectorXi>(rowAt.data(), n);
    impl_->columns.indices() = Eigen::Map<Eigen::VectorXi>(columnAt.data(), n);
    impl_->permuted = impl_->rows * A * impl_->columns.transpose();
    impl_->analyzed = impl_->klu->analyze(impl_->permuted, true);
  } else {
    impl_->analyzed = impl_->klu->analyze(A, false);
  }
}

LinearSolver::Status LinearSolver::factorize(const SparseMatrix& A) {
  if (impl_->replayPending) replay();
  if (impl_->klu) impl_->klu->lastFull = false;
  const Status status = factorizeMatrix(A);
  Impl::Record& record = impl_->record;
  const bool full = impl_->klu && impl_->klu->lastFull;
  if (full) {
    if (&A != &record.full) record.full = A;
    record.hasFull = true;
  }
  if (&A != &record.last) record.last = A;
  record.hasLast = true;
  record.lastWasFull = full;
  return status;
}

LinearSolver::Status LinearSolver::factorizeMatrix(const SparseMatrix& A) {
  if (impl_->sparse) {
    if (!impl_->analyzed) analyzePattern(A, impl_->pivotOrder);
    if (!impl_->analyzed) return Status::Singular;
    if (impl_->blockTridiagonal) {
      impl_->factoredByBlocks = impl_->blocks.factorize(A);
      if (impl_->factoredByBlocks) return Status::Ok;
      if (!impl_->klu) {
        impl_->klu = std::make_unique<SparseFactors>();
        if (!impl_->klu->analyze(A, false)) return Status::Singular;
      }
    }
    if (impl_->ordered) {
      impl_->permuted = impl_->rows * A * impl_->columns.transpose();
      return impl_->klu->factorize(impl_->permuted) ? Status::Ok : Status::Singular;
    }
    return impl_->klu->factorize(A) ? Status::Ok : Status::Singular;
  }
  const Eigen::MatrixXd dense(A);
  impl_->dense.compute(dense);
  // PartialPivLU does not report singularity: judge each pivot against its
  // own column (row pivoting keeps the columns), since the blocks of an
  // iteration matrix differ in units: a constraint column's pivot is the
  // Schur complement |Phi_q|^2/|S| (or the small regularisation of a
  // dependent row), far below the largest mass entry yet sound.
  const Eigen::VectorXd pivots = impl_->dense.matrixLU().diagonal().cwiseAbs();
  const Eigen::VectorXd columnScale = dense.cwiseAbs().colwise().maxCoeff().transpose();
  if (!(pivots.array() > 1e-14 * columnScale.array()).all()) return Status::Singular;
  return Status::Ok;
}

Eigen::VectorXd LinearSolver::solve(const Eigen::VectorXd& b) const {
  Eigen::VectorXd x;
  solve(b, x);
  return x;
}

namespace {
// P A = L U solved by plain loops: Eigen's triangular solves dispatch to
// blocked kernels whose set-up outweighs the arithmetic for the few
// unknowns of a small tree (a pendulum's substep: two solves of one
// unknown, 6 % of its time in the profile).
constexpr int kLoopSolveMaximum = 16;

void loopSolve(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  const Eigen::MatrixXd& LU = lu.matrixLU();
  const int* perm = lu.permutationP().indices().data();
  const int n = int(LU.rows());
  x.resize(n);
  for (int i = 0; i < n; ++i) x[perm[i]] = b[i];
  for (int i = 1; i < n; ++i)
    for (int j = 0; j < i; ++j) x[i] -= LU(i, j) * x[j];
  for (int i = n - 1; i >= 0; --i) {
    for (int j = i + 1; j < n; ++j) x[i] -= LU(i, j) * x[j];
    x[i] /= LU(i, i);
  }
}
}  // namespace

void LinearSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  if (impl_->replayPending) replay();
  if (impl_->sparse && impl_->factoredByBlocks)
    impl_->blocks.solve(b, x);
  else if (impl_->sparse && impl_->ordered)
    x = impl_->columns.transpose() * impl_->klu->solve(impl_->rows * b);
  else if (impl_->sparse)
    x = impl_->klu->solve(b);
  else if (b.size() <= kLoopSolveMaximum)
    loopSolve(impl_->dense, b, x);
  else
    x = impl_->dense.solve(b);
}

}  // namespace mfbd
