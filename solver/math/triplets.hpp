// Entries (row, column, value) of a sparse matrix as its parts write them:
// the system's tangent and constraint Jacobian, and the flexible mesh's
// blocks of it, before the integrator compresses them.
#pragma once
#include <vector>

#include <Eigen/SparseCore>

namespace mfbd {

using Triplets = std::vector<Eigen::Triplet<double>>;

}  // namespace mfbd
