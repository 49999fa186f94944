// Linear solver with the analyze / factorize / solve / status shape: the
// sparsity pattern is analysed once per topology, then only refactorised.
// Dense LU below a size threshold, KLU (SuiteSparse) above.
#pragma once
#include <memory>

#include <Eigen/SparseCore>

namespace mfbd {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

class LinearSolver {
 public:
  enum class Status { Ok, Singular };
  static constexpr int kDenseThreshold = 60;

  LinearSolver();
  ~LinearSolver();
  LinearSolver(const LinearSolver&);
  LinearSolver& operator=(const LinearSolver&);

  // Symbolic analysis; call again only when the pattern changes.
  void analyzePattern(const SparseMatrix& A);
  Status factorize(const SparseMatrix& A);
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  bool usesSparse() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mfbd
