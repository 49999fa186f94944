#include "system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "coupling/joint_constraint.hpp"
#include "rigid/force_elements.hpp"
#include "rigid/recursive_dynamics.hpp"

namespace mfbd {

System::System(Model model)
    : model_(std::move(model)),
      data_(model_),
      jointInputs_(VectorXd::Zero(model_.jointInputCount)),
      flexibleInputs_(VectorXd::Zero(model_.flexible.inputCount)),
      forceInputs_(VectorXd::Zero(model_.forceInputCount)) {
  startDrives(0.0);
  // A body moves with the rates of the joints on its path to ground.
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
  // Two rates couple in the tree's tangent (mass, and the derivatives of the
  // joint-space forces) only when one joint is outboard of the other: the
  // forces on a subtree depend on the poses of that subtree and its path to
  // ground. Cut joints and force elements between two bodies couple any
  // branches: then every pair.
  bool branchesCoupled = false;
  for (const Joint& j : model_.joints) branchesCoupled = branchesCoupled || j.cut;
  for (const ForceElement& f : model_.forces)
    branchesCoupled = branchesCoupled || (f.kind != ForceElement::Kind::AppliedForce &&
                                          f.marker1.body != kGroundIndex && f.marker2.body != kGroundIndex);
  auto outboardOf = [&](int inner, int outer) {
    for (int at = outer; at != kGroundIndex; at = model_.bodies[at].parent)
      if (at == inner) return true;
    return false;
  };
  ratesCoupled_.resize(n, n);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k)
      ratesCoupled_(i, k) = branchesCoupled || outboardOf(bodyOfColumn[i], bodyOfColumn[k]) ||
                            outboardOf(bodyOfColumn[k], bodyOfColumn[i]);
}

void System::startDrives(double t0) {
  drives_.startAngle.assign(model_.flexible.drives.size(), 0.0);
  drives_.stepStart = t0;
  jointDriveStepStart_ = t0;
  jointDriveStart_.assign(model_.joints.size(), 0.0);
  for (std::size_t k = 0; k < model_.joints.size(); ++k) {
    const Joint& j = model_.joints[k];
    if (j.driveRateInput) jointDriveStart_[k] = model_.initialConfiguration.scalars[j.scalarOffset];
  }
}

double System::driveCoordinate(const Joint& joint, double t) const {
  if (!joint.driveRateInput) return joint.drive(t);
  return jointDriveStart_[&joint - model_.joints.data()] + jointInputs_[joint.inputOffset] * (t - jointDriveStepStart_);
}

void System::retract(Configuration& q, const VectorXd& dq) const { mfbd::retract(model_.blocks, q, dq); }

void System::endStep(double t) {
  for (std::size_t d = 0; d < drives_.startAngle.size(); ++d)
    drives_.startAngle[d] = drives_.angle(model_.flexible, flexibleInputs_, int(d), t);
  drives_.stepStart = t;
  for (std::size_t k = 0; k < model_.joints.size(); ++k)
    if (model_.joints[k].driveRateInput) jointDriveStart_[k] = driveCoordinate(model_.joints[k], t);
  jointDriveStepStart_ = t;
}

// tau = actuator inputs - viscous joint damping - rotational springs, along each joint's DOFs.
void System::jointForces(const Configuration& q, const VectorXd& v, VectorXd& tau) const {
  tau.setZero(model_.rigidVelocityCount);
  for (const Joint& j : model_.joints) {
    auto t = tau.segment(j.velocityOffset, j.dofs);
    t = -(j.damping + j.springDamping) * v.segment(j.velocityOffset, j.dofs);
    if (j.springStiffness != 0.0) t[0] -= j.springStiffness * (q.scalars[j.scalarOffset] - j.springFreeCoordinate);
    if (j.actuated) t += jointInputs_.segment(j.inputOffset, j.dofs);
  }
}

