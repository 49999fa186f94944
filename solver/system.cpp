#include "system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "coupling/joint_constraint.hpp"
#include "rigid/force_elements.hpp"
#include "rigid/joint_motion.hpp"
#include "rigid/recursive_dynamics.hpp"
#include "system_poses.hpp"

namespace mfbd {

System::System(Model model)
    : model_(std::move(model)),
      data_(model_),
      jointInputs_(VectorXd::Zero(model_.jointInputCount)),
      flexibleInputs_(VectorXd::Zero(model_.flexible.inputCount)),
      forceInputs_(VectorXd::Zero(model_.forceInputCount)) {
  jointSignals_.resize(model_.jointInputCount);
  flexibleSignals_.resize(model_.flexible.inputCount);
  forceSignals_.resize(model_.forceInputCount);
  startDrives(0.0);
  // Which coordinate block holds each rate (for per-joint perturbations).
  blockOfRate_.assign(model_.velocityCount, -1);
  for (std::size_t k = 0; k < model_.blocks.size(); ++k)
    for (int d = 0; d < model_.blocks[k].size; ++d) blockOfRate_[model_.blocks[k].velocityOffset + d] = int(k);
  // A body moves with the rates of the joints on its path to ground.
  const int n = model_.rigidVelocityCount;
  std::vector<int> bodyOfColumn(n, kGroundIndex);
  supportColumns_.resize(model_.bodies.size());
  weldOnNodes_.assign(model_.flexibleBodyJoints.size(), Vec6::Zero());
  for (int b = 0; b < int(model_.bodies.size()); ++b) {
    for (int at = b; at != kGroundIndex; at = model_.bodies[at].parent) {
      const Joint& j = model_.joints[model_.bodies[at].inboardJoint];
      for (int d = 0; d < j.dofs; ++d) supportColumns_[b].push_back(j.velocityOffset + d);
    }
    const Joint& own = model_.joints[model_.bodies[b].inboardJoint];
    for (int d = 0; d < own.dofs; ++d) bodyOfColumn[own.velocityOffset + d] = b;
  }
  // Two rates couple in the tree's tangent (mass, and the derivatives of the
  // joint-space forces) when one joint is outboard of the other: the forces
  // on a subtree depend on the poses of that subtree and its path to ground.
  // A cut joint or a force element between bodies a and b couples, besides,
  // every pair of the rates that move a or b: its force depends on both
  // poses and lands on both paths to ground (R3's 40 loops: a band of three
  // rates, not the dense 81 x 81 of all pairs).
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
  for (const Joint& j : model_.joints)
    if (j.cut) coupleSupports(j.parentMarker.body, j.childMarker.body);
  for (const ForceElement& f : model_.forces)
    if (f.kind != ForceElement::Kind::AppliedForce) coupleSupports(f.marker1.body, f.marker2.body);
  // The joint-space tangent costs a residual per rate and a factorization
  // of its pattern: the recursive form pays off once that pattern holds
  // about a dense block of kRecursiveNewtonMatrixRates rates (a chain of
  // that length). Not automatically with cut joints: their multipliers
  // couple every body between the loop's ends in the elimination (R3's
  // 40 loops, 0.6 s at h = 5e-3: 41 ms against 6.8 ms in joint space).
  using Form = SolverOptions::NewtonMatrix;
  bool cutJoints = false;
  for (const Joint& j : model_.joints) cutJoints = cutJoints || j.cut;
  const int coupled = int(ratesCoupled_.count());
  const int dense = SolverOptions::kRecursiveNewtonMatrixRates * SolverOptions::kRecursiveNewtonMatrixRates;
  recursiveMatrix_ = model_.analysis == Analysis::Dynamic && !model_.bodies.empty() &&
                     (model_.solver.newtonMatrix == Form::Recursive ||
                      (model_.solver.newtonMatrix == Form::Automatic && !cutJoints && coupled >= dense));
  // Rates that no row shares go into one finite-difference column of the
  // tangent together (Curtis, Powell & Reid 1974): greedy colouring, each
  // rate the first colour that none of the rates sharing a row with it has.
  // (The recursive form has its own tangent.)
  std::vector<int> colourOf(n, -1);
  std::vector<char> taken;
  for (int k = 0; k < n && !recursiveMatrix_; ++k) {
    taken.assign(n, 0);
    for (int row = 0; row < n; ++row)
      if (ratesCoupled_(row, k))
        for (int other = 0; other < k; ++other)
          if (ratesCoupled_(row, other)) taken[colourOf[other]] = 1;
    colourOf[k] = int(std::find(taken.begin(), taken.end(), 0) - taken.begin());
    if (colourOf[k] >= int(tangentColours_.size())) tangentColours_.resize(colourOf[k] + 1);
    tangentColours_[colourOf[k]].push_back(k);
  }
  // Blocks whose translation rates turn with a stored rotation: free nodes
  // (rdot in the world frame) and free joints (ddot in the parent marker
  // frame). Their rotation rates are in the turning frame already, and the
  // constraint rows are in a joint's parent marker frame, so D S D^T with
  // these turns is the Newton matrix of the configuration turned rigidly
  // (turnWithRotations). Not for the recursive form, whose auxiliary
  // body variations are world-frame quantities of every body.
  if (!recursiveMatrix_) {
    for (const FlexNode& node : model_.flexible.nodes)
      if (node.free && node.rotation >= 0) turningBlocks_.push_back({node.dof[0], node.rotation});
    for (const Joint& j : model_.joints)
      if (!j.cut && j.type == JointType::Free) turningBlocks_.push_back({j.velocityOffset, j.rotation});
  }
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
  return jointDriveStart_[&joint - model_.joints.data()] +
         jointSignals_.integral(joint.inputOffset, jointDriveStepStart_, t);
}

void System::inputsAt(double t) {
  jointSignals_.evaluate(t, jointInputs_);
  forceSignals_.evaluate(t, forceInputs_);
  flexibleSignals_.evaluate(t, flexibleInputs_);
}

bool System::stateFits() const {
  const auto fits = [](const InputSignals& s, int n) {
    return s.value.size() == n && s.d1.size() == n && s.d2.size() == n && s.anchor.size() == n;
  };
  return fits(jointSignals_, model_.jointInputCount) && fits(forceSignals_, model_.forceInputCount) &&
         fits(flexibleSignals_, model_.flexible.inputCount) &&
         drives_.startAngle.size() == model_.flexible.drives.size() &&
         jointDriveStart_.size() == model_.joints.size();
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
    if (j.actuated) t += jointInputs_.segment(j.inputOffset, j.dofs);
  }
}

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
    weldOnNodes_[&w - model_.flexibleBodyJoints.data()] =
        c.jacobianParent.transpose() * lambda.segment<6>(w.constraintOffset);
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
  inputsAt(t);
  nodesAndTree(t, q, v, vdot, lambda, phi);
  if (!model_.bodies.empty()) r.head(model_.rigidVelocityCount) = rigid_;
  if (!model_.flexible.empty()) {
    const bool inertia = model_.analysis == Analysis::Dynamic;
    if (!flexibleResidual(model_.flexible, nodes_, model_.gravity, flexibleInputs_, t, inertia, r))
      r.setConstant(std::numeric_limits<double>::quiet_NaN());  // a failed iterate: the step is retried smaller
    if (lambda.size() > 0) weldForcesOnNodes(r);
  }
}

