// Assembly of the mechanism at initialization (Simulation::initialize):
// closed loops and drives met by least-change projection of positions and
// velocities (kept rates held), the flexible bodies that hang from links
// the initial coordinates moved carried with them, and the names of the
// constraint rows for messages.
#include <algorithm>
#include <limits>

#include <Eigen/QR>

#include "integrator/constraint_rank.hpp"
#include "math/number_text.hpp"
#include "rigid/recursive_dynamics.hpp"
#include "simulation.hpp"

namespace mfbd {

std::string Simulation::constraintOwner(int row) const {
  for (const Joint& j : system_.model().joints)
    if (j.constraintOffset >= 0 && row >= j.constraintOffset &&
        row < j.constraintOffset + (j.driven ? 1 : constraintCount(j.type)))
      return std::string(j.driven ? "drive of joint '" : "cut joint '") + j.name + "'";
  for (const FlexibleBodyJoint& w : system_.model().flexibleBodyJoints)
    if (row >= w.constraintOffset && row < w.constraintOffset + 6) return "flexible body joint '" + w.name + "'";
  return "constraint row " + std::to_string(row);
}

Eigen::MatrixXd Simulation::constraintJacobian(const Configuration& q, const VectorXd& v) {
  const int n = system_.velocityCount(), m = system_.constraintCount();
  Triplets G;
  system_.constraintJacobian(state_.t, q, v, G);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, n);
  for (const auto& e : G) J(e.row(), e.col()) += e.value();
  return J;
}