namespace {

JointConstraint constraintOf(const Joint& j) {
  return {j.type, {j.parentMarker.position, j.parentMarker.orientation},
          {j.childMarker.position, j.childMarker.orientation}};
}

// Pose of a body's centre-of-mass frame; ground is the identity.
BodyPose poseOf(const Data& data, int body) {
  if (body == kGroundIndex) return {Vec3::Zero(), Mat3::Identity()};
  return {data.body[body].position, data.body[body].orientation};
}

BodyTwist twistOf(const Data& data, int body) {
  if (body == kGroundIndex) return {Vec3::Zero(), Vec3::Zero()};
  return {data.body[body].velocity, data.body[body].angularVelocity};
}

}  // namespace

// Joint-space residual B^T (M Ydot - Q + Phi_Z^T lambda) - tau: the cut
// joints' forces -Phi_Z^T lambda enter the backward loop as applied wrenches.
void System::rigidResidual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                           const VectorXd& lambda, VectorXd& r, VectorXd& phi) {
  forwardKinematics(model_, data_, q, v, vdot);
  for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
    data_.appliedForce[i] = model_.bodies[i].mass * model_.gravity;
    data_.appliedTorque[i].setZero();
  }
  applyForceElements(model_.forces, forceInputs_, data_);
  phi.setZero(model_.constraintCount);
  constraintLengthScale_ = 1.0;
  for (const Joint& j : model_.joints) {
    if (j.driven) constraintLengthScale_ = std::max(constraintLengthScale_, std::abs(q.scalars[j.scalarOffset]));
    if (!j.cut) continue;
    const int parent = j.parentMarker.body, child = j.childMarker.body;
    const double reach = std::max(poseOf(data_, parent).r.norm() + j.parentMarker.position.norm(),
                                  poseOf(data_, child).r.norm() + j.childMarker.position.norm());
    constraintLengthScale_ = std::max(constraintLengthScale_, reach);
    const ConstraintEvaluation c = evaluateJointConstraint(constraintOf(j), poseOf(data_, parent), poseOf(data_, child));
    const int m = int(c.phi.size());
    phi.segment(j.constraintOffset, m) = c.phi;
    if (lambda.size() == 0) continue;
    const auto l = lambda.segment(j.constraintOffset, m);
    const Vec6 onChild = -c.jacobianChild.transpose() * l;
    data_.appliedForce[child] += onChild.head<3>();
    data_.appliedTorque[child] += onChild.tail<3>();
    if (parent != kGroundIndex) {
      const Vec6 onParent = -c.jacobianParent.transpose() * l;
      data_.appliedForce[parent] += onParent.head<3>();
      data_.appliedTorque[parent] += onParent.tail<3>();
    }
  }
  // Flexible body joints: rows, and their forces on the virtual bodies (the
  // node side is added in residual(); nodes_ is current).
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
    const BodyPose node = poseOfNode(nodes_[w.node]), body = poseOf(data_, w.virtualBody);
    constraintLengthScale_ =
        std::max({constraintLengthScale_, node.r.norm() + w.weld.parentMarker.position.norm(), body.r.norm()});
    const ConstraintEvaluation c = evaluateJointConstraint(w.weld, node, body);
    phi.segment<6>(w.constraintOffset) = c.phi;
    if (lambda.size() == 0) continue;
    const Vec6 onBody = -c.jacobianChild.transpose() * lambda.segment<6>(w.constraintOffset);
    data_.appliedForce[w.virtualBody] += onBody.head<3>();
    data_.appliedTorque[w.virtualBody] += onBody.tail<3>();
  }
  jointForces(q, v, tau_);
  backwardNewtonEuler(model_, data_, tau_, r);
  // Drives: coordinate - drive(t) = 0; the multiplier acts along the DOF.
  for (const Joint& j : model_.joints) {
    if (!j.driven) continue;
    phi[j.constraintOffset] = q.scalars[j.scalarOffset] - driveCoordinate(j, t);
    if (lambda.size() > 0) r[j.velocityOffset] += lambda[j.constraintOffset];
  }
}

