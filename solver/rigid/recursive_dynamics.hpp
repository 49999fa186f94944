// The recursive formulation in joint coordinates (docs/design.md 3):
// a forward loop over the tree for poses, velocities Y = B qdot and
// accelerations Ydot = B qddot + Bdot qdot, and a backward loop that
// accumulates each subtree's Newton-Euler wrench, which gives both the
// joint-space equations F = B^T (M Ydot - Q) - tau and the joint reactions.
// Cartesian quantities are world-frame, at each body's centre of mass; the
// paper's body-frame Y differs by the block rotation diag(A^T, A^T), which
// leaves B^T M B and B^T Q unchanged.
#pragma once
#include "model/data.hpp"

namespace mfbd {

// Poses, velocities, accelerations and motion subspaces of every body.
void forwardKinematics(const Model& model, Data& data, const Configuration& q, const VectorXd& v,
                       const VectorXd& vdot);

// Derivatives of a body's acceleration bias (Sdot qdot + Xdot Y_parent:
// Coriolis, centripetal and gyroscopic rate terms, [linear; angular]) with
// respect to its parent's [velocity; angular velocity] and its joint's
// rates, at fixed poses (after forwardKinematics).
struct BiasRateDerivatives {
  Eigen::Matrix<double, 6, 6> parent;  // zero for a body on ground
  Matrix6X rates;                      // 6 x dofs
};
BiasRateDerivatives biasRateDerivatives(const Model& model, const Data& data, const Configuration& q,
                                        const VectorXd& v, int body);

// B from the motion subspaces (after forwardKinematics).
void computeVelocityTransformation(const Model& model, Data& data);

// Backward loop: subtree wrenches and the joint-space residual
// F_j = S_j^T W_j - tau_j (tau: generalized joint forces), after
// forwardKinematics and with data.applied* filled.
void backwardNewtonEuler(const Model& model, Data& data, const VectorXd& jointForces, VectorXd& residual);

// Joint-space mass matrix B^T M B by composite rigid bodies (after
// forwardKinematics), into M (resized).
void jointSpaceMassMatrix(const Model& model, Data& data, Eigen::MatrixXd& M);

// Force and torque that joint k's parent exerts on its child, expressed in the
// child marker frame, torque about the child marker origin (after the
// backward loop).
void jointReaction(const Model& model, const Data& data, int joint, Vec3& force, Vec3& torque);

}  // namespace mfbd
