// The internal force of the corotational beam (flex/corotational_beam.hpp),
// written once as a kernel over T = double (one element) or T = Lanes (four
// elements side by side, flex/element_force_lanes.cpp), in the frames
// R_i = A_i C_i of flex/element_state.hpp. The tangent of this force is in
// corotational_beam.cpp (internalForceTangent).
#pragma once
#include "flex/consistent_mass.hpp"
#include "flex/element_state.hpp"
#include "math/rotation_series.hpp"

namespace mfbd {

// q of the shallow arch and its gradient on e_l (nonzero on the bending
// pairs (2, 5) and (3, 6)). For a Vec7 or an array of 7, of doubles or
// Lanes (math/lanes.hpp).
template <class T, class E, class G>
T archStrain(const E& e, G& gradient) {
  for (int i = 0; i < 7; ++i) gradient[i] = T(0.0);
  T q = T(0.0);
  for (int a = 2; a <= 3; ++a) {
    const T t1 = e[a], t2 = e[a + 3];
    q = q + (T(2.0) * t1 * t1 - t1 * t2 + T(2.0) * t2 * t2) / T(30.0);
    gradient[a] = (T(4.0) * t1 - t2) / T(30.0);
    gradient[a + 3] = (T(4.0) * t2 - t1) / T(30.0);
  }
  return q;
}

// The element constants the internal force reads, for one element or, as
// Lanes, for four: K_l in the pairs of localStiffnessTimes (row i is
// diagonal[i] e_i + pair[i] e_partner(i), partner 1 <-> 4, 2 <-> 5,
// 3 <-> 6; pair[0] = 0).
template <class T>
struct ElementConstants {
  T L0, EA, damping, mass;
  T diagonal[7], pair[7];
};

ElementConstants<double> elementConstants(const CorotationalBeam& beam, double dampingBeta);

// K_l e on arrays, in the pairs of localTimoshenkoStiffness.
template <class T>
void localStiffnessTimes(const ElementConstants<T>& k, const T e[7], T out[7]) {
  out[0] = k.diagonal[0] * e[0];
  for (int a = 1; a <= 3; ++a) {
    const int b = a + 3;
    out[a] = k.diagonal[a] * e[a] + k.pair[a] * e[b];
    out[b] = k.pair[b] * e[a] + k.diagonal[b] * e[b];
  }
}

// localElasticForce (corotational_beam.hpp) on arrays.
template <class T>
void localElasticForce(const ElementConstants<T>& k, const T e[7], T f[7]) {
  T g[7];
  const T q = archStrain<T>(e, g);
  const T N = k.EA * (e[0] / k.L0 + q);
  localStiffnessTimes(k, e, f);
  f[0] = N;
  for (int i = 1; i < 7; ++i) f[i] = f[i] + (N * k.L0) * g[i];  // g[0] = 0
}

// The internal force f = B^T f_l (corotational_beam.hpp: internalForceVector)
// plus, where k.mass > 0, the consistent inertia less weight: the corotated
// frame, the local rotations (math/rotation_series.hpp), the local force
// with damping beta K_l edot_l, edot_l = B v, and f = B^T f_l, each product
// with B written out from the frame (the tangent's Kinematics forms B in
// full, corotational_beam.cpp). False when the corotated frame is
// undefined or the force not finite (in any lane).
template <class T>
bool elementForce(const ElementState<T>& s, const ElementConstants<T>& k, ElementForce<T>& out) {
  using std::sqrt;  // and mfbd::sqrt(Lanes)
  const Matrix3<T>&R0 = s.R[0], &R1 = s.R[1];
  const Vector3<T>& x = s.chord;
  const T l = sqrt(squaredNorm(x));
  if (!allGreater(l / k.L0, 1e-9)) return false;
  const T inverseLength = T(1.0) / l;
  const Vector3<T> e1 = inverseLength * x;
  const Vector3<T>&q0 = R0.col[1], &q1 = R1.col[1];
  const Vector3<T> qMean = T(0.5) * (q0 + q1);
  const Vector3<T> n = cross(e1, qMean);
  const T qy = sqrt(squaredNorm(n));
  if (!allGreater(qy, 1e-6)) return false;
  const Vector3<T> e3 = n / qy;
  const Vector3<T> e2 = cross(e3, e1);
  const T eta = dot(qMean, e1) / qy;
  const Vector3<T> theta0 = relativeRotationVector(e1, e2, e3, R0), theta1 = relativeRotationVector(e1, e2, e3, R1);
  const T tangent0 = inverseTangentE(squaredNorm(theta0)), tangent1 = inverseTangentE(squaredNorm(theta1));
  const T u = (squaredNorm(x) - k.L0 * k.L0) / (l + k.L0);
  // twist_i = R_i^T (q_i x e3) / (2 qy): e1.dw_r of node i's spin
  const Vector3<T> twist0 = transposeTimes(R0, cross(q0, e3) / (T(2.0) * qy));
  const Vector3<T> twist1 = transposeTimes(R1, cross(q1, e3) / (T(2.0) * qy));
  // Pr d and Pr^T w (chordSpinTimes, chordSpinTransposeTimes)
  auto chordSpin = [&](const Vector3<T>& d) {
    return inverseLength * (dot(e2, d) * e3 - dot(e3, d) * (eta * e1 + e2));
  };
  auto chordSpinTranspose = [&](const Vector3<T>& w) {
    return inverseLength * (dot(e3, w) * e2 - (eta * dot(e1, w) + dot(e2, w)) * e3);
  };
  const T el[7] = {u, theta0.x, theta0.y, theta0.z, theta1.x, theta1.y, theta1.z};
  T fl[7];
  localElasticForce(k, el, fl);
  if (!allZero(k.damping)) {
    // edot_l = B v (strainIncrement)
    const Vector3<T> spin = chordSpin(s.chordRate) + (dot(twist0, s.spin[0]) + dot(twist1, s.spin[1])) * e1;
    const Vector3<T> rate0 = inverseTangentTimes(theta0, tangent0, s.spin[0] - transposeTimes(R0, spin), false);
    const Vector3<T> rate1 = inverseTangentTimes(theta1, tangent1, s.spin[1] - transposeTimes(R1, spin), false);
    const T rate[7] = {dot(e1, s.chordRate), rate0.x, rate0.y, rate0.z, rate1.x, rate1.y, rate1.z};
    T damping[7];
    localStiffnessTimes(k, rate, damping);
    for (int i = 0; i < 7; ++i) fl[i] = fl[i] + k.damping * damping[i];
  }
  // f = B^T f_l (strainMapTranspose)
  const Vector3<T> m0 = inverseTangentTimes(theta0, tangent0, Vector3<T>{fl[1], fl[2], fl[3]}, true);
  const Vector3<T> m1 = inverseTangentTimes(theta1, tangent1, Vector3<T>{fl[4], fl[5], fl[6]}, true);
  const Vector3<T> w = -(R0 * m0 + R1 * m1);
  const Vector3<T> chord = chordSpinTranspose(w);
  const T axial = dot(e1, w);
  out.force[0] = -chord - fl[0] * e1;
  out.force[1] = chord + fl[0] * e1;
  out.moment[0] = axial * twist0 + m0;
  out.moment[1] = axial * twist1 + m1;
  if (!allZero(k.mass)) addInertiaForce(s, k.L0, k.mass, out);
  // A NaN or infinity anywhere (u, theta, the frame) reaches the force; so does its sum.
  const Vector3<T> sum = out.force[0] + out.force[1] + out.moment[0] + out.moment[1];
  return allFinite(sum.x + sum.y + sum.z);
}

}  // namespace mfbd
