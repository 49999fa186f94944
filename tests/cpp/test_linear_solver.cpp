// The linear solvers behind the Newton matrix: block LU of a beam line's
// block-tridiagonal matrix against dense LU, and the fall-back to the
// pivoting sparse LU when block elimination would need a pivot from
// another block; the small dense LU's own substitution loops.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "integrator/block_tridiagonal.hpp"
#include "integrator/linear_solver.hpp"

namespace mfbd {
namespace {

// A block-tridiagonal matrix with the given block sizes, full blocks of
// random entries (every entry stored, as the beam's assembly does), the
// diagonal blocks shifted by `shift` I.
SparseMatrix blockTridiagonalMatrix(const std::vector<int>& sizes, double shift, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<int> start{0};
  for (int s : sizes) start.push_back(start.back() + s);
  std::vector<Eigen::Triplet<double>> triplets;
  const int blocks = int(sizes.size());
  for (int k = 0; k < blocks; ++k)
    for (int l = std::max(0, k - 1); l <= std::min(blocks - 1, k + 1); ++l)
      for (int i = start[k]; i < start[k + 1]; ++i)
        for (int j = start[l]; j < start[l + 1]; ++j)
          triplets.emplace_back(i, j, uniform(random) + (i == j ? shift : 0.0));
  SparseMatrix A(start.back(), start.back());
  A.setFromTriplets(triplets.begin(), triplets.end());
  A.makeCompressed();
  return A;
}

double relativeError(const Eigen::VectorXd& x, const Eigen::VectorXd& reference) {
  return (x - reference).norm() / reference.norm();
}

TEST(BlockTridiagonal, SolvesBlocksOfMixedSizesAsDenseLUDoes) {
  // Supports leave a beam node 0, 1, 3 or 4 unknowns; here 1 to 6 mixed.
  const SparseMatrix A = blockTridiagonalMatrix({3, 6, 6, 4, 6, 1, 6, 6, 2}, 4.0, 7u);
  BlockTridiagonal blocks;
  ASSERT_TRUE(blocks.analyze(A));
  ASSERT_TRUE(blocks.factorize(A));
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
  const Eigen::VectorXd reference = Eigen::MatrixXd(A).partialPivLu().solve(b);
  Eigen::VectorXd x;
  blocks.solve(b, x);
  EXPECT_LT(relativeError(x, reference), 1e-13);
  // New values in the same pattern: refactorised, same answer as dense LU.
  const SparseMatrix A2 = blockTridiagonalMatrix({3, 6, 6, 4, 6, 1, 6, 6, 2}, 5.0, 8u);
  ASSERT_TRUE(blocks.factorize(A2));
  blocks.solve(b, x);
  EXPECT_LT(relativeError(x, Eigen::MatrixXd(A2).partialPivLu().solve(b)), 1e-13);
}

TEST(BlockTridiagonal, SolvesTwoBlocks) {
  // A beam of two free nodes (F3, F4 at 2 elements), one of them supported.
  const SparseMatrix A = blockTridiagonalMatrix({6, 4}, 3.0, 5u);
  BlockTridiagonal blocks;
  ASSERT_TRUE(blocks.analyze(A));
  ASSERT_TRUE(blocks.factorize(A));
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), 2.0, -1.0);
  Eigen::VectorXd x;
  blocks.solve(b, x);
  EXPECT_LT(relativeError(x, Eigen::MatrixXd(A).partialPivLu().solve(b)), 1e-13);
}

TEST(BlockTridiagonal, RefusesAnEntryBeyondTheNeighbourBlocks) {
  SparseMatrix A = blockTridiagonalMatrix({6, 6, 6, 6}, 4.0, 3u);
  A.coeffRef(0, 18) = 1.0;  // block 0 coupled with block 3
  A.makeCompressed();
  BlockTridiagonal blocks;
  EXPECT_FALSE(blocks.analyze(A));
}

TEST(LinearSolver, FallsBackToPivotingLUWhereBlockEliminationWouldNeedIt) {
  // The first diagonal block zero: block elimination has no pivot there,
  // the matrix itself is regular (a well-conditioned random one).
  SparseMatrix A = blockTridiagonalMatrix({6, 6, 6, 6, 6}, 4.0, 11u);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) A.coeffRef(i, j) = 0.0;
  BlockTridiagonal blocks;
  ASSERT_TRUE(blocks.analyze(A));
  EXPECT_FALSE(blocks.factorize(A));
  LinearSolver solver;
  solver.analyzePattern(A);
  ASSERT_EQ(solver.factorize(A), LinearSolver::Status::Ok);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), 1.0, -3.0);
  const Eigen::VectorXd reference = Eigen::MatrixXd(A).partialPivLu().solve(b);
  EXPECT_LT(relativeError(solver.solve(b), reference), 1e-12);
  // And back to the block LU for a matrix of the same pattern that allows it.
  const SparseMatrix regular = blockTridiagonalMatrix({6, 6, 6, 6, 6}, 4.0, 12u);
  ASSERT_EQ(solver.factorize(regular), LinearSolver::Status::Ok);
  EXPECT_LT(relativeError(solver.solve(b), Eigen::MatrixXd(regular).partialPivLu().solve(b)), 1e-13);
}

TEST(LinearSolver, SmallDenseMatricesSolveWithPivotingAtEverySize) {
  // Sizes on both sides of the substitution loops' limit (16), each with a
  // zero first pivot that only a row exchange gets past: x solves A x = b
  // to round-off of the matrix's conditioning.
  std::mt19937 random(5u);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int n : {1, 2, 3, 6, 16, 17, 40}) {
    Eigen::MatrixXd dense = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return uniform(random); });
    dense.diagonal().array() += 3.0;
    if (n > 1) dense(0, 0) = 0.0;
    const SparseMatrix A = dense.sparseView();
    LinearSolver solver;
    solver.analyzePattern(A);
    ASSERT_EQ(solver.factorize(A), LinearSolver::Status::Ok) << "n = " << n;
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 2.0, -1.0);
    const Eigen::VectorXd x = solver.solve(b);
    EXPECT_LT((dense * x - b).norm() / b.norm(), 1e-13) << "n = " << n;
  }
}

}  // namespace
}  // namespace mfbd
