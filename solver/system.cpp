#include "system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "coupling/joint_constraint.hpp"
#include "rigid/force_elements.hpp"
#include "rigid/joint_motion.hpp"
#include "rigid/recursive_dynamics.hpp"

namespace mfbd {

System::System(Model model)
    : model_(std::move(model)),
      data_(model_) {
  jointSignals_.resize(model_.jointInputCount);
  flexibleSignals_.resize(model_.flexible.inputCount);
  forceSignals_.resize(model_.forceInputCount);
  startDrives(0.0);
  constraints_ = twoMarkerConstraints(model_);
  // Which coordinate block holds each rate (for per-joint perturbations).
  blockOfRate_.assign(model_.velocityCount, -1);
  for (std::size_t k = 0; k < model_.blocks.size(); ++k)
    for (int d = 0; d < model_.blocks[k].size; ++d) blockOfRate_[model_.blocks[k].velocityOffset + d] = int(k);
  jointSpaceSparsity();
  recursiveMatrix_ = chooseRecursiveNewtonMatrix();
  if (recursiveMatrix_) return;  // it has its own tangent, and no turning blocks (below)
  colourRates();
  // Blocks whose translation rates turn with a stored rotation: free nodes
  // (rdot in the world frame) and free joints (ddot in the parent marker
  // frame). Their rotation rates are in the turning frame already, and the
  // constraint rows are in a joint's parent marker frame, so D S D^T with
  // these turns is the Newton matrix of the configuration turned rigidly
  // (turnWithRotations). Not for the recursive form, whose auxiliary
  // body variations are world-frame quantities of every body.
  for (const FlexNode& node : model_.flexible.nodes)
    if (node.free && node.rotation >= 0) turningBlocks_.push_back({node.dof[0], node.rotation});
  for (const Joint& j : model_.joints)
    if (!j.cut && j.type == JointType::Free) turningBlocks_.push_back({j.velocityOffset, j.rotation});
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
  const std::size_t k = std::size_t(&joint - model_.joints.data());
  if (joint.driveRateInput)
    return jointDriveStart_[k] + jointSignals_.integral(joint.inputOffset, jointDriveStepStart_, t);
  if (driveSamples_.size() != model_.joints.size()) driveSamples_.resize(model_.joints.size());
  return joint.drive.jet(t, driveSamples_[k]).value;
}

void System::inputsAt(double t) {
  jointSignals_.evaluate(t);
  forceSignals_.evaluate(t);
  flexibleSignals_.evaluate(t);
}

bool System::stateFits() const {
  const auto fits = [](const InputSignals& s, int n) {
    return s.value.size() == n && s.d1.size() == n && s.d2.size() == n && s.anchor.size() == n;
  };
  return fits(jointSignals_, model_.jointInputCount) && fits(forceSignals_, model_.forceInputCount) &&
         fits(flexibleSignals_, model_.flexible.inputCount) &&
         drives_.startAngle.size() == model_.flexible.drives.size() &&
         jointDriveStart_.size() == model_.joints.size() &&
         std::is_sorted(redundantRows_.begin(), redundantRows_.end()) &&
         std::all_of(redundantRows_.begin(), redundantRows_.end(),
                     [&](int row) { return row >= 0 && row < model_.constraintCount; });
}

void System::retract(Configuration& q, const VectorXd& dq) const { mfbd::retract(model_.blocks, q, dq); }

void System::turnWithRotations(const Configuration& from, const Configuration& to, VectorXd& x,
                               bool transpose) const {
  // turn = R_to R_from^T, applied as two products with a vector.
  for (const TurningBlock& b : turningBlocks_) {
    const Mat3 &RFrom = from.rotations[b.rotation], &RTo = to.rotations[b.rotation];
    auto block = x.segment<3>(b.velocityOffset);
    const Vec3 turned = transpose ? Vec3(RFrom * (RTo.transpose() * block)) : Vec3(RTo * (RFrom.transpose() * block));
    block = turned;
  }
}

void System::turnOverStep(const Configuration& q, const VectorXd& v, double h, VectorXd& x) const {
  for (const TurningBlock& b : turningBlocks_) {
    const Mat3& R = q.rotations[b.rotation];  // R exp(h omega) R^T, applied to the block
    auto block = x.segment<3>(b.velocityOffset);
    const Vec3 turned = R * (expSO3(h * Vec3(v.segment<3>(b.velocityOffset + 3))) * (R.transpose() * block));
    block = turned;
  }
}

void System::endStep(double t) {
  for (std::size_t d = 0; d < drives_.startAngle.size(); ++d)
    drives_.startAngle[d] = drives_.angle(model_.flexible, flexibleSignals_, int(d), t);
  drives_.stepStart = t;
  for (std::size_t k = 0; k < model_.joints.size(); ++k)
    if (model_.joints[k].driveRateInput) jointDriveStart_[k] = driveCoordinate(model_.joints[k], t);
  jointDriveStepStart_ = t;
}

// tau = actuator inputs - viscous joint damping - rotational springs, along each joint's DOFs.
void System::jointForces(const Configuration& q, const VectorXd& v, VectorXd& tau) const {
  tau.setZero(model_.rigidVelocityCount);
  for (const Joint& j : model_.joints) {
    if (j.cut) continue;  // no coordinates of its own (its offsets are not rates)
    auto t = tau.segment(j.velocityOffset, j.dofs);
    t = -(j.damping + j.springDamping) * v.segment(j.velocityOffset, j.dofs);
    if (j.springStiffness != 0.0) t[0] -= j.springStiffness * (q.scalars[j.scalarOffset] - j.springFreeCoordinate);
    if (j.actuated) t += jointSignals_.current().segment(j.inputOffset, j.dofs);
  }
}

// Joint-space residual B^T (M Ydot - Q + Phi_Z^T lambda) - tau: the
// constraints' forces -Phi_Z^T lambda enter the backward loop as applied
// wrenches; their node sides go into nodeRows when given.
void System::rigidResidual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                           const VectorXd& lambda, VectorXd& r, VectorXd& phi, VectorXd* nodeRows) {
  forwardKinematics(model_, data_, q, v, vdot);
  for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
    data_.appliedForce[i] = model_.bodies[i].mass * model_.gravity;
    data_.appliedTorque[i].setZero();
  }
  applyForceElements(model_.forces, forceSignals_.current(), t, data_);
  phi.setZero(model_.constraintCount);
  constraintLengthScale_ = 1.0;
  twoMarkerRowsAndForces(lambda, phi, nodeRows);
  jointForces(q, v, tau_);
  backwardNewtonEuler(model_, data_, tau_, r);
  driveRowsAndForces(t, q, lambda, phi, r);
}

