// Block LU of a block-tridiagonal matrix with blocks of up to 6 unknowns:
// the Newton matrix of a beam line, whose nodes (6 unknowns each, fewer at
// supports) couple only with their neighbours along the line.
//
// The blocks are found from the pattern alone: consecutive columns with the
// same rows are one block (a node's unknowns), and the matrix qualifies when
// every entry lies in a block's own, previous or next block row. Each block
// is padded to 6 x 6 with a unit diagonal, so the elimination runs on
// fixed-size matrices:
//   S_0 = D_0,  S_k = D_k - L_k S_{k-1}^-1 U_{k-1},
// with L_k, D_k, U_k the blocks left of, on and right of the diagonal. A
// solve is then three 6 x 6 products per block against KLU's indexed
// sparse triangles (a cantilever of 1000 elements: 23 against 105-170 ns
// per element and solve).
// Pivoting stays within a block; factorize refuses (false) a matrix whose
// Schur complements S_k grow or turn near singular (no cross-block pivot
// would be needed in a mass- or stiffness-dominated beam; something else
// is happening), and the caller then takes a pivoting sparse LU.
#pragma once
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace mfbd {

class BlockTridiagonal {
 public:
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;

  // True if A's pattern is block tridiagonal in blocks of at most 6 (and
  // at least two blocks); then factorize and solve work on it.
  bool analyze(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& A);
  bool factorize(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& A);
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

 private:
  std::vector<int> start_;  // first unknown of each block (and the size at the end)
  // For each stored entry of A (in its value order): where it goes in
  // blocks_, the D_k, L_k, U_k of all blocks one after the other.
  std::vector<int> destination_;
  std::vector<double> blocks_;
  // The factors: S_k^-1, G_k = L_k S_{k-1}^-1 (k >= 1), W_k = S_k^-1 U_k.
  std::vector<Mat6> inverse_, forward_, backward_;
  mutable std::vector<Vec6> work_;  // the forward sweep's y_k
};

}  // namespace mfbd