// Node rows of the flexible body joints' forces: W^T Phi_node^T lambda,
// Phi_node^T lambda from the residual of the tree (weldOnNodes_).
void System::weldForcesOnNodes(VectorXd& r) const {
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
    const NodeState& n = nodes_[w.node];
    const Vec6 g = nodeVariation(n).transpose() * weldOnNodes_[&w - model_.flexibleBodyJoints.data()];
    const FlexNode& node = model_.flexible.nodes[w.node];
    for (int k = 0; k < 6; ++k)
      if (node.dof[k] >= 0) r[node.dof[k]] += node.P.col(k).dot(g);
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
  Eigen::MatrixXd S = cM * jointSpaceMassMatrix(model_, data_);
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

// Constraint rows: drives on their joint rates; cut joints and flexible body
// joints over the bodies they join, Phi_Z, either mapped to the joint rates
// that move those bodies (Phi_q = Phi_Z B: joint-space form) or over the
// auxiliary body-level unknowns (bodyColumns: the recursive form); node
// columns Phi_node W P. After forwardKinematics, with nodes_ current.
void System::constraintRows(bool bodyColumns, Triplets& constraintJacobian) {
  if (!bodyColumns && model_.constraintCount > 0) computeVelocityTransformation(model_, data_);
  const Eigen::MatrixXd& B = data_.velocityTransformation;
  // Rows of Phi_b [dr_b; dphi_b] for a body b.
  auto bodyBlock = [&](int row, int body, const ConstraintJacobian& J) {
    if (body == kGroundIndex) return;
    if (bodyColumns) {
      for (int c = 0; c < 6; ++c)
        for (int i = 0; i < J.rows(); ++i) constraintJacobian.emplace_back(row + i, bodyUnknown(body) + c, J(i, c));
      return;
    }
    const Eigen::MatrixXd rows = J * B.middleRows<6>(6 * body);
    for (int col : supportColumns_[body])
      for (int i = 0; i < J.rows(); ++i) constraintJacobian.emplace_back(row + i, col, rows(i, col));
  };
  for (const Joint& j : model_.joints) {
    if (j.driven) constraintJacobian.emplace_back(j.constraintOffset, j.velocityOffset, 1.0);
    if (!j.cut) continue;
    const int parent = j.parentMarker.body, child = j.childMarker.body;
    const ConstraintEvaluation c = evaluateJointConstraint(constraintOf(j), poseOf(data_, parent), poseOf(data_, child));
    if (bodyColumns || parent == kGroundIndex) {
      bodyBlock(j.constraintOffset, parent, c.jacobianParent);
      bodyBlock(j.constraintOffset, child, c.jacobianChild);
      continue;
    }
    // Joint space: the two bodies' rows summed over the rates that move them.
    const Eigen::MatrixXd rows = c.jacobianChild * B.middleRows<6>(6 * child) + c.jacobianParent * B.middleRows<6>(6 * parent);
    std::vector<int> columns = supportColumns_[parent];
    columns.insert(columns.end(), supportColumns_[child].begin(), supportColumns_[child].end());
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    for (int col : columns)
      for (int i = 0; i < rows.rows(); ++i) constraintJacobian.emplace_back(j.constraintOffset + i, col, rows(i, col));
  }
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
    const NodeState& n = nodes_[w.node];
    const FlexNode& node = model_.flexible.nodes[w.node];
    const ConstraintEvaluation c = evaluateJointConstraint(w.weld, poseOfNode(n), poseOf(data_, w.virtualBody));
    bodyBlock(w.constraintOffset, w.virtualBody, c.jacobianChild);
    const Mat6 rows = c.jacobianParent * nodeVariation(n) * node.P;
    for (int i = 0; i < 6; ++i)
      for (int k = 0; k < 6; ++k)
        if (node.dof[k] >= 0) constraintJacobian.emplace_back(w.constraintOffset + i, node.dof[k], rows(i, k));
  }
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
    flexibleTangent(model_.flexible, nodes_, model_.gravity, flexibleInputs_, t, inertia, inertia ? cM : 0.0,
                    inertia ? cC : 0.0, cK, iteration);
    weldTangent(lambda, cK, recursive, iteration);
  }
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