// Composite rigid bodies and a dense Cholesky factor (Featherstone 2008,
// ch. 6): for a small tree with neither constraints nor flexible bodies a
// stage of an explicit method needs M^-1 Q alone, which the sparse
// iteration matrix (assembled as triplets, a second forward pass, a sparse
// LU) computes at several times the cost. The residual at vdot = 0 is -Q,
// and leaves the forward pass at q in data_ for the mass matrix.
bool System::unconstrainedAccelerations(double t, const Configuration& q, const VectorXd& v, VectorXd& vdot) {
  constexpr int kDenseTree = 64;  // rates; a longer tree keeps the sparse, recursive form
  const int n = model_.velocityCount;
  if (model_.constraintCount > 0 || !model_.flexible.empty() || n > kDenseTree || n == 0) return false;
  noAccelerations_.setZero(n);
  residual(t, q, v, noAccelerations_, noMultipliers_, vdot, noConstraints_);
  jointSpaceMassMatrix(model_, data_, massMatrix_);
  massFactor_.compute(massMatrix_);
  if (massFactor_.info() != Eigen::Success) return false;
  vdot = massFactor_.solve(-vdot);
  return true;
}

// Node states and the flexible part first, so that the constraints' node
// sides add to it; the tree's part after.
void System::residual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                      const VectorXd& lambda, VectorXd& r, VectorXd& phi) {
  r.setZero(model_.velocityCount);
  inputsAt(t);
  bool failed = false;  // a failed iterate: the step is retried smaller
  if (!model_.flexible.empty()) {
    flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleSignals_, nodes_);
    const bool inertia = model_.analysis == Analysis::Dynamic;
    failed = !flexibleResidual(model_.flexible, nodes_, model_.gravity, flexibleSignals_.current(), t, inertia, r);
  }
  if (model_.bodies.empty()) {
    phi.resize(0);
  } else {  // rigidResidual sizes phi (no reallocation per residual)
    rigidResidual(t, q, v, vdot, lambda, rigid_, phi, &r);
    r.head(model_.rigidVelocityCount) = rigid_;
    redundantViolation_ = leaveOutRedundantRows(phi);
  }
  if (failed) r.setConstant(std::numeric_limits<double>::quiet_NaN());
}

