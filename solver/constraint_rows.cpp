// The constraint rows of a System: the two-marker constraints (cut joints
// and flexible body joints, two_marker_constraints.hpp), each written once
// against its two sides, with one loop each for the rows and their forces
// in the residual, the Jacobian rows, gamma and the geometric stiffness;
// and the drives, one row on a joint coordinate each (not two-marker: no
// pose, a unit Jacobian entry on one rate, no stiffness), in loops of their
// own. The list itself: two_marker_constraints.cpp.
#include <algorithm>

#include "rigid/recursive_dynamics.hpp"
#include "system.hpp"
#include "two_marker_constraints.hpp"

namespace mfbd {

SideColumns System::columnsOf(const ConstraintSide& side, bool bodyColumns) const {
  SideColumns s;
  if (side.onNode()) {
    const FlexNode& node = model_.flexible.nodes[side.node];
    s.map = nodeVariation(nodes_[side.node]) * node.P;
    for (int k = 0; k < 6; ++k)
      if (node.dof[k] >= 0) s.columns.emplace_back(node.dof[k], k);
  } else if (side.body != kGroundIndex && bodyColumns) {
    s.map = Mat6::Identity();
    for (int k = 0; k < 6; ++k) s.columns.emplace_back(bodyUnknown(side.body) + k, k);
  } else if (side.body != kGroundIndex) {
    // B's rows of the body: current after computeVelocityTransformation.
    s.map = data_.velocityTransformation.middleRows<6>(6 * side.body);
    for (int col : supportColumns_[side.body]) s.columns.emplace_back(col, col);
  }
  return s;
}

// J map: a constraint's rows over a side's unknowns (for a body in joint
// space, straight from B's rows of the body).
Eigen::MatrixXd System::rowsOn(const ConstraintSide& side, const SideColumns& columns, const ConstraintJacobian& J,
                               bool bodyColumns) const {
  if (side.onNode() || side.isGround() || bodyColumns) return J * columns.map;
  return J * data_.velocityTransformation.middleRows<6>(6 * side.body);
}

// Rows Phi into phi, the length scale of the constraints, and their forces
// -Phi_z^T lambda: on bodies as applied wrenches (before the backward
// loop), on nodes into their rows of `nodeRows` (when given: the flexible
// part of the residual, after flexibleResidual).
void System::twoMarkerRowsAndForces(const VectorXd& lambda, VectorXd& phi, VectorXd* nodeRows) {
  const SideState state{data_, nodes_};
  for (const TwoMarkerConstraint& k : constraints_) {
    const BodyPose parent = poseOf(state, k.parent), child = poseOf(state, k.child);
    constraintLengthScale_ = std::max({constraintLengthScale_, parent.r.norm() + k.joint.parentMarker.position.norm(),
                                       child.r.norm() + k.joint.childMarker.position.norm()});
    const ConstraintEvaluation c = evaluateJointConstraint(k.joint, parent, child);
    phi.segment(k.firstRow, k.rows) = c.phi;
    if (lambda.size() == 0) continue;
    const auto l = lambda.segment(k.firstRow, k.rows);
    const ConstraintSide* sides[2] = {&k.parent, &k.child};
    const ConstraintJacobian* jacobians[2] = {&c.jacobianParent, &c.jacobianChild};
    for (int s = 0; s < 2; ++s) {
      const ConstraintSide& side = *sides[s];
      if (side.isGround() || (side.onNode() && !nodeRows)) continue;
      const Vec6 f = jacobians[s]->transpose() * l;  // Phi_z^T lambda on this side
      if (!side.onNode()) {
        data_.appliedForce[side.body] -= f.head<3>();
        data_.appliedTorque[side.body] -= f.tail<3>();
        continue;
      }
      const FlexNode& node = model_.flexible.nodes[side.node];
      const Vec6 g = nodeVariationTransposeTimes(nodes_[side.node], f);
      for (int d = 0; d < 6; ++d)
        if (node.dof[d] >= 0) (*nodeRows)[node.dof[d]] += node.P.col(d).dot(g);
    }
  }
}

// Phi_q: each constraint's rows over the unknowns of its two sides, summed
// where both sides move with the same unknowns (two bodies on one path to
// ground). After forwardKinematics, with nodes_ current.
void System::twoMarkerJacobian(bool bodyColumns, Triplets& constraintJacobian) {
  const SideState state{data_, nodes_};
  for (const TwoMarkerConstraint& k : constraints_) {
    const ConstraintEvaluation c = evaluateJointConstraint(k.joint, poseOf(state, k.parent), poseOf(state, k.child));
    const SideColumns parent = columnsOf(k.parent, bodyColumns), child = columnsOf(k.child, bodyColumns);
    const Eigen::MatrixXd parentRows = rowsOn(k.parent, parent, c.jacobianParent, bodyColumns),
                          childRows = rowsOn(k.child, child, c.jacobianChild, bodyColumns);
    // The child's columns, then the parent's; where both sides are bodies
    // in joint space, their paths to ground share rates: one entry per rate,
    // in ascending order (the order of each row's terms in
    // velocityConstraints' sums).
    std::vector<std::pair<int, VectorXd>> rowsOf;
    for (const auto& [unknown, col] : child.columns) rowsOf.emplace_back(unknown, childRows.col(col));
    for (const auto& [unknown, col] : parent.columns) rowsOf.emplace_back(unknown, parentRows.col(col));
    if (!bodyColumns && !k.parent.onNode() && !k.child.onNode() && !k.parent.isGround()) {
      std::stable_sort(rowsOf.begin(), rowsOf.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
      std::size_t kept = 0;  // one entry per unknown: child + parent
      for (std::size_t e = 0; e < rowsOf.size(); ++e)
        if (kept > 0 && rowsOf[kept - 1].first == rowsOf[e].first) rowsOf[kept - 1].second += rowsOf[e].second;
        else rowsOf[kept++] = rowsOf[e];
      rowsOf.resize(kept);
    }
    for (const auto& [unknown, rows] : rowsOf)
      for (int i = 0; i < k.rows; ++i) constraintJacobian.emplace_back(k.firstRow + i, unknown, rows[i]);
  }
}

// gamma = Phi_z zddot(vdot = 0) + (Phidot_z zdot): each side's accelerations
// at vdot = 0 (the bias of the forward loop, driven supports' nodes), plus
// the constraint's own velocity terms. After forwardKinematics and the node
// states at vdot = 0.
void System::twoMarkerAccelerationTerms(VectorXd& gamma) const {
  const SideState state{data_, nodes_};
  for (const TwoMarkerConstraint& k : constraints_) {
    const BodyPose parent = poseOf(state, k.parent), child = poseOf(state, k.child);
    const ConstraintEvaluation c = evaluateJointConstraint(k.joint, parent, child);
    gamma.segment(k.firstRow, k.rows) =
        c.jacobianParent * accelerationOf(state, k.parent) + c.jacobianChild * accelerationOf(state, k.child) +
        mfbd::constraintAccelerationTerm(k.joint, parent, twistOf(state, k.parent), child, twistOf(state, k.child));
  }
}

// Geometric stiffness K = d(Phi_z^T lambda)/dz, each 6 x 6 block between two
// sides mapped by their columns; on a node's own block, besides, the turning
// of its frame in W^T: d(A^T N)/dtheta = skew(A^T N). In the joint-space
// form the body-body blocks are left out: the finite differences of the
// tree's residual hold them already.
void System::twoMarkerStiffness(const VectorXd& lambda, double cK, bool bodyColumns, Triplets& iteration) {
  if (cK == 0.0 || lambda.size() == 0) return;
  const SideState state{data_, nodes_};
  for (const TwoMarkerConstraint& k : constraints_) {
    if (!bodyColumns && !k.parent.onNode() && !k.child.onNode()) continue;
    const BodyPose parentPose = poseOf(state, k.parent), childPose = poseOf(state, k.child);
    const auto l = lambda.segment(k.firstRow, k.rows);
    const GeometricStiffness K = constraintGeometricStiffness(k.joint, parentPose, childPose, l);
    const ConstraintSide* sides[2] = {&k.parent, &k.child};
    const SideColumns columns[2] = {columnsOf(k.parent, bodyColumns), columnsOf(k.child, bodyColumns)};
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        if (sides[a]->isGround() || sides[b]->isGround()) continue;
        if (!bodyColumns && !sides[a]->onNode() && !sides[b]->onNode()) continue;
        Eigen::MatrixXd block = columns[a].map.transpose() * K.block<6, 6>(6 * a, 6 * b) * columns[b].map;
        if (a == b && sides[a]->onNode()) {
          const ConstraintEvaluation c = evaluateJointConstraint(k.joint, parentPose, childPose);
          const ConstraintJacobian& J = a == 0 ? c.jacobianParent : c.jacobianChild;
          const NodeState& n = nodes_[sides[a]->node];
          const Mat6& P = model_.flexible.nodes[sides[a]->node].P;
          const Vec3 moment = n.pose.A.transpose() * (J.transpose() * l).tail<3>();
          block += P.transpose().rightCols<3>() * skew(moment) * P.bottomRows<3>();
        }
        for (const auto& [row, i] : columns[a].columns)
          for (const auto& [col, j] : columns[b].columns) iteration.emplace_back(row, col, cK * block(i, j));
      }
  }
}

// Drives: coordinate - drive(t) = 0 and its multiplier along the joint's
// rate (after the backward loop).
void System::driveRowsAndForces(double t, const Configuration& q, const VectorXd& lambda, VectorXd& phi,
                                VectorXd& r) {
  for (const Joint& j : model_.joints) {
    if (!j.driven) continue;
    constraintLengthScale_ = std::max(constraintLengthScale_, std::abs(q.scalars[j.scalarOffset]));
    phi[j.constraintOffset] = q.scalars[j.scalarOffset] - driveCoordinate(j, t);
    if (lambda.size() > 0) r[j.velocityOffset] += lambda[j.constraintOffset];
  }
}

void System::driveJacobian(Triplets& constraintJacobian) const {
  for (const Joint& j : model_.joints)
    if (j.driven) constraintJacobian.emplace_back(j.constraintOffset, j.velocityOffset, 1.0);
}

void System::constraintRows(bool bodyColumns, Triplets& constraintJacobian) {
  if (!bodyColumns && model_.constraintCount > 0) computeVelocityTransformation(model_, data_);
  driveJacobian(constraintJacobian);
  twoMarkerJacobian(bodyColumns, constraintJacobian);
}

VectorXd System::constraintAccelerationTerm(double t, const Configuration& q, const VectorXd& v) {
  VectorXd gamma = VectorXd::Zero(model_.constraintCount);
  inputsAt(t);
  forwardKinematics(model_, data_, q, v, VectorXd::Zero(model_.velocityCount));
  // A rate input held over the step has no acceleration; an interpolated
  // one has its derivative.
  for (const Joint& j : model_.joints) {
    if (j.driven && !j.driveRateInput) gamma[j.constraintOffset] = -j.drive.acceleration(t);
    if (j.driven && j.driveRateInput && jointSignals_.moving)
      gamma[j.constraintOffset] = -jointSignals_.rate(j.inputOffset, t);
  }
  // Node accelerations at vdot = 0: those of driven supports.
  if (!model_.flexibleBodyJoints.empty())
    flexibleNodeStates(model_.flexible, q, v, VectorXd::Zero(model_.velocityCount), t, drives_, flexibleSignals_,
                       nodes_);
  twoMarkerAccelerationTerms(gamma);
  leaveOutRedundantRows(gamma);
  return gamma;
}

double System::leaveOutRedundantRows(VectorXd& rows) const {
  double largest = 0.0;
  for (int row : redundantRows_) {
    largest = std::max(largest, std::abs(rows[row]));
    rows[row] = 0.0;
  }
  return largest;
}

const TwoMarkerConstraint& System::constraintAtRow(int firstRow) const {
  return *std::find_if(constraints_.begin(), constraints_.end(),
                       [&](const TwoMarkerConstraint& k) { return k.firstRow == firstRow; });
}

JointReaction System::reaction(const TwoMarkerConstraint& k, const VectorXd& lambda) const {
  const SideState state{data_, nodes_};
  return constraintReaction(k.joint, poseOf(state, k.parent), poseOf(state, k.child),
                            lambda.segment(k.firstRow, k.rows));
}

void System::cutJointReaction(int joint, const VectorXd& lambda, Vec3& force, Vec3& torque) const {
  const JointReaction r = reaction(constraintAtRow(model_.joints[joint].constraintOffset), lambda);
  force = r.force;
  torque = r.torque;
}

void System::flexibleBodyJointReaction(int k, const VectorXd& lambda, Vec3& force, Vec3& torque) const {
  const JointReaction r = reaction(constraintAtRow(model_.flexibleBodyJoints[k].constraintOffset), lambda);
  force = r.force;
  torque = r.torque;
}

double System::flexibleBodyJointViolation(int k) const {
  const TwoMarkerConstraint& c = constraintAtRow(model_.flexibleBodyJoints[k].constraintOffset);
  const SideState state{data_, nodes_};
  return evaluateJointConstraint(c.joint, poseOf(state, c.parent), poseOf(state, c.child)).phi.cwiseAbs().maxCoeff();
}

}  // namespace mfbd