// Body-level stiffness and damping of the force elements, -dQ/d(pose) and
// -dQ/d(twist) of each element's wrenches, by finite differences of that
// element alone (6 evaluations per body it touches).
void System::forceElementTangent(double cC, double cK, Triplets& iteration) {
  if (cC == 0.0 && cK == 0.0) return;
  const double eps = 1e-7;
  for (const ForceElement& e : model_.forces) {
    const int ends[2] = {e.marker1.body, e.kind == ForceElement::Kind::AppliedForce ? kGroundIndex : e.marker2.body};
    const ForceElementWrenches w0 = forceElementWrenches(e, forceInputs_, data_);
    for (int side = 0; side < 2; ++side) {
      const int moved = ends[side];
      if (moved == kGroundIndex) continue;
      BodyKinematics& k = data_.body[moved];
      const BodyKinematics saved = k;
      for (int d = 0; d < 6; ++d) {
        // Pose by eps e_d and twist by (cC/cK) eps e_d: the difference
        // quotient is K e_d + (cC/cK) C e_d (the twist alone when cK = 0).
        const double twist = cK != 0.0 ? cC / cK * eps : eps;
        if (cK != 0.0) {
          if (d < 3) k.position[d] += eps;
          else k.orientation = expSO3(eps * Vec3::Unit(d - 3)) * k.orientation;
        }
        if (d < 3) k.velocity[d] += twist;
        else k.angularVelocity[d - 3] += twist;
        const ForceElementWrenches w1 = forceElementWrenches(e, forceInputs_, data_);
        k = saved;
        const double factor = -(cK != 0.0 ? cK : cC) / eps;
        for (int on = 0; on < 2; ++on) {
          if (ends[on] == kGroundIndex) continue;
          const Vec6 dw = on == 0 ? Vec6(w1.onBody1 - w0.onBody1) : Vec6(w1.onBody2 - w0.onBody2);
          for (int i = 0; i < 6; ++i) iteration.emplace_back(bodyUnknown(ends[on]) + i, bodyUnknown(moved) + d, factor * dw[i]);
        }
      }
    }
  }
}

