// Consistent mass of a beam element's centre line (DESIGN.md 3 "Flexible
// bodies"): the cubic Hermite interpolation of the Euler-Bernoulli element,
// written in world quantities so that it holds at any rotation.
//
// The centre line between the nodes is interpolated from the nodes'
// positions and the element's tangent as each node carries it,
//   r(xi) = N1 r1 + N2 s1 + N3 r2 + N4 s2,   s_i = L0 A_i d_i,   xi in [0, 1],
//   N1 = 1 - 3 xi^2 + 2 xi^3, N2 = xi - 2 xi^2 + xi^3,
//   N3 = 3 xi^2 - 2 xi^3,     N4 = xi^3 - xi^2,
// with d_i = C_i e1, the element axis in node i's frame (so the reference
// line is straight). For small deflections of a straight beam the slopes
// s_i / L0 are the nodal rotations: the classic consistent mass of Archer
// (1963), rhoA L0 / 420 [156 22 54 -13; 22 4 13 -3; 54 13 156 -22;
// -13 -3 -22 4] on [r1; s1; r2; s2], whose bending frequencies converge at
// fourth order in the element size (the linear interpolation of the centre
// line, which it replaces, converges at second order).
//
// The kinetic energy T = 1/2 int rhoA |rdot|^2 = 1/2 pdot^T M_p pdot with
// p = [r1; s1; r2; s2] and M_p constant, and pdot = W [v1; omega1; v2; omega2]
// with sdot_i = -L0 A_i skew(d_i) omega_i. d'Alembert's principle on the
// virtual displacements W dq gives the element's generalized inertia force
//   f = W^T M_p (pddot - g_p),   pddot = W [a; omegadot] + Wdot [v; omega],
//   sddot_i = L0 A_i (omegadot_i x d_i + omega_i x (omega_i x d_i)),
// g_p = [g; 0; g; 0] (the weight: M_p g_p = int rhoA N g, as N1 + N3 = 1),
// so energy is conserved exactly by the semi-discrete equations: no
// configuration-dependent mass approximations. f is ordered like an element
// force, [f1 (world); m1 (node-1 frame); f2; m2]. The rotary inertia of the
// section stays lumped at the nodes (lumpedNodalInertia).
#pragma once
#include "flex/corotational_beam.hpp"

namespace mfbd {

// The element's inertia minus weight f and its derivatives with respect to
// [a; omegadot] (M), [v; omega] (C) and the increments [dr; dtheta] (K),
// with the velocities and accelerations held (nodal_inertia.hpp's
// conventions). `mass` = rhoA L0.
struct ConsistentInertia {
  Vec12 f = Vec12::Zero();
  Mat12 M = Mat12::Zero(), C = Mat12::Zero(), K = Mat12::Zero();
};

// f alone (residual evaluations); without inertia (statics) pass zero
// velocities and accelerations: f is then minus the consistent weight,
// nodal forces rhoA L0 g / 2 and moments rhoA L0^2 / 12 about the axis.
Vec12 consistentInertiaForce(const CorotationalBeam& beam, double mass, const NodePose& n1, const NodeVelocity& v1,
                             const NodeAcceleration& a1, const NodePose& n2, const NodeVelocity& v2,
                             const NodeAcceleration& a2, const Vec3& gravity);

ConsistentInertia consistentInertia(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                    const NodeVelocity& v1, const NodeAcceleration& a1, const NodePose& n2,
                                    const NodeVelocity& v2, const NodeAcceleration& a2, const Vec3& gravity);

// Kinetic energy 1/2 pdot^T M_p pdot and the weight's potential
// -rhoA L0 g . (r1 / 2 + s1 / 12 + r2 / 2 - s2 / 12) of the centre line.
struct ConsistentEnergy {
  double kinetic = 0.0, gravity = 0.0;
};
ConsistentEnergy consistentEnergy(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                  const NodeVelocity& v1, const NodePose& n2, const NodeVelocity& v2,
                                  const Vec3& gravity);

}  // namespace mfbd
