// Consistent mass of a beam element's centre line (docs/design.md 3 "Flexible
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
#include <cmath>

#include "flex/corotational_beam.hpp"
#include "flex/element_state.hpp"

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

// consistentInertiaForce's f added to an element force, for one element or
// four (flex/element_state.hpp), in the frames R_i, where the element axis
// d_i = C_i e1 is e1: F = M_p (pddot - g_p) on [r1; r2; b1; b2],
// f += [F_r1 + k; L0 e1 x (R_1^T F_b1); F_r2 - k; L0 e1 x (R_2^T F_b2)],
// k = (L0 / l) P (F_b1 + F_b2).
template <class T>
void addInertiaForce(const ElementState<T>& s, const T& L0, const T& mass, ElementForce<T>& out) {
  using std::sqrt;  // and mfbd::sqrt(Lanes)
  const auto& shape = kConsistentShape;
  const T l = sqrt(squaredNorm(s.chord));
  const Vector3<T> e = s.chord / l, &cdot = s.chordRate, &cddot = s.chordAcceleration;
  const T lDot = dot(e, cdot);
  const Vector3<T> eDot = (cdot - lDot * e) / l;
  const Vector3<T> eDdot = (cddot - dot(e, cddot) * e - (T(2.0) * lDot) * eDot - dot(eDot, cdot) * e) / l;
  // L0 (omegadot x e1 + omega x (omega x e1)) in R_i's frame, turned to the world
  Vector3<T> p[4] = {s.acceleration[0], s.acceleration[1], s.acceleration[0], s.acceleration[1]};
  for (int i = 0; i < 2; ++i) {
    const Vector3<T>&w = s.spin[i], &wdot = s.spinRate[i];
    const Vector3<T> local{-(w.y * w.y + w.z * w.z), wdot.z + w.x * w.y, w.x * w.z - wdot.y};
    p[2 + i] = s.R[i] * (L0 * local) - L0 * eDdot;
  }
  const T m = mass / T(420.0);
  Vector3<T> F[4];
  for (int r = 0; r < 4; ++r)
    F[r] = m * (T(shape[r][0]) * p[0] + T(shape[r][1]) * p[1] + T(shape[r][2]) * p[2] + T(shape[r][3]) * p[3]);
  const Vector3<T> G = F[2] + F[3];
  const Vector3<T> k = (L0 / l) * (G - dot(e, G) * e);
  out.force[0] = out.force[0] + F[0] + k;
  out.force[1] = out.force[1] + F[1] - k;
  for (int i = 0; i < 2; ++i) {
    const Vector3<T> g = transposeTimes(s.R[i], F[2 + i]);  // e1 x g = (0, -g_z, g_y)
    out.moment[i] = out.moment[i] + L0 * Vector3<T>{T(0.0), -g.z, g.y};
  }
}

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
