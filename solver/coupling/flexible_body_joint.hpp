// The flexible body joint (docs/design.md 3): six rows that weld a virtual body to
// a flexible node, Phi^er = 0, written with the fixed joint of the joint
// library: the node is the parent (its marker: the virtual body's design
// frame, fixed in the node frame), the virtual body the child (its marker:
// its own frame). The multipliers are the force and torque passed between
// node and virtual body.
//
// A node's coordinates vary as r <- r + dr, A <- A exp(dtheta) (dtheta in the
// node frame, as the configuration's retraction), the joint library's as
// A <- exp(dphi) A: dphi = A dtheta, so node columns are Phi_node W with
// W = diag(I, A), and node rows of a generalized force are W^T g.
#pragma once
#include <string>

#include "coupling/joint_constraint.hpp"
#include "flex/flexible_mesh.hpp"

namespace mfbd {

struct FlexibleBodyJoint {
  std::string name;
  int virtualBody = -1;  // model body index
  int node = -1;         // mesh node index
  JointConstraint weld;  // fixed type, node -> virtual body
  int constraintOffset = -1;
};

inline BodyPose poseOfNode(const NodeState& s) { return {s.pose.r, s.pose.A}; }

// World-frame twist of a node (its angular velocity is stored in the node frame).
inline BodyTwist twistOfNode(const NodeState& s) { return {s.velocity.v, s.pose.A * s.velocity.omega}; }

// [dr; dphi] (world) = W [dr; dtheta] (node frame).
inline Mat6 nodeVariation(const NodeState& s) {
  Mat6 W = Mat6::Identity();
  W.bottomRightCorner<3, 3>() = s.pose.A;
  return W;
}

}  // namespace mfbd
