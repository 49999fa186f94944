// The two-marker constraints of a System (docs/design.md 3): cut joints
// between two bodies and flexible body joints between a flexible node and
// its virtual body, in one list built once from the Model. Each has the rows
// of the joint library (coupling/joint_constraint.hpp) between its two
// sides; a side is a body of the tree (or ground) or a flexible node, and
// the difference between the two lives here alone:
//
// * a body's pose and twist are those of its centre-of-mass frame (ground:
//   identity, at rest); a 6-vector [dr; dphi] on it is B times the joint
//   rates (joint-space form) or the body's own auxiliary unknowns
//   (recursive form);
// * a node's coordinates vary as r <- r + dr, A <- A exp(dtheta) (dtheta in
//   the node frame, as the configuration's retraction), the joint
//   library's as A <- exp(dphi) A: dphi = A dtheta, so [dr; dphi] = W P
//   times the node's free DOFs, W = diag(I, A), and a generalized force g on
//   the node enters its rows as P^T W^T g.
//
// Internal to the System's files.
#pragma once
#include <vector>

#include "coupling/joint_constraint.hpp"
#include "flex/flexible_mesh.hpp"
#include "model/data.hpp"
#include "model/model.hpp"

namespace mfbd {

// One end of a two-marker constraint.
struct ConstraintSide {
  int body = kGroundIndex;  // a body of the tree, or ground (when node < 0)
  int node = -1;            // a flexible mesh node
  bool onNode() const { return node >= 0; }
  bool isGround() const { return node < 0 && body == kGroundIndex; }  // no variation
};

struct TwoMarkerConstraint {
  JointConstraint joint;         // type and the two markers (parent on `parent`)
  ConstraintSide parent, child;
  int firstRow = 0, rows = 0;    // in Phi and lambda
};

// Cut joints in joint order, then flexible body joints in theirs.
std::vector<TwoMarkerConstraint> twoMarkerConstraints(const Model& model);

// What a side reads: the tree's kinematics and the node states.
struct SideState {
  const Data& data;
  const std::vector<NodeState>& nodes;
};

inline BodyPose poseOf(const SideState& s, const ConstraintSide& side) {
  if (side.onNode()) return {s.nodes[side.node].pose.r, s.nodes[side.node].pose.A};
  if (side.body == kGroundIndex) return {Vec3::Zero(), Mat3::Identity()};
  return {s.data.body[side.body].position, s.data.body[side.body].orientation};
}

// World-frame twist (a node's angular velocity is stored in the node frame).
inline BodyTwist twistOf(const SideState& s, const ConstraintSide& side) {
  if (side.onNode()) {
    const NodeState& n = s.nodes[side.node];
    return {n.velocity.v, n.pose.A * n.velocity.omega};
  }
  if (side.body == kGroundIndex) return {Vec3::Zero(), Vec3::Zero()};
  return {s.data.body[side.body].velocity, s.data.body[side.body].angularVelocity};
}

// [rddot; alpha] (world) of the current accelerations.
inline Vec6 accelerationOf(const SideState& s, const ConstraintSide& side) {
  Vec6 a = Vec6::Zero();
  if (side.onNode()) {
    const NodeState& n = s.nodes[side.node];
    a << n.acceleration.a, n.pose.A * n.acceleration.omegaDot;
  } else if (side.body != kGroundIndex) {
    a << s.data.body[side.body].acceleration, s.data.body[side.body].angularAcceleration;
  }
  return a;
}

// W = diag(I, A): [dr; dphi] (world) = W [dr; dtheta] (node frame).
inline Mat6 nodeVariation(const NodeState& s) {
  Mat6 W = Mat6::Identity();
  W.bottomRightCorner<3, 3>() = s.pose.A;
  return W;
}

// W^T f: a world-frame [force; torque] f as the node's generalized force
// (the torque in the node frame), without forming W.
inline Vec6 nodeVariationTransposeTimes(const NodeState& s, const Vec6& f) {
  Vec6 g;
  g << f.head<3>(), s.pose.A.transpose() * f.tail<3>();
  return g;
}

// How [dr; dphi] on a side varies with the Newton matrix's unknowns:
// [dr; dphi] = map x, x the unknowns; `columns` pairs each unknown that can
// be nonzero with its column of map.
struct SideColumns {
  Eigen::Matrix<double, 6, Eigen::Dynamic> map;
  std::vector<std::pair<int, int>> columns;
};

}  // namespace mfbd