void System::constraintJacobian(double t, const Configuration& q, const VectorXd& v, Triplets& jacobian) {
  inputsAt(t);
  const VectorXd zero = VectorXd::Zero(model_.velocityCount);
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, zero, t, drives_, flexibleSignals_, nodes_);
  if (!model_.bodies.empty()) forwardKinematics(model_, data_, q, v, zero);
  constraintRows(false, jacobian);
}

VectorXd System::velocityConstraints(double t, const Configuration& q, const VectorXd& v) {
  const int n = model_.velocityCount, m = model_.constraintCount;
  VectorXd r, before, after;
  const double dt = 1e-6 * std::max(1.0, std::abs(t));
  residual(t + dt, q, v, VectorXd::Zero(n), VectorXd::Zero(m), r, after);
  residual(t - dt, q, v, VectorXd::Zero(n), VectorXd::Zero(m), r, before);
  VectorXd violation = (after - before) / (2.0 * dt);
  Triplets jacobian;
  constraintJacobian(t, q, v, jacobian);
  for (const auto& e : jacobian) violation[e.row()] += e.value() * v[e.col()];
  // A drive's row from its rate, exactly: the difference above leaves the
  // round-off of its coordinate over dt (1e-9 rad/s at 7 rad), which a
  // velocity projection would put into the driven rate.
  for (const Joint& j : model_.joints)
    if (j.driven)
      violation[j.constraintOffset] =
          v[j.velocityOffset] - (j.driveRateInput ? jointSignals_.at(j.inputOffset, t) : j.drive.rate(t));
  leaveOutRedundantRows(violation);
  return violation;
}

void System::tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                     const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                     Triplets& constraintJacobian) {
  inputsAt(t);
  const bool recursive = auxiliaryCount(cM) > 0;
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleSignals_, nodes_);
  if (recursive)
    recursiveTangent(t, q, v, vdot, lambda, cM, cC, cK, iteration, constraintJacobian);
  else if (!model_.bodies.empty())
    rigidTangent(t, q, v, vdot, lambda, cM, cC, cK, iteration, constraintJacobian);
  else
    constraintRows(false, constraintJacobian);
  if (!model_.flexible.empty()) {
    const bool inertia = model_.analysis == Analysis::Dynamic;
    flexibleTangent(model_.flexible, nodes_, model_.gravity, flexibleSignals_.current(), t, inertia, inertia ? cM : 0.0,
                    inertia ? cC : 0.0, cK, iteration);
  }
  twoMarkerStiffness(lambda, cK, recursive, iteration);
  if (!redundantRows_.empty())
    constraintJacobian.erase(std::remove_if(constraintJacobian.begin(), constraintJacobian.end(),
                                            [&](const Eigen::Triplet<double>& e) {
                                              return std::binary_search(redundantRows_.begin(),
                                                                        redundantRows_.end(), e.row());
                                            }),
                             constraintJacobian.end());
}

// The rigid tree's joint-space tangent differentiates its residual over
// every rate (n + 1 evaluations); the recursive form's costs a few. A beam
// element's tangent costs about 16 of its residuals (internal force and
// consistent inertia with their tangents, 5.9 us, against 0.37 us:
// benchmarks/flexible_phases.cpp), so a mesh's tangent about 16 of the
// mesh's residuals. The larger part is taken for the whole.
bool System::elasticCoordinates() const {
  if (!model_.flexible.nodes.empty() || !model_.forces.empty()) return true;
  for (const Joint& j : model_.joints)
    if (j.springStiffness != 0.0) return true;
  return false;
}

double System::tangentCost() const {
  double rigid = 0.0;
  if (!model_.bodies.empty()) rigid = recursiveMatrix_ ? 3.0 : double(tangentColours_.size() + 1);
  const double flexible = model_.flexible.elements.empty() ? 0.0 : 16.0;
  return std::max({1.0, rigid, flexible});
}

// What outputs read: the node states, and the tree's kinematics and subtree
// wrenches (joint reactions). Not the elements' forces: section forces and
// energies are computed where they are read, for the elements listed.
void System::evaluate(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                      const VectorXd& lambda) {
  VectorXd phi;
  inputsAt(t);
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleSignals_, nodes_);
  if (!model_.bodies.empty()) rigidResidual(t, q, v, vdot, lambda, rigid_, phi);
}

void System::evaluateKinematics(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot) {
  inputsAt(t);
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleSignals_, nodes_);
  if (!model_.bodies.empty()) forwardKinematics(model_, data_, q, v, vdot);
}

}  // namespace mfbd
