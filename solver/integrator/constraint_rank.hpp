// The numerical rank of a constraint Jacobian Phi_q, and which rows are
// redundant: a planar loop closed in 3-D (rows that vanish identically), the
// Bricard mechanism (one row a combination of others), a mechanism at a
// singular configuration, or two drives that prescribe the same motion.
// The integrator handles such rows by its regularised constraint block
// (time_stepper.hpp); this names them, for the log at initialization and
// for the message of a step that fails.
#pragma once
#include <vector>

#include <Eigen/Core>

namespace mfbd {

struct ConstraintRank {
  int rank = 0;
  // Rows whose gradient vanishes (relative to the largest row): they
  // constrain nothing here.
  std::vector<int> vanishingRows;
  // Each dependent row, followed by the independent rows of which it is a
  // combination.
  std::vector<std::vector<int>> dependentRows;
  // The rows the others make redundant: the vanishing ones and the first
  // of each dependent set, increasing.
  std::vector<int> redundantRows() const;
};

// Rank by QR with column pivoting of the row-normalised Phi_q^T: a row is
// dependent when its part outside the span of the rows before it is below
// `tolerance` (relative, rows of unit norm).
ConstraintRank constraintRank(const Eigen::MatrixXd& jacobian, double tolerance = 1e-9);

}  // namespace mfbd
