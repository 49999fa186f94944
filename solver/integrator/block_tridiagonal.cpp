#include "integrator/block_tridiagonal.hpp"

#include <algorithm>
#include <cmath>

namespace mfbd {

namespace {
constexpr int kBlockValues = 3 * 36;  // D_k, L_k, U_k of one block row

// S^-1 by Gauss-Jordan elimination with partial pivoting, unrolled on the
// fixed size (Eigen's LU inverse goes through its general triangular
// solvers, a fifth of a static beam's Newton iteration). False when a
// pivot (the same as LU's) is below 1e-12 of its column's scale in S: the
// rows differ in units.
bool invert(BlockTridiagonal::Mat6 S, BlockTridiagonal::Mat6& inverse) {
  using Mat6 = BlockTridiagonal::Mat6;
  const BlockTridiagonal::Vec6 scale = S.cwiseAbs().colwise().maxCoeff().transpose();
  Mat6 X = Mat6::Identity();
  for (int c = 0; c < 6; ++c) {
    int p;
    S.col(c).tail(6 - c).cwiseAbs().maxCoeff(&p);
    p += c;
    if (!(std::abs(S(p, c)) > 1e-12 * scale[c])) return false;
    if (p != c) {
      S.row(p).swap(S.row(c));
      X.row(p).swap(X.row(c));
    }
    const double pivot = 1.0 / S(c, c);
    S.row(c) *= pivot;
    X.row(c) *= pivot;
    for (int r = 0; r < 6; ++r) {
      const double f = S(r, c);
      if (r == c || f == 0.0) continue;
      S.row(r) -= f * S.row(c);
      X.row(r) -= f * X.row(c);
    }
  }
  inverse = X;
  return true;
}
}  // namespace

bool BlockTridiagonal::analyze(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& A) {
  start_.clear();
  const int n = int(A.rows());
  if (A.cols() != n || !A.isCompressed() || n == 0) return false;
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  auto samePattern = [&](int a, int b) {
    return outer[a + 1] - outer[a] == outer[b + 1] - outer[b] &&
           std::equal(inner + outer[a], inner + outer[a + 1], inner + outer[b]);
  };
  for (int j = 0; j < n; ++j)
    if (j == 0 || !samePattern(j - 1, j) || j - start_.back() == 6) start_.push_back(j);
  start_.push_back(n);
  const int blocks = int(start_.size()) - 1;
  if (blocks < 2) return false;
  std::vector<int> blockOf(n);
  for (int k = 0; k < blocks; ++k) std::fill(blockOf.begin() + start_[k], blockOf.begin() + start_[k + 1], k);
  destination_.resize(A.nonZeros());
  for (int j = 0; j < n; ++j) {
    const int column = blockOf[j], c = j - start_[column];
    for (int p = outer[j]; p < outer[j + 1]; ++p) {
      const int row = blockOf[inner[p]], r = inner[p] - start_[row];
      int which;  // 0: D_row, 1: L_row (column block row - 1), 2: U_row (column block row + 1)
      if (row == column) which = 0;
      else if (row == column + 1) which = 1;
      else if (row + 1 == column) which = 2;
      else return false;
      destination_[p] = kBlockValues * row + 36 * which + 6 * c + r;
    }
  }
  blocks_.resize(std::size_t(kBlockValues) * blocks);
  inverse_.resize(blocks);
  forward_.resize(blocks);
  backward_.resize(blocks);
  return true;
}

bool BlockTridiagonal::factorize(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& A) {
  const int blocks = int(start_.size()) - 1;
  std::fill(blocks_.begin(), blocks_.end(), 0.0);
  const double* values = A.valuePtr();
  for (std::size_t p = 0; p < destination_.size(); ++p) blocks_[destination_[p]] += values[p];
  for (int k = 0; k < blocks; ++k) {
    double* row = blocks_.data() + std::size_t(kBlockValues) * k;
    Eigen::Map<Mat6> D(row);
    const Eigen::Map<const Mat6> L(row + 36), U(row + 72);
    const int size = start_[k + 1] - start_[k];
    for (int i = size; i < 6; ++i) D(i, i) = 1.0;  // padding: decoupled unit rows
    Mat6 S = D;
    if (k > 0) {
      S.noalias() -= L * backward_[k - 1];
      forward_[k].noalias() = L * inverse_[k - 1];
    }
    // The complement judged against the block it came from, its pivots
    // against their columns (invert).
    if (!(S.cwiseAbs().maxCoeff() <= 1e6 * D.cwiseAbs().maxCoeff())) return false;
    if (!invert(S, inverse_[k])) return false;
    backward_[k].noalias() = inverse_[k] * U;
  }
  return true;
}

void BlockTridiagonal::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  const int blocks = int(start_.size()) - 1;
  x.resize(b.size());
  // Forward: y_k = b_k - G_k y_(k-1), padded blocks with zeros.
  std::vector<Vec6>& y = work_;
  y.resize(blocks);
  for (int k = 0; k < blocks; ++k) {
    const int size = start_[k + 1] - start_[k];
    if (size == 6) {
      y[k] = b.segment<6>(start_[k]);
    } else {
      y[k].setZero();
      y[k].head(size) = b.segment(start_[k], size);
    }
    if (k > 0) y[k].noalias() -= forward_[k] * y[k - 1];
  }
  // Backward: x_k = S_k^-1 y_k - W_k x_(k+1).
  Vec6 next = Vec6::Zero();
  for (int k = blocks - 1; k >= 0; --k) {
    Vec6 xk = inverse_[k] * y[k];
    if (k + 1 < blocks) xk.noalias() -= backward_[k] * next;
    const int size = start_[k + 1] - start_[k];
    x.segment(start_[k], size) = xk.head(size);
    next = xk;
  }
}

}  // namespace mfbd