// The flexible body joints' geometric stiffness K = d(Phi_z^T lambda)/dz
// between node and virtual body: node-node, mapped by W P, plus the turning
// of the node frame in W^T: d(A^T N)/dtheta = skew(A^T N); node-body and
// body-node blocks over the virtual body's joint rates (B) or, in the
// recursive form, over its body-level unknowns, where the body-body block
// joins them (the joint-space finite differences of the rigid residual
// hold that one already).
void System::weldTangent(const VectorXd& lambda, double cK, bool bodyColumns, Triplets& iteration) const {
  if (cK == 0.0 || lambda.size() == 0) return;
  const Eigen::MatrixXd& B = data_.velocityTransformation;  // current: rigidTangent computed it
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) {
    const NodeState& n = nodes_[w.node];
    const FlexNode& node = model_.flexible.nodes[w.node];
    const BodyPose nodePose = poseOfNode(n), bodyPose = poseOf(data_, w.virtualBody);
    const ConstraintEvaluation c = evaluateJointConstraint(w.weld, nodePose, bodyPose);
    const Mat6 WP = nodeVariation(n) * node.P;
    const auto l = lambda.segment<6>(w.constraintOffset);
    const GeometricStiffness K = constraintGeometricStiffness(w.weld, nodePose, bodyPose, l);
    Mat6 nodeNode = WP.transpose() * K.topLeftCorner<6, 6>() * WP;
    const Vec3 moment = n.pose.A.transpose() * (c.jacobianParent.transpose() * l).tail<3>();
    nodeNode += node.P.transpose().rightCols<3>() * skew(moment) * node.P.bottomRows<3>();
    for (int k = 0; k < 6; ++k)
      for (int l2 = 0; l2 < 6; ++l2)
        if (node.dof[k] >= 0 && node.dof[l2] >= 0)
          iteration.emplace_back(node.dof[k], node.dof[l2], cK * nodeNode(k, l2));
    if (bodyColumns) {
      const Mat6 nodeBody = WP.transpose() * K.topRightCorner<6, 6>(), bodyNode = K.bottomLeftCorner<6, 6>() * WP;
      const int y = bodyUnknown(w.virtualBody);
      for (int k = 0; k < 6; ++k)
        for (int c2 = 0; c2 < 6; ++c2) {
          if (node.dof[k] >= 0) {
            iteration.emplace_back(node.dof[k], y + c2, cK * nodeBody(k, c2));
            iteration.emplace_back(y + c2, node.dof[k], cK * bodyNode(c2, k));
          }
          iteration.emplace_back(y + k, y + c2, cK * K(6 + k, 6 + c2));
        }
      continue;
    }
    const Eigen::Matrix<double, 6, Eigen::Dynamic> Bv = B.middleRows<6>(6 * w.virtualBody);
    const Eigen::Matrix<double, 6, Eigen::Dynamic> nodeRigid = WP.transpose() * K.topRightCorner<6, 6>() * Bv;
    const Eigen::Matrix<double, Eigen::Dynamic, 6> rigidNode = Bv.transpose() * K.bottomLeftCorner<6, 6>() * WP;
    for (int k = 0; k < 6; ++k) {
      if (node.dof[k] < 0) continue;
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
  inputsAt(t);
  forwardKinematics(model_, data_, q, v, VectorXd::Zero(model_.velocityCount));
  for (const Joint& j : model_.joints) {
    // A rate input held over the step has no acceleration; an interpolated
    // one has its derivative.
    if (j.driven && !j.driveRateInput) gamma[j.constraintOffset] = -j.drive.acceleration(t);
    if (j.driven && j.driveRateInput && jointSignals_.moving)
      gamma[j.constraintOffset] = -jointSignals_.rate(j.inputOffset, t);
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
    flexibleNodeStates(model_.flexible, q, v, VectorXd::Zero(model_.velocityCount), t, drives_, flexibleSignals_,
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

// What outputs read: the node states, and the tree's kinematics and subtree
// wrenches (joint reactions). Not the elements' forces: section forces and
// energies are computed where they are read, for the elements listed.
void System::evaluate(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                      const VectorXd& lambda) {
  VectorXd phi;
  inputsAt(t);
  nodesAndTree(t, q, v, vdot, lambda, phi);
}

void System::evaluateKinematics(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot) {
  inputsAt(t);
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleSignals_, nodes_);
  if (!model_.bodies.empty()) forwardKinematics(model_, data_, q, v, vdot);
}

// Node states, then the tree's residual into rigid_ and the constraints into
// phi (nodes first: the flexible body joints of the rigid part read them).
void System::nodesAndTree(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                          const VectorXd& lambda, VectorXd& phi) {
  phi.resize(0);
  if (!model_.flexible.empty()) flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleSignals_, nodes_);
  if (!model_.bodies.empty()) rigidResidual(t, q, v, vdot, lambda, rigid_, phi);
}

}  // namespace mfbd
