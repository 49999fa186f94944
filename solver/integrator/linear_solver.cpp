#include "integrator/linear_solver.hpp"

#include <algorithm>

#include <Eigen/Dense>
#include <Eigen/KLUSupport>

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

struct LinearSolver::Impl {
  bool sparse = false;
  Eigen::PartialPivLU<Eigen::MatrixXd> dense;
  // KLU holds raw SuiteSparse handles and cannot be copied; a copy of the
  // solver (state saving) re-analyses lazily.
  std::unique_ptr<Eigen::KLU<SparseMatrix>> klu;
  bool analyzed = false;
};

LinearSolver::LinearSolver() : impl_(std::make_unique<Impl>()) {}
LinearSolver::~LinearSolver() = default;
LinearSolver::LinearSolver(const LinearSolver& other) : impl_(std::make_unique<Impl>()) {
  impl_->sparse = other.impl_->sparse;
  impl_->dense = other.impl_->dense;
}
LinearSolver& LinearSolver::operator=(const LinearSolver& other) {
  if (this != &other) {
    impl_ = std::make_unique<Impl>();
    impl_->sparse = other.impl_->sparse;
    impl_->dense = other.impl_->dense;
  }
  return *this;
}

bool LinearSolver::usesSparse() const { return impl_->sparse; }

void LinearSolver::analyzePattern(const SparseMatrix& A) {
  // Dense LU also for a matrix that is dense anyway (joint coordinates of a
  // long closed chain: B^T M B and Phi_q B fill it), where KLU's sparse
  // kernel is slower.
  const double size = double(A.rows());
  impl_->sparse = A.rows() > kDenseThreshold && !(A.rows() <= kDenseMaximum && A.nonZeros() > 0.2 * size * size);
  if (!impl_->sparse) return;
  impl_->klu = std::make_unique<Eigen::KLU<SparseMatrix>>();
  impl_->klu->analyzePattern(A);
  impl_->analyzed = true;
}

LinearSolver::Status LinearSolver::factorize(const SparseMatrix& A) {
  if (impl_->sparse) {
    if (!impl_->analyzed) analyzePattern(A);
    impl_->klu->factorize(A);
    return impl_->klu->info() == Eigen::Success ? Status::Ok : Status::Singular;
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
  if (impl_->sparse) return impl_->klu->solve(b);
  return impl_->dense.solve(b);
}

}  // namespace mfbd
