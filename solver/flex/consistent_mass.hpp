// Consistent mass of a beam element's centre line (DESIGN.md 3 "Flexible
// bodies"): the interpolation of the classic beam element, linear along the
// element and cubic (Hermite) across it, written in world quantities so that
// it holds at any rotation.
//
// Between the nodes the centre line is the chord plus two bubbles,
//   r(xi) = (1 - xi) r1 + xi r2 + N2 b1 + N4 b2,   xi in [0, 1],
//   b_i = L0 (A_i d_i - e),   N2 = xi - 2 xi^2 + xi^3,   N4 = xi^3 - xi^2,
// with d_i = C_i e1 the element axis in node i's frame and e the chord's
// direction: b_i is the node's slope relative to the chord (its rotation
// from the chord times L0 for small ones), and has no component along the
// chord to first order, so the axial motion is the linear bar's (whose
// Galerkin load the nodes then carry exactly) and the transverse motion is
// the Hermite cubic's. For small deflections of a straight beam this is the
// consistent mass of the Euler-Bernoulli element (Archer 1963), whose
// bending frequencies converge at fourth order in the element size.
//
// With p = [r1; r2; b1; b2] the kinetic energy is T = 1/2 pdot^T M_p pdot,
// M_p = rhoA L0 / 420 [140 70 21 -14; 70 140 14 -21; 21 14 4 -3;
// -14 -21 -3 4] (x I3), constant; p depends on the nodes through
// dp = J dq: db_i = L0 A_i (dtheta_i x d_i) - (L0 / l) P (dr2 - dr1),
// P = I - e e^T, l the chord length. d'Alembert's principle on the virtual
// displacements J dq gives the element's generalized inertia force
//   f = J^T M_p (pddot - g_p),   g_p = [g; g; 0; 0]
// (M_p g_p = int rhoA N g: the weight as the consistent load), exactly
// conservative: no approximation of a configuration-dependent mass.
// f is ordered like an element force, [f1 (world); m1 (node-1 frame); f2;
// m2]. The rotary inertia of the section stays lumped at the nodes
// (lumpedNodalInertia).
#pragma once
#include "flex/corotational_beam.hpp"

namespace mfbd {

// int_0^1 N N^T dxi of the shape functions [1 - xi, xi, N2, N4] on
// [r1; r2; b1; b2], times 420 (M_p = rhoA L0 / 420 times it).
inline constexpr double kConsistentShape[4][4] = {
    {140, 70, 21, -14}, {70, 140, 14, -21}, {21, 14, 4, -3}, {-14, -21, -3, 4}};

// The element's inertia minus weight f and its tangent
//   S = cM df/d[a; omegadot] + cC df/d[v; omega] + cK df/d[dr; dtheta]
// (velocities and accelerations held; nodal_inertia.hpp's conventions),
// formed at once for the Newton matrix's factors. `mass` = rhoA L0.
struct ConsistentInertia {
  Vec12 f = Vec12::Zero();
  Mat12 S = Mat12::Zero();
};

// f alone (residual evaluations); without inertia (statics) pass zero
// velocities and accelerations: f is then minus the consistent weight,
// nodal forces rhoA L0 g / 2 and moments rhoA L0^2 g / 12 about the axis.
Vec12 consistentInertiaForce(const CorotationalBeam& beam, double mass, const NodePose& n1, const NodeVelocity& v1,
                             const NodeAcceleration& a1, const NodePose& n2, const NodeVelocity& v2,
                             const NodeAcceleration& a2, const Vec3& gravity);

ConsistentInertia consistentInertia(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                    const NodeVelocity& v1, const NodeAcceleration& a1, const NodePose& n2,
                                    const NodeVelocity& v2, const NodeAcceleration& a2, const Vec3& gravity,
                                    double cM, double cC, double cK);

// Kinetic energy 1/2 pdot^T M_p pdot and the weight's potential
// -rhoA L0 g . (r1 / 2 + r2 / 2 + b1 / 12 - b2 / 12) of the centre line.
struct ConsistentEnergy {
  double kinetic = 0.0, gravity = 0.0;
};
ConsistentEnergy consistentEnergy(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                  const NodeVelocity& v1, const NodePose& n2, const NodeVelocity& v2,
                                  const Vec3& gravity);

}  // namespace mfbd
