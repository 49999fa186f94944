// The rigid tree's joint-space tangent: its sparsity, fixed by the
// topology, the colouring of its rates for finite differences, and the
// tangent itself (mass analytic, the rest by differences of the residual).
#include <algorithm>

#include "rigid/recursive_dynamics.hpp"
#include "system.hpp"

namespace mfbd {

// A body moves with the rates of the joints on its path to ground. Two
// rates couple in the tree's tangent (mass, and the derivatives of the
// joint-space forces) when one joint is outboard of the other: the forces on
// a subtree depend on the poses of that subtree and its path to ground. A
// two-marker constraint or a force element between bodies a and b couples,
// besides, every pair of the rates that move a or b: its force depends on
// both poses and lands on both paths to ground (R3's 40 loops: a band of
// three rates, not the dense 81 x 81 of all pairs).
void System::jointSpaceSparsity() {
  const int n = model_.rigidVelocityCount;
  std::vector<int> bodyOfColumn(n, kGroundIndex);
  supportColumns_.resize(model_.bodies.size());
  for (int b = 0; b < int(model_.bodies.size()); ++b) {
    for (int at = b; at != kGroundIndex; at = model_.bodies[at].parent) {
      const Joint& j = model_.joints[model_.bodies[at].inboardJoint];
      for (int d = 0; d < j.dofs; ++d) supportColumns_[b].push_back(j.velocityOffset + d);
    }
    const Joint& own = model_.joints[model_.bodies[b].inboardJoint];
    for (int d = 0; d < own.dofs; ++d) bodyOfColumn[own.velocityOffset + d] = b;
  }
  auto outboardOf = [&](int inner, int outer) {
    for (int at = outer; at != kGroundIndex; at = model_.bodies[at].parent)
      if (at == inner) return true;
    return false;
  };
  ratesCoupled_.resize(n, n);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k)
      ratesCoupled_(i, k) =
          outboardOf(bodyOfColumn[i], bodyOfColumn[k]) || outboardOf(bodyOfColumn[k], bodyOfColumn[i]);
  auto coupleSupports = [&](int a, int b) {
    std::vector<int> columns;
    for (int body : {a, b})
      if (body != kGroundIndex) columns.insert(columns.end(), supportColumns_[body].begin(), supportColumns_[body].end());
    for (int i : columns)
      for (int k : columns) ratesCoupled_(i, k) = true;
  };
  // A node side moves no rate (a flexible body joint's virtual body alone
  // couples nothing new: its rates are on one path).
  for (const TwoMarkerConstraint& c : constraints_) coupleSupports(c.parent.body, c.child.body);
  for (const ForceElement& f : model_.forces)
    if (f.kind != ForceElement::Kind::AppliedForce) coupleSupports(f.marker1.body, f.marker2.body);
}

// Rates that no row shares go into one finite-difference column of the
// tangent together (Curtis, Powell & Reid 1974): greedy colouring, each
// rate the first colour that none of the rates sharing a row with it has.
void System::colourRates() {
  const int n = model_.rigidVelocityCount;
  std::vector<int> colourOf(n, -1);
  std::vector<char> taken;
  for (int k = 0; k < n; ++k) {
    taken.assign(n, 0);
    for (int row = 0; row < n; ++row)
      if (ratesCoupled_(row, k))
        for (int other = 0; other < k; ++other)
          if (ratesCoupled_(row, other)) taken[colourOf[other]] = 1;
    colourOf[k] = int(std::find(taken.begin(), taken.end(), 0) - taken.begin());
    if (colourOf[k] >= int(tangentColours_.size())) tangentColours_.resize(colourOf[k] + 1);
    tangentColours_[colourOf[k]].push_back(k);
  }
}

// Mass block analytic (B^T M B); velocity and configuration derivatives by
// finite differences of the rigid residual, for now, a residual per colour
// of rates that share no row (tangentColours_). Every entry that can be
// nonzero (ratesCoupled_) is emitted, zeros included, so the sparsity pattern
// never changes.
void System::rigidTangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                          const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                          Triplets& constraintJacobian) {
  const int n = model_.rigidVelocityCount;
  forwardKinematics(model_, data_, q, v, vdot);
  Eigen::MatrixXd& S = massMatrix_;
  jointSpaceMassMatrix(model_, data_, S);
  S *= cM;
  constraintRows(false, constraintJacobian);
  if (cC != 0.0 || cK != 0.0) {
    VectorXd r0, r1, phi;
    rigidResidual(t, q, v, vdot, lambda, r0, phi);
    const double eps = 1e-7;
    VectorXd dq = VectorXd::Zero(model_.velocityCount);
    for (const std::vector<int>& colour : tangentColours_) {
      // Perturb q by eps along the colour's rates and v by (cC/cK) times
      // that: (r1 - r0)/eps = K e_i + (cC/cK) C e_i in the rows of rate i.
      for (int i : colour) dq[i] = eps;
      Configuration qp = q;
      VectorXd vp = v;
      if (cK != 0.0) {
        retract(qp, dq);
        vp += cC / cK * dq;
      } else {
        vp += dq;
      }
      rigidResidual(t, qp, vp, vdot, lambda, r1, phi);
      const double c = (cK != 0.0 ? cK : cC) / eps;
      for (int i : colour) {
        dq[i] = 0.0;
        for (int row = 0; row < n; ++row)
          if (ratesCoupled_(row, i)) S(row, i) += c * (r1[row] - r0[row]);
      }
    }
    forwardKinematics(model_, data_, q, v, vdot);  // the workspace of q again, not of the last perturbation
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (ratesCoupled_(i, j)) iteration.emplace_back(i, j, S(i, j));
}


}  // namespace mfbd
