// The "nodal body" of a flexible mesh (docs/design.md 3): node state and its
// lumped inertia with the gyroscopic term.
//
// Conventions shared by every flex element (binding):
//  * pose: position r (world) and orientation A (node frame -> world);
//  * velocity [rdot (world); omega (node frame)], acceleration
//    [rddot (world); omegadot (node frame)];
//  * increment [dr (world); dtheta (node frame)]: r <- r + dr,
//    A <- A * expSO3(dtheta); generalized forces are ordered
//    [force (world); moment (node frame)], conjugate to that increment.
#pragma once
#include "math/rotation.hpp"

namespace mfbd {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

struct NodePose {
  Vec3 r = Vec3::Zero();
  Mat3 A = Mat3::Identity();
};

struct NodeVelocity {
  Vec3 v = Vec3::Zero();      // rdot, world
  Vec3 omega = Vec3::Zero();  // angular velocity, node frame
};

struct NodeAcceleration {
  Vec3 a = Vec3::Zero();         // rddot, world
  Vec3 omegaDot = Vec3::Zero();  // node frame
};

// Lumped mass m [kg] at the node and rotational inertia J [kg m^2] about the
// node, in the node frame (constant there, so the inertia force does not
// depend on the pose).
struct NodalInertia {
  double m = 0.0;
  Mat3 J = Mat3::Zero();
};

// Inertia force f = [m rddot; J omegadot + omega x (J omega)], the term the
// node adds to the residual M a + g(q, v) + f_int - f_ext = 0, with its
// tangents:
//   M = df/d[rddot; omegadot] = diag(m I, J)            (mass matrix)
//   G = df/d[rdot; omega]     = diag(0, skew(omega) J - skew(J omega))
//                                                      (gyroscopic damping)
// and df/d[dr; dtheta] = 0 (nothing depends on the pose).
struct NodalInertiaForces {
  Vec6 f = Vec6::Zero();
  Mat6 M = Mat6::Zero();
  Mat6 G = Mat6::Zero();
};

NodalInertiaForces nodalInertiaForces(const NodalInertia& inertia,
                                      const NodeVelocity& velocity,
                                      const NodeAcceleration& acceleration);

// The force f alone (residual evaluations need no tangents).
Vec6 nodalInertiaForce(const NodalInertia& inertia, const NodeVelocity& velocity,
                       const NodeAcceleration& acceleration);

// Weight of the nodal body as an applied generalized force [m g; 0]
// (g in world, the node is its own centre of mass).
Vec6 nodalGravityForce(const NodalInertia& inertia, const Vec3& gravity);

}  // namespace mfbd