void System::residual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                      const VectorXd& lambda, VectorXd& r, VectorXd& phi) {
  r.setZero(model_.velocityCount);
  phi.resize(0);
  // Nodes first: the flexible body joints of the rigid part read them.
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleInputs_, nodes_);
  if (!model_.bodies.empty()) {
    rigidResidual(t, q, v, vdot, lambda, rigid_, phi);
    r.head(model_.rigidVelocityCount) = rigid_;
  }
  if (!model_.flexible.empty()) {
    const bool inertia = model_.analysis == Analysis::Dynamic;
    if (!flexibleResidual(model_.flexible, nodes_, model_.gravity, flexibleInputs_, t, inertia, r))
      r.setConstant(std::numeric_limits<double>::quiet_NaN());  // a failed iterate: the step is retried smaller
    if (lambda.size() > 0) weldForcesOnNodes(lambda, r);
  }
}

// Node rows of the flexible body joints' forces: W^T Phi_node^T lambda.
void System::weldForcesOnNodes(const VectorXd& lambda, VectorXd& r) const {
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
    const NodeState& n = nodes_[w.node];
    const ConstraintEvaluation c = evaluateJointConstraint(w.weld, poseOfNode(n), poseOf(data_, w.virtualBody));
    const Vec6 g = nodeVariation(n).transpose() * (c.jacobianParent.transpose() * lambda.segment<6>(w.constraintOffset));
    const FlexNode& node = model_.flexible.nodes[w.node];
    for (int k = 0; k < 6; ++k)
      if (node.dof[k] >= 0) r[node.dof[k]] += node.P.col(k).dot(g);
  }
}

// Mass block analytic (B^T M B); velocity and configuration derivatives by
// finite differences of the rigid residual, for now. Every entry that can be
// nonzero (ratesCoupled_) is emitted, zeros included, so the sparsity pattern
// never changes.
void System::rigidTangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                          const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                          Triplets& constraintJacobian) {
  const int n = model_.rigidVelocityCount;
  forwardKinematics(model_, data_, q, v, vdot);
  if (model_.constraintCount > 0) computeVelocityTransformation(model_, data_);
  Eigen::MatrixXd S = cM * jointSpaceMassMatrix(model_, data_);
  // Constraint rows Phi_q = Phi_Z B, over the rates that move the bodies.
  const Eigen::MatrixXd& B = data_.velocityTransformation;
  for (const Joint& j : model_.joints) {
    if (j.driven) constraintJacobian.emplace_back(j.constraintOffset, j.velocityOffset, 1.0);
    if (!j.cut) continue;
    const int parent = j.parentMarker.body, child = j.childMarker.body;
    const ConstraintEvaluation c = evaluateJointConstraint(constraintOf(j), poseOf(data_, parent), poseOf(data_, child));
    Eigen::MatrixXd rows = c.jacobianChild * B.middleRows<6>(6 * child);
    if (parent != kGroundIndex) rows += c.jacobianParent * B.middleRows<6>(6 * parent);
    // Nonzero only in the rates that move the two bodies.
    std::vector<int> columns = parent == kGroundIndex ? std::vector<int>() : supportColumns_[parent];
    columns.insert(columns.end(), supportColumns_[child].begin(), supportColumns_[child].end());
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    for (int col : columns)
      for (int i = 0; i < rows.rows(); ++i) constraintJacobian.emplace_back(j.constraintOffset + i, col, rows(i, col));
  }
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
    const ConstraintEvaluation c =
        evaluateJointConstraint(w.weld, poseOfNode(nodes_[w.node]), poseOf(data_, w.virtualBody));
    const Eigen::MatrixXd rows = c.jacobianChild * B.middleRows<6>(6 * w.virtualBody);
    for (int col : supportColumns_[w.virtualBody])
      for (int i = 0; i < 6; ++i) constraintJacobian.emplace_back(w.constraintOffset + i, col, rows(i, col));
  }
  if (cC != 0.0 || cK != 0.0) {
    VectorXd r0, r1, phi;
    rigidResidual(t, q, v, vdot, lambda, r0, phi);
    const double eps = 1e-7;
    for (int i = 0; i < n; ++i) {
      // Perturb q by eps e_i and v by (cC/cK) eps e_i: (r1 - r0)/eps = K e_i + (cC/cK) C e_i.
      VectorXd dq = VectorXd::Zero(model_.velocityCount);
      dq[i] = eps;
      Configuration qp = q;
      VectorXd vp = v;
      if (cK != 0.0) {
        retract(qp, dq);
        vp[i] += cC / cK * eps;
      } else {
        vp[i] += eps;
      }
      rigidResidual(t, qp, vp, vdot, lambda, r1, phi);
      S.col(i) += (cK != 0.0 ? cK : cC) * (r1 - r0) / eps;
    }
    forwardKinematics(model_, data_, q, v, vdot);  // the workspace of q again, not of the last perturbation
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (ratesCoupled_(i, j)) iteration.emplace_back(i, j, S(i, j));
}

