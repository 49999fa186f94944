#include "integrator/constraint_rank.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/QR>

namespace mfbd {

std::vector<int> ConstraintRank::redundantRows() const {
  std::vector<int> rows = vanishingRows;
  for (const std::vector<int>& set : dependentRows) rows.push_back(set.front());
  std::sort(rows.begin(), rows.end());
  return rows;
}

ConstraintRank constraintRank(const Eigen::MatrixXd& jacobian, double tolerance) {
  ConstraintRank result;
  const Eigen::VectorXd norms = jacobian.rowwise().norm();
  const double largest = norms.size() ? norms.maxCoeff() : 0.0;
  std::vector<int> kept;  // rows with a gradient
  for (int i = 0; i < int(norms.size()); ++i) {
    if (norms[i] <= tolerance * largest || largest == 0.0) result.vanishingRows.push_back(i);
    else kept.push_back(i);
  }
  if (kept.empty()) return result;
  // Columns of A: the kept rows scaled to unit norm, so that metres and
  // radians, long and short lever arms weigh alike.
  Eigen::MatrixXd A(jacobian.cols(), int(kept.size()));
  for (int k = 0; k < int(kept.size()); ++k) A.col(k) = jacobian.row(kept[k]).transpose() / norms[kept[k]];
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(tolerance);
  result.rank = int(qr.rank());
  const auto& order = qr.colsPermutation().indices();
  const Eigen::MatrixXd& packed = qr.matrixR();  // R on and above the diagonal
  for (int k = result.rank; k < int(kept.size()); ++k) {
    // The dependent column as a combination of the independent ones: R11 x = R12 e_k.
    const Eigen::VectorXd x = packed.topLeftCorner(result.rank, result.rank)
                                  .triangularView<Eigen::Upper>()
                                  .solve(packed.col(k).head(result.rank));
    std::vector<int> set = {kept[order[k]]};
    const double scale = x.size() ? x.cwiseAbs().maxCoeff() : 0.0;
    for (int i = 0; i < int(x.size()); ++i)
      if (std::abs(x[i]) > 1e-6 * scale) set.push_back(kept[order[i]]);
    result.dependentRows.push_back(set);
  }
  return result;
}

}  // namespace mfbd