// The owners of constraint rows, each named once: "cut joint 'a', drive of
// joint 'b' and 3 more".
std::string Simulation::constraintOwners(const std::vector<int>& rows) const {
  std::vector<std::string> names;
  for (int row : rows) {
    const std::string name = constraintOwner(row);
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  std::string text;
  const std::size_t shown = std::min<std::size_t>(names.size(), 3);
  for (std::size_t i = 0; i < shown; ++i) text += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  if (names.size() > shown) text += " and " + std::to_string(names.size() - shown) + " more";
  return text;
}

// Redundant constraint rows, in joint names: rows that constrain nothing
// (`vanishing`: a planar loop in 3-D) and rows that are combinations of
// others (Bricard; two drives of one motion).
std::string Simulation::redundantConstraints(const ConstraintRank& rank, bool vanishing) {
  std::string text;
  if (vanishing && !rank.vanishingRows.empty())
    text += std::to_string(rank.vanishingRows.size()) + " rows constrain nothing here (of " +
            constraintOwners(rank.vanishingRows) + ")";
  for (const std::vector<int>& set : rank.dependentRows) {
    if (!text.empty()) text += "; ";
    text += "a row of " + constraintOwner(set.front()) + " depends on " +
            constraintOwners(std::vector<int>(set.begin() + 1, set.end()));
    if (&set - rank.dependentRows.data() == 2 && rank.dependentRows.size() > 3) {
      text += "; " + std::to_string(rank.dependentRows.size() - 3) + " more dependent rows";
      break;
    }
  }
  return text;
}

// Least-change projection: q <- q o exp(-J^T (J J^T)^-1 Phi) until Phi = 0,
// then v <- v - J^T (J J^T)^-1 (J v + Phi_t). J J^T gets a tiny ridge so
// redundant rows (a planar loop in 3D) do not make it singular.
bool Simulation::assembleConstraints(std::string& message, std::vector<std::string>* notes) {
  const int n = system_.velocityCount(), m = system_.constraintCount();
  if (m == 0) return true;
  const double tol = scene_.solver.tolerance;
  auto jacobian = [&](const Configuration& q, const VectorXd& v) { return constraintJacobian(q, v); };
  auto constraints = [&](const Configuration& q, double t) {
    VectorXd r, phi;
    system_.residual(t, q, state_.v, VectorXd::Zero(n), VectorXd::Zero(m), r, phi);
    return phi;
  };
  auto leastChange = [&](const Eigen::MatrixXd& J, const VectorXd& rhs) {
    Eigen::MatrixXd JJt = J * J.transpose();
    JJt.diagonal().array() += 1e-12 * std::max(1.0, JJt.diagonal().maxCoeff());
    return VectorXd(J.transpose() * JJt.ldlt().solve(rhs));
  };
  const Configuration start = state_.q;
  VectorXd phi = constraints(state_.q, state_.t);
  // The rows are met to the tolerance or to their round-off (a few ulps of
  // the positions they are computed from), whichever is larger, as in a
  // substep: a tolerance below round-off cannot be met.
  auto met = [&] {
    const double phiFloor = 64.0 * std::numeric_limits<double>::epsilon() * system_.constraintLengthScale();
    return phi.cwiseAbs().maxCoeff() <= std::max(tol, phiFloor);
  };
  for (int k = 0; k < 50 && !met(); ++k) {
    system_.retract(state_.q, -leastChange(jacobian(state_.q, state_.v), phi));
    phi = constraints(state_.q, state_.t);
  }
  int worst;
  if (!met()) {
    phi.cwiseAbs().maxCoeff(&worst);
    message = "cannot assemble the mechanism: " + constraintOwner(worst) + " is violated by " +
              numberText(std::abs(phi[worst])) + " after projection (is the loop closable?)";
    return false;
  }
  // Velocities: the least change of the rates the scene does not keep
  // (initial.keep_rates): their columns alone enter the projection.
  Eigen::MatrixXd J = jacobian(state_.q, state_.v);
  std::vector<std::string> kept;
  for (const Joint& j : system_.model().joints)
    if (j.keepRates && !j.cut) {
      J.middleCols(j.velocityOffset, j.dofs).setZero();
      kept.push_back("'" + j.name + "'");
    }
  const VectorXd dv = -leastChange(J, system_.velocityConstraints(state_.t, state_.q, state_.v));
  state_.v += dv;
  const VectorXd left = system_.velocityConstraints(state_.t, state_.q, state_.v);
  if (!kept.empty() && left.cwiseAbs().maxCoeff(&worst) > std::max(tol, 1e-9 * std::max(1.0, state_.v.norm()))) {
    std::string joints = kept.front();
    for (std::size_t i = 1; i < kept.size(); ++i) joints += ", " + kept[i];
    message = "cannot keep the initial rates of joint " + joints + " (initial.keep_rates): the velocity constraint of " +
              constraintOwner(worst) + " is then violated by " + numberText(std::abs(left[worst])) +
              "; keep fewer rates, or rates the constraints allow";
    return false;
  }
  warnGivenRatesChanged(dv);
  if (notes) {
    for (const Joint& j : system_.model().joints) {
      if (j.cut || j.dofs == 0 || j.scalarOffset < 0) continue;
      const double moved = (state_.q.scalars - start.scalars).segment(j.scalarOffset, j.rotation >= 0 ? j.dofs - 3 : j.dofs)
                               .cwiseAbs().maxCoeff();
      const double rate = dv.segment(j.velocityOffset, j.dofs).cwiseAbs().maxCoeff();
      if (moved > tol || rate > tol)
        notes->push_back("assembly moved joint '" + j.name + "' by " + numberText(moved) +
                         " and its rate by " + numberText(rate));
    }
  }
  return true;
}

// Rates the scene gave (initial.rates) that the velocity projection changed:
// the user meant them, so the change is a warning, not a note.
void Simulation::warnGivenRatesChanged(const VectorXd& dv) {
  const double tol = std::max(scene_.solver.tolerance, 1e-9 * std::max(1.0, state_.v.lpNorm<Eigen::Infinity>()));
  for (const JointSpec& spec : scene_.joints) {
    if (spec.initialRates.empty() || spec.keepRates) continue;
    for (const Joint& j : system_.model().joints) {
      if (j.name != spec.name || j.cut || j.dofs == 0) continue;
      const VectorXd change = dv.segment(j.velocityOffset, j.dofs);
      if (change.lpNorm<Eigen::Infinity>() <= tol) continue;
      std::string now;
      for (int k = 0; k < j.dofs; ++k)
        now += (k ? ", " : "") + numberText(state_.v[j.velocityOffset + k]);
      warnings_.push_back("the assembly changed the initial rates of joint '" + j.name + "' (initial.rates) by " +
                          numberText(change.lpNorm<Eigen::Infinity>()) + " to [" + now +
                          "], the least change that meets the velocity constraints; set initial.keep_rates to "
                          "keep them and adjust the other joints");
    }
  }
}

namespace {

std::size_t flexibleBodyOf(const FlexibleMesh& mesh, int node) {
  std::size_t f = 0;
  while (node >= mesh.bodies[f].firstNode + mesh.bodies[f].nodeCount) ++f;
  return f;
}

// A virtual body that only its weld holds (a free joint to ground).
bool heldByWeldOnly(const Model& model, const FlexibleBodyJoint& w) {
  const Joint& inboard = model.joints[model.bodies[w.virtualBody].inboardJoint];
  return inboard.type == JointType::Free && inboard.parentMarker.body == kGroundIndex;
}

// Whether body b hangs (through the tree) below a virtual body held only by
// its weld to a flexible body not carried yet: it moves when that one does.
bool waitsForCarry(const Model& model, int b, const std::vector<bool>& carried) {
  for (; b != kGroundIndex; b = model.joints[model.bodies[b].inboardJoint].parentMarker.body)
    for (const FlexibleBodyJoint& w : model.flexibleBodyJoints)
      if (w.virtualBody == b && heldByWeldOnly(model, w) && !carried[flexibleBodyOf(model.flexible, w.node)])
        return true;
  return false;
}

}  // namespace

// A joint's initial coordinates move the links after it; a flexible body
// that hangs from such a link (welded to a virtual body the tree carries)
// moves with it, rigidly: nodes turned and shifted as the virtual body
// is, their velocities those of points of it. Without that the body
// starts stretched between its design place and the moved link (a rod
// under a link raised by 0.6 rad: 2.4e6 J of strain energy). Bodies with
// supports stay where the scene puts them; a flexible body moves with the
// first such link it hangs from. The carry goes on down: the virtual
// bodies held only by their welds to a carried body's nodes move with it,
// and with them what hangs from them (a payload, another flexible body).
void Simulation::carryFlexibleBodies() {
  const Model& model = system_.model();
  if (model.flexible.bodies.empty() || model.flexibleBodyJoints.empty()) return;
  const int n = system_.velocityCount();
  Configuration design = state_.q;
  for (const Joint& j : model.joints) {
    if (j.cut || j.dofs == 0 || j.scalarOffset < 0) continue;
    design.scalars.segment(j.scalarOffset, j.rotation >= 0 ? j.dofs - 3 : j.dofs).setZero();
    if (j.rotation >= 0) design.rotations[j.rotation] = Mat3::Identity();
  }
  system_.evaluateKinematics(state_.t, design, VectorXd::Zero(n), VectorXd::Zero(n));
  const std::vector<BodyKinematics> before = system_.data().body;
  std::vector<bool> carried(model.flexible.bodies.size(), false);
  while (carryOneFlexibleBody(before, carried)) {
  }
}

// Carries the first flexible body not yet carried that hangs from a link
// whose place is known (see carryFlexibleBodies); false when none is left.
bool Simulation::carryOneFlexibleBody(const std::vector<BodyKinematics>& before, std::vector<bool>& carried) {
  const Model& model = system_.model();
  const FlexibleMesh& mesh = model.flexible;
  const int n = system_.velocityCount();
  system_.evaluateKinematics(state_.t, state_.q, state_.v, VectorXd::Zero(n));
  const std::vector<BodyKinematics> after = system_.data().body;
  for (const FlexibleBodyJoint& w : model.flexibleBodyJoints) {
    const std::size_t f = flexibleBodyOf(mesh, w.node);
    const FlexibleBody& body = mesh.bodies[f];
    bool free = true;
    for (int i = body.firstNode; i < body.firstNode + body.nodeCount; ++i) free = free && mesh.nodes[i].free;
    if (carried[f] || !free || heldByWeldOnly(model, w) || waitsForCarry(model, w.virtualBody, carried)) continue;
    carried[f] = true;
    const BodyKinematics& link = after[w.virtualBody];
    const Mat3 R = link.orientation * before[w.virtualBody].orientation.transpose();
    const Vec3 shift = link.position - R * before[w.virtualBody].position;
    auto pointVelocity = [&](const Vec3& r) { return Vec3(link.velocity + link.angularVelocity.cross(r - link.position)); };
    for (int i = body.firstNode; i < body.firstNode + body.nodeCount; ++i) {
      const FlexNode& node = mesh.nodes[i];
      auto displacement = state_.q.scalars.segment<3>(node.scalarOffset);
      Mat3& A = state_.q.rotations[node.rotation];
      const Vec3 r = R * (node.reference.r + displacement) + shift;
      displacement = r - node.reference.r;
      A = R * A;
      state_.v.segment<3>(node.dof[0]) = pointVelocity(r);
      state_.v.segment<3>(node.dof[3]) = A.transpose() * link.angularVelocity;
    }
    // The free joint (to ground) of each virtual body welded to this body's
    // nodes: from P C^-1 at zero coordinates to (R, shift) P C^-1, so the
    // joint's motion is P^-1 (R, shift) P; its rates [ddot in P; omega in C].
    for (const FlexibleBodyJoint& held : model.flexibleBodyJoints) {
      if (!heldByWeldOnly(model, held) || flexibleBodyOf(mesh, held.node) != f) continue;
      const Joint& j = model.joints[model.bodies[held.virtualBody].inboardJoint];
      const Mat3& P = j.parentMarker.orientation;
      const Vec3& p = j.parentMarker.position;
      const Mat3 Q = P.transpose() * R * P;
      state_.q.rotations[j.rotation] = Q;
      state_.q.scalars.segment<3>(j.scalarOffset) = P.transpose() * (R * p + shift - p);
      state_.v.segment<3>(j.velocityOffset) = P.transpose() * pointVelocity(R * p + shift);  // the marker's origin
      state_.v.segment<3>(j.velocityOffset + 3) = (P * Q).transpose() * link.angularVelocity;
    }
    return true;
  }
  return false;
}

}  // namespace mfbd
