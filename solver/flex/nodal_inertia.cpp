#include "flex/nodal_inertia.hpp"

namespace mfbd {

Vec6 nodalInertiaForce(const NodalInertia& inertia, const NodeVelocity& velocity,
                       const NodeAcceleration& acceleration) {
  const Vec3& w = velocity.omega;
  Vec6 f;
  // Euler's equations in the body (node) frame: J wdot + w x J w.
  f.head<3>() = inertia.m * acceleration.a;
  f.tail<3>() = inertia.J * acceleration.omegaDot + w.cross(inertia.J * w);
  return f;
}

NodalInertiaForces nodalInertiaForces(const NodalInertia& inertia,
                                      const NodeVelocity& velocity,
                                      const NodeAcceleration& acceleration) {
  const Vec3& w = velocity.omega;
  const Vec3 Jw = inertia.J * w;
  NodalInertiaForces out;
  out.f = nodalInertiaForce(inertia, velocity, acceleration);
  out.M.topLeftCorner<3, 3>() = inertia.m * Mat3::Identity();
  out.M.bottomRightCorner<3, 3>() = inertia.J;
  // d(w x J w)/dw = skew(w) J - skew(J w)
  out.G.bottomRightCorner<3, 3>() = skew(w) * inertia.J - skew(Jw);
  return out;
}

Vec6 nodalGravityForce(const NodalInertia& inertia, const Vec3& gravity) {
  Vec6 f = Vec6::Zero();
  f.head<3>() = inertia.m * gravity;
  return f;
}

}  // namespace mfbd