void System::tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                     const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                     Triplets& constraintJacobian) {
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleInputs_, nodes_);
  if (!model_.bodies.empty()) rigidTangent(t, q, v, vdot, lambda, cM, cC, cK, iteration, constraintJacobian);
  if (!model_.flexible.empty()) {
    const bool inertia = model_.analysis == Analysis::Dynamic;
    flexibleTangent(model_.flexible, nodes_, flexibleInputs_, t, inertia ? cM : 0.0, inertia ? cC : 0.0, cK,
                    iteration);
    weldTangent(lambda, cK, iteration, constraintJacobian);
  }
}

// The flexible body joints' blocks that the rigid finite differences do not
// see (they hold the nodes fixed): node columns of the rows, Phi_node W P;
// and the geometric stiffness K = d(Phi_z^T lambda)/dz between node and
// virtual body, mapped by W P (node) and B (virtual body), plus the turning
// of the node frame in W^T: d(A^T N)/dtheta = skew(A^T N).
void System::weldTangent(const VectorXd& lambda, double cK, Triplets& iteration, Triplets& constraintJacobian) const {
  const Eigen::MatrixXd& B = data_.velocityTransformation;  // current: rigidTangent computed it
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
    const NodeState& n = nodes_[w.node];
    const FlexNode& node = model_.flexible.nodes[w.node];
    const BodyPose nodePose = poseOfNode(n), bodyPose = poseOf(data_, w.virtualBody);
    const ConstraintEvaluation c = evaluateJointConstraint(w.weld, nodePose, bodyPose);
    const Mat6 WP = nodeVariation(n) * node.P;
    const Mat6 rows = c.jacobianParent * WP;
    for (int i = 0; i < 6; ++i)
      for (int k = 0; k < 6; ++k)
        if (node.dof[k] >= 0) constraintJacobian.emplace_back(w.constraintOffset + i, node.dof[k], rows(i, k));
    if (cK == 0.0 || lambda.size() == 0) continue;
    const auto l = lambda.segment<6>(w.constraintOffset);
    const GeometricStiffness K = constraintGeometricStiffness(w.weld, nodePose, bodyPose, l);
    Mat6 nodeNode = WP.transpose() * K.topLeftCorner<6, 6>() * WP;
    const Vec3 moment = n.pose.A.transpose() * (c.jacobianParent.transpose() * l).tail<3>();
    nodeNode += node.P.transpose().rightCols<3>() * skew(moment) * node.P.bottomRows<3>();
    const Eigen::Matrix<double, 6, Eigen::Dynamic> Bv = B.middleRows<6>(6 * w.virtualBody);
    const Eigen::Matrix<double, 6, Eigen::Dynamic> nodeRigid = WP.transpose() * K.topRightCorner<6, 6>() * Bv;
    const Eigen::Matrix<double, Eigen::Dynamic, 6> rigidNode = Bv.transpose() * K.bottomLeftCorner<6, 6>() * WP;
    for (int k = 0; k < 6; ++k) {
      if (node.dof[k] < 0) continue;
      for (int l2 = 0; l2 < 6; ++l2)
        if (node.dof[l2] >= 0) iteration.emplace_back(node.dof[k], node.dof[l2], cK * nodeNode(k, l2));
      for (int col : supportColumns_[w.virtualBody]) {
        iteration.emplace_back(node.dof[k], col, cK * nodeRigid(k, col));
        iteration.emplace_back(col, node.dof[k], cK * rigidNode(col, k));
      }
    }
  }
}

