// Linear solver with the analyze / factorize / solve / status shape: the
// sparsity pattern is analysed once per topology, then only refactorised.
// Dense LU below a size threshold or for a mostly filled matrix, KLU (SuiteSparse) otherwise.
#pragma once
#include <memory>
#include <vector>

#include <Eigen/SparseCore>

#include "math/state_archive.hpp"

namespace mfbd {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// Triplets -> compressed matrix with a pattern that is kept: the first
// assembly sorts the triplets and records the value slot of each; later
// assemblies with the same triplet positions (the same element blocks in the
// same order) only add the values into their slots, summing duplicates in
// the same order as setFromTriplets, so the matrix is bit-identical to it.
class SparseAssembly {
 public:
  // Returns true when the pattern is new (a new symbolic analysis is due).
  bool assign(int size, const std::vector<Eigen::Triplet<double>>& triplets);
  const SparseMatrix& matrix() const { return matrix_; }
  // The kept pattern decides whether the next assembly is new (and so
  // whether the solver re-analyses): part of the integrator's state.
  template <class Archive>
  void visitState(Archive& ar) {
    ar(matrix_, entries_);
  }
  // Every kept slot lies in the matrix (checked after a restore).
  bool valid() const;

 private:
  struct Entry {
    int row, col;  // of a triplet of the kept pattern
    int slot;      // its index into matrix_.valuePtr()
    template <class Archive>
    void visitState(Archive& ar) {
      ar(row, col, slot);
    }
  };
  SparseMatrix matrix_;
  std::vector<Entry> entries_;
};

class LinearSolver {
 public:
  enum class Status { Ok, Singular };
  static constexpr int kDenseThreshold = 60;  // dense LU up to this size
  static constexpr int kDenseMaximum = 1500;   // and up to this size when more than 20 % filled

  LinearSolver();
  ~LinearSolver();
  LinearSolver(const LinearSolver&);
  LinearSolver& operator=(const LinearSolver&);

  // Symbolic analysis; call again only when the pattern changes. With a
  // pivot order (row, column pairs, possibly fewer than the size), the
  // sparse LU eliminates those first, in that order, then the rest in
  // index order; pivoting still guards each pivot's size.
  void analyzePattern(const SparseMatrix& A, const std::vector<std::pair<int, int>>& pivotOrder = {});
  Status factorize(const SparseMatrix& A);
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  // The same into x (its storage reused when it has the size).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  bool usesSparse() const;

  // State save and restore: not the factors but what they were computed
  // from (see Impl::Record); a restored solver recomputes them, bit for
  // bit, at its next factorize or solve.
  void saveState(StateWriter& ar);
  void loadState(StateReader& ar);
  void saveOrLoad(StateWriter& ar) { saveState(ar); }
  void saveOrLoad(StateReader& ar) { loadState(ar); }

 private:
  Status factorizeMatrix(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& A);
  void replay() const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mfbd
