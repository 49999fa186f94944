// The joint library as constraints between two markers, in absolute form
// (docs/design.md 3): cut joints that close loops of the rigid tree, and the 6-DOF
// flexible body joint that welds a virtual body to a flexible node.
//
// A joint connects marker P, fixed in body i (the parent), and marker C, fixed
// in body j (the child). With body poses (r_k, A_k) the marker frames are
//   p = r_i + A_i s_P,  P = A_i C_P        c = r_j + A_j s_C,  Q = A_j C_C.
// The constraint Phi(r_i, A_i, r_j, A_j) = 0 leaves free exactly the relative
// motions of rigid/joint_motion.hpp (revolute/prismatic/cylindrical along the
// marker z axis; planar in x-y turning about z; universal about P's x, then
// about C's y; spherical; fixed; free), and the two marker frames coincide in
// the design configuration. Rows, in this order (p_k, q_k: the columns of P, Q;
// d = P^T (c - p) the relative displacement in the parent marker frame;
// theta = logSO3(P^T Q) the relative rotation vector):
//
//   type         m  rows
//   revolute     5  d_x, d_y, d_z,  -p_y.q_z, p_x.q_z
//   prismatic    5  d_x, d_y,       theta_x, theta_y, theta_z
//   cylindrical  4  d_x, d_y,       -p_y.q_z, p_x.q_z
//   universal    4  d_x, d_y, d_z,  -p_x.q_y
//   spherical    3  d_x, d_y, d_z
//   planar       3  d_z,            -p_y.q_z, p_x.q_z
//   fixed        6  d_x, d_y, d_z,  theta_x, theta_y, theta_z
//   free         0
//
// Translation rows are in metres. Rotation rows are radians: the dot products
// are signed so that, near the design configuration, each equals the small
// relative rotation about the P axis it names (-p_y.q_z ~ theta_x,
// p_x.q_z ~ theta_y, -p_x.q_y ~ theta_z), so both row kinds read alike and
// their multipliers are torques. Every form has a gradient of norm ~1 at the
// design configuration and no singularity within 90 degrees (dot rows) or
// 180 degrees (log rows) of it.
//
// The flexible body joint of docs/design.md 3 is the fixed type with the flexible
// node as parent (P = {0, C_j}) and the virtual body as child (C = {0, I}):
// the same manifold as [r_j - r_j1; theta((A_j C_j)^T A_j1)], its translation
// rows turned into the node's marker frame and taken child minus parent.
//
// Variations and signs (binding for the solver):
// * A pose varies as r <- r + dr, A <- expSO3(dphi) A, dphi a world-frame
//   rotation vector; body velocities are [rdot; omega], omega in world. Each
//   body's 6-vector is [dr; dphi]; the 12-vector of a joint is
//   z = [dr_i; dphi_i; dr_j; dphi_j].
// * dPhi = Phi_i [dr_i; dphi_i] + Phi_j [dr_j; dphi_j] + O(d^2).
// * Ground is body i with r = 0, A = I and no variation: ignore Phi_i.
// * The constraint applies the generalized force -Phi_z^T lambda to the
//   bodies (EOM: M Ydot + Phi_Z^T lambda - Q = 0, docs/design.md 3). Its world
//   force and torque about r_j on body j are -Phi_j^T lambda.
#pragma once
#include <Eigen/Core>

#include "math/rotation.hpp"
#include "scene/scene.hpp"

namespace mfbd {

// A marker frame in its body's frame.
struct MarkerPlacement {
  Vec3 position = Vec3::Zero();
  Mat3 orientation = Mat3::Identity();
};

// A body's pose: world position of its reference point, rotation body -> world.
struct BodyPose {
  Vec3 r = Vec3::Zero();
  Mat3 A = Mat3::Identity();
};

// A body's velocity: of its reference point, and its angular velocity (world).
struct BodyTwist {
  Vec3 v = Vec3::Zero();
  Vec3 omega = Vec3::Zero();
};

struct JointConstraint {
  JointType type = JointType::Fixed;
  MarkerPlacement parentMarker;  // P, on body i
  MarkerPlacement childMarker;   // C, on body j
};

// At most 6 rows: fixed-capacity storage, no heap allocation per evaluation.
using ConstraintVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 6, 1>;
using ConstraintJacobian = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::ColMajor, 6, 6>;
using GeometricStiffness = Eigen::Matrix<double, 12, 12>;

struct ConstraintEvaluation {
  ConstraintVector phi;               // m
  ConstraintJacobian jacobianParent;  // Phi_i, m x 6, columns [dr_i; dphi_i]
  ConstraintJacobian jacobianChild;   // Phi_j, m x 6, columns [dr_j; dphi_j]
};

// The force and torque the joint applies ON the child body, both in marker
// C's frame, the torque about C's origin (FMU output).
struct JointReaction {
  Vec3 force = Vec3::Zero();
  Vec3 torque = Vec3::Zero();
};

// m = 6 - dofs: the number of constraint rows of a joint type.
int constraintCount(JointType type);

ConstraintEvaluation evaluateJointConstraint(const JointConstraint& joint, const BodyPose& parent,
                                             const BodyPose& child);

// gamma with d2/dt2 Phi = Phi_i [rddot_i; alpha_i] + Phi_j [rddot_j; alpha_j]
// + gamma, alpha the world angular accelerations. gamma_k = zdot^T K(e_k) zdot
// with K the geometric stiffness below, zdot = [v_i; omega_i; v_j; omega_j].
ConstraintVector constraintAccelerationTerm(const JointConstraint& joint, const BodyPose& parent,
                                            const BodyTwist& parentTwist, const BodyPose& child,
                                            const BodyTwist& childTwist);

// K = d(Phi_z^T lambda)/dz (12 x 12) for Newton's tangent: column b is the
// derivative of the 12-vector Phi_z^T lambda along the pose variation e_b,
// applied as above. Not symmetric in general (the world-frame rotation
// variations do not commute); K's rows and columns are ordered as z.
GeometricStiffness constraintGeometricStiffness(const JointConstraint& joint, const BodyPose& parent,
                                                const BodyPose& child,
                                                const Eigen::Ref<const Eigen::VectorXd>& lambda);

// The reaction on the child from the multipliers (see the sign convention
// above): [F; N_rj] = -Phi_j^T lambda in world, moved to C's origin and frame.
JointReaction constraintReaction(const JointConstraint& joint, const BodyPose& parent, const BodyPose& child,
                                 const Eigen::Ref<const Eigen::VectorXd>& lambda);

}  // namespace mfbd