// gamma = Phi_Z (Bdot qdot) + (Phidot_Z Y): the bias accelerations of the
// forward loop at qddot = 0, plus the constraints' own velocity terms.
VectorXd System::constraintAccelerationTerm(double t, const Configuration& q, const VectorXd& v) {
  VectorXd gamma = VectorXd::Zero(model_.constraintCount);
  forwardKinematics(model_, data_, q, v, VectorXd::Zero(model_.velocityCount));
  for (const Joint& j : model_.joints) {
    // A rate input is held over the step: no acceleration.
    if (j.driven && !j.driveRateInput) gamma[j.constraintOffset] = -j.drive.acceleration(t);
    if (!j.cut) continue;
    const int parent = j.parentMarker.body, child = j.childMarker.body;
    const JointConstraint jc = constraintOf(j);
    const ConstraintEvaluation c = evaluateJointConstraint(jc, poseOf(data_, parent), poseOf(data_, child));
    auto bias = [&](int b) {
      Vec6 a = Vec6::Zero();
      if (b != kGroundIndex) a << data_.body[b].acceleration, data_.body[b].angularAcceleration;
      return a;
    };
    gamma.segment(j.constraintOffset, c.phi.size()) =
        c.jacobianChild * bias(child) + c.jacobianParent * bias(parent) +
        mfbd::constraintAccelerationTerm(jc, poseOf(data_, parent), twistOf(data_, parent), poseOf(data_, child),
                                    twistOf(data_, child));
  }
  if (!model_.flexibleBodyJoints.empty()) {
    // Node accelerations at vdot = 0: those of driven supports.
    flexibleNodeStates(model_.flexible, q, v, VectorXd::Zero(model_.velocityCount), t, drives_, flexibleInputs_,
                       nodes_);
    for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
      const NodeState& n = nodes_[w.node];
      const BodyPose nodePose = poseOfNode(n), bodyPose = poseOf(data_, w.virtualBody);
      const ConstraintEvaluation c = evaluateJointConstraint(w.weld, nodePose, bodyPose);
      const BodyKinematics& b = data_.body[w.virtualBody];
      Vec6 nodeBias, bodyBias;
      nodeBias << n.acceleration.a, n.pose.A * n.acceleration.omegaDot;
      bodyBias << b.acceleration, b.angularAcceleration;
      gamma.segment<6>(w.constraintOffset) =
          c.jacobianParent * nodeBias + c.jacobianChild * bodyBias +
          mfbd::constraintAccelerationTerm(w.weld, nodePose, twistOfNode(n), bodyPose, twistOf(data_, w.virtualBody));
    }
  }
  return gamma;
}

void System::cutJointReaction(int joint, const VectorXd& lambda, Vec3& force, Vec3& torque) const {
  const Joint& j = model_.joints[joint];
  const JointReaction r = constraintReaction(constraintOf(j), poseOf(data_, j.parentMarker.body),
                                             poseOf(data_, j.childMarker.body),
                                             lambda.segment(j.constraintOffset, mfbd::constraintCount(j.type)));
  force = r.force;
  torque = r.torque;
}

void System::flexibleBodyJointReaction(int k, const VectorXd& lambda, Vec3& force, Vec3& torque) const {
  const FlexibleBodyJoint& w = model_.flexibleBodyJoints[k];
  const JointReaction r = constraintReaction(w.weld, poseOfNode(nodes_[w.node]), poseOf(data_, w.virtualBody),
                                             lambda.segment<6>(w.constraintOffset));
  force = r.force;
  torque = r.torque;
}

double System::flexibleBodyJointViolation(int k) const {
  const FlexibleBodyJoint& w = model_.flexibleBodyJoints[k];
  return evaluateJointConstraint(w.weld, poseOfNode(nodes_[w.node]), poseOf(data_, w.virtualBody))
      .phi.cwiseAbs()
      .maxCoeff();
}

void System::evaluate(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                      const VectorXd& lambda) {
  VectorXd r, phi;
  residual(t, q, v, vdot, lambda, r, phi);
}

}  // namespace mfbd
