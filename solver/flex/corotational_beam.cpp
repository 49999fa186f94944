#include "flex/corotational_beam.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flex/consistent_mass.hpp"
#include "flex/element_state.hpp"
#include "math/lanes.hpp"

namespace mfbd {

namespace {

using Mat3x12 = Eigen::Matrix<double, 3, 12>;
using Mat7x12 = Eigen::Matrix<double, 7, 12>;
using Row12 = Eigen::Matrix<double, 1, 12>;

// ---------------------------------------------------------------------------
// Local linear Timoshenko stiffness on e_l = [u; theta1; theta2].
// With the chord as local x the local transverse displacements vanish, so of
// the exact two-node Timoshenko matrix (Przemieniecki, "Theory of matrix
// structural analysis", 1968) only the rotation block remains:
//   EI / ((1+Phi) L) [[4+Phi, 2-Phi], [2-Phi, 4+Phi]],  Phi = 12 EI/(GA L^2).
// ---------------------------------------------------------------------------
double shearParameter(double EI, double GA, double L) {
  if (!(GA > 0.0) || std::isinf(GA)) return 0.0;  // shear-rigid: Euler-Bernoulli
  return 12.0 * EI / (GA * L * L);
}

void addBending(Mat7& K, int i1, int i2, double EI, double Phi, double L) {
  const double k = EI / ((1.0 + Phi) * L);
  K(i1, i1) += k * (4.0 + Phi);
  K(i2, i2) += k * (4.0 + Phi);
  K(i1, i2) += k * (2.0 - Phi);
  K(i2, i1) += k * (2.0 - Phi);
}

Mat7 localTimoshenkoStiffness(const BeamSection& s, double L) {
  Mat7 K = Mat7::Zero();
  K(0, 0) = s.EA / L;
  K(1, 1) = K(4, 4) = s.GJ / L;
  K(1, 4) = K(4, 1) = -s.GJ / L;
  // Bending about y deflects along z (shear GAz); about z along y (GAy).
  addBending(K, 2, 5, s.EIy, shearParameter(s.EIy, s.GAz, L), L);
  addBending(K, 3, 6, s.EIz, shearParameter(s.EIz, s.GAy, L), L);
  return K;
}

// ---------------------------------------------------------------------------
// Inverse tangent T^-1(theta) = I + S/2 + e(t) S^2 (S = skew(theta),
// t = |theta|, e = (1 - (t/2) cot(t/2)) / t^2, see math/rotation.cpp) and its
// derivative in a direction dtheta,
//   dT^-1 = skew(dtheta)/2 + e (skew(dtheta) S + S skew(dtheta))
//           + (e'(t)/t) (theta . dtheta) S^2.
// The closed forms of e and e'/t cancel badly for small t (e'/t loses ~1e-9
// at t = 0.3); below 0.3 use the Taylor series, e = sum_n |B_2n|/(2n)! t^(2n-2)
// (from x cot x), truncated where the next term is below 1e-12 relative.
// ---------------------------------------------------------------------------
struct InverseTangentCoefficients {
  double e = 0.0, dEoverT = 0.0;
};

InverseTangentCoefficients inverseTangentCoefficients(double t2) {  // t2 = |theta|^2
  InverseTangentCoefficients k;
  if (t2 < 0.09) {  // t < 0.3
    const double c[5] = {1.0 / 720.0, 1.0 / 30240.0, 1.0 / 1209600.0, 1.0 / 47900160.0,
                         691.0 / 1307674368000.0};  // t^2 .. t^10 of e
    k.e = 1.0 / 12.0 + t2 * (c[0] + t2 * (c[1] + t2 * (c[2] + t2 * (c[3] + t2 * c[4]))));
    k.dEoverT = 2 * c[0] + t2 * (4 * c[1] + t2 * (6 * c[2] + t2 * (8 * c[3] + t2 * 10 * c[4])));
  } else {
    const double t = std::sqrt(t2), cotHalf = 1.0 / std::tan(0.5 * t), sinHalf = std::sin(0.5 * t);
    k.e = (1.0 - 0.5 * t * cotHalf) / t2;
    k.dEoverT = -2.0 / (t2 * t2) + cotHalf / (2.0 * t2 * t) + 1.0 / (4.0 * t2 * sinHalf * sinHalf);
  }
  return k;
}

InverseTangentCoefficients inverseTangentCoefficients(const Vec3& theta) {
  return inverseTangentCoefficients(theta.squaredNorm());
}

// T^-1 itself, with S^2 = theta theta^T - t^2 I (the series keeps e exact to
// round-off where the closed form of math/rotation.cpp cancels).
Mat3 inverseTangent(const Vec3& theta, const InverseTangentCoefficients& k) {
  Mat3 Tinv = k.e * theta * theta.transpose() + 0.5 * skew(theta);
  Tinv.diagonal().array() += 1.0 - k.e * theta.squaredNorm();
  return Tinv;
}

// The derivative applied to a vector x, as a linear map of dtheta:
// dT^-1 x = J dtheta, or with transposed dT^-T x = J dtheta, where
//   J = -+ skew(x)/2 - e (skew(theta x x) + S skew(x)) + (e'/t) (S^2 x) theta^T.
Mat3 inverseTangentVariation(const Vec3& theta, const InverseTangentCoefficients& k, const Vec3& x,
                             bool transposed) {
  const Mat3 S = skew(theta), X = skew(x);
  const Vec3 SSx = theta.cross(theta.cross(x));
  return (transposed ? 0.5 : -0.5) * X - k.e * (skew(theta.cross(x)) + S * X) + k.dEoverT * SSx * theta.transpose();
}

// ---------------------------------------------------------------------------
// Element kinematics in the current configuration.
// Corotated frame (Battini & Pacoste 2002): e1 along the chord,
// q = (q1 + q2)/2 the mean of the nodes' section y axes q_i = A_i C_i y,
// e3 = e1 x q / |e1 x q|, e2 = e3 x e1. It depends only on relative
// positions and orientations, so any rigid motion (any number of turns)
// moves it rigidly and leaves e_l unchanged.
// ---------------------------------------------------------------------------
struct Kinematics {
  bool valid = false;
  Mat3 A[2], R[2];  // node orientations; node copies of the element frame A_i C_i
  Vec3 e1, e2, e3;  // corotated frame (world)
  double l = 0.0, inverseLength = 0.0;
  Vec3 q[2], qMean;
  double qx = 0.0, qy = 0.0, eta = 0.0;  // qMean = qx e1 + qy e2, eta = qx/qy
  Vec3 theta[2];                         // local rotations log(Rr^T R_i)
  InverseTangentCoefficients tangentCoefficients[2];
  Mat3 Tinv[2];
  double u = 0.0;  // elongation
  // Spin of the corotated frame, dw_r = P dq on dq = [dr1; dtheta1; dr2; dtheta2],
  // P = [-Pr, e1 twist_1^T, Pr, e1 twist_2^T], applied from e_j and twist_i
  // alone where only products are needed (residuals).
  Vec3 twist[2];
  // Tangent maps in full (only the tangent needs them, see tangentMaps):
  Mat3 Pr;
  Mat3x12 P;     // dw_r = P dq
  Mat3x12 X[2];  // R_i^T (dw_i - dw_r) = X_i dq, so dtheta_i = Tinv_i X_i dq
  Mat7x12 B;     // de_l = B dq
};

// Chord part of the frame spin, dw_r = Pr (dr2 - dr1) + ...: the components
// e2.dw_r = -e3.(dr2-dr1)/l, e3.dw_r = e2.(dr2-dr1)/l of the chord's rotation
// and the chord part -eta e3.(dr2-dr1)/l of the twist e1.dw_r:
//   l Pr = -eta e1 e3^T - e2 e3^T + e3 e2^T.
Mat3 chordSpin(const Kinematics& k) {
  return (-k.eta * k.e1 * k.e3.transpose() - k.e2 * k.e3.transpose() + k.e3 * k.e2.transpose()) *
         k.inverseLength;
}

// Pr d and Pr^T w without forming Pr.
Vec3 chordSpinTimes(const Kinematics& k, const Vec3& d) {
  return (k.e3 * k.e2.dot(d) - (k.eta * k.e1 + k.e2) * k.e3.dot(d)) * k.inverseLength;
}

Vec3 chordSpinTransposeTimes(const Kinematics& k, const Vec3& w) {
  return (k.e2 * k.e3.dot(w) - k.e3 * (k.eta * k.e1.dot(w) + k.e2.dot(w))) * k.inverseLength;
}

// Twist part of the frame spin: e1.dw_r gets (q_i x e3).dw_i / (2 qy) from
// node i's world spin dw_i (rotation of q's projection about e1).
Vec3 twistRow(const Kinematics& k, int i) { return k.q[i].cross(k.e3) / (2.0 * k.qy); }

Kinematics corotatedFrame(const CorotationalBeam& beam, const NodePose& n1,
                          const NodePose& n2) {
  Kinematics k;
  k.A[0] = n1.A;
  k.A[1] = n2.A;
  k.R[0] = beam.identityC1 ? n1.A : Mat3(n1.A * beam.C1);
  k.R[1] = beam.identityC2 ? n2.A : Mat3(n2.A * beam.C2);
  const Vec3 x = n2.r - n1.r;
  k.l = x.norm();
  if (!(k.l > 1e-9 * beam.L0)) return k;
  k.inverseLength = 1.0 / k.l;
  k.e1 = x * k.inverseLength;
  k.q[0] = k.R[0].col(1);
  k.q[1] = k.R[1].col(1);
  k.qMean = 0.5 * (k.q[0] + k.q[1]);
  const Vec3 n = k.e1.cross(k.qMean);
  // |q| <= 1; qy -> 0 only at ~90 deg local bending of both nodes or a
  // ~180 deg relative twist, far outside small local deformations.
  k.qy = n.norm();
  if (!(k.qy > 1e-6)) return k;
  k.e3 = n / k.qy;
  k.e2 = k.e3.cross(k.e1);
  k.qx = k.qMean.dot(k.e1);
  k.eta = k.qx / k.qy;
  Mat3 Rr;
  Rr << k.e1, k.e2, k.e3;
  for (int i = 0; i < 2; ++i) {
    k.theta[i] = logSO3(Rr.transpose() * k.R[i]);
    k.tangentCoefficients[i] = inverseTangentCoefficients(k.theta[i]);
    k.Tinv[i] = inverseTangent(k.theta[i], k.tangentCoefficients[i]);
    // dw_i = A_i dtheta_i, so e1.dw_r gets twistRow . A_i dtheta_i
    k.twist[i] = k.A[i].transpose() * twistRow(k, i);
  }
  // l - L0 without cancellation when l ~ L0
  k.u = (x.squaredNorm() - beam.L0 * beam.L0) / (k.l + beam.L0);
  k.valid = std::isfinite(k.u) && k.theta[0].allFinite() && k.theta[1].allFinite();
  return k;
}

// P dq and P^T w from the compact form (no 3 x 12 products).
Vec3 frameSpin(const Kinematics& k, const Vec12& dq) {
  return chordSpinTimes(k, dq.segment<3>(6) - dq.segment<3>(0)) +
         k.e1 * (k.twist[0].dot(dq.segment<3>(3)) + k.twist[1].dot(dq.segment<3>(9)));
}

Vec12 frameSpinTranspose(const Kinematics& k, const Vec3& w) {
  const Vec3 chord = chordSpinTransposeTimes(k, w);
  const double axial = k.e1.dot(w);
  Vec12 out;
  out << -chord, axial * k.twist[0], chord, axial * k.twist[1];
  return out;
}

// de_l = B dq without forming B: du = e1.(dr2 - dr1) and
// dtheta_i = Tinv_i X_i dq = Tinv_i (C_i^T dtheta_i - R_i^T P dq).
Vec7 strainIncrement(const CorotationalBeam& beam, const Kinematics& k, const Vec12& dq) {
  const Vec3 spin = frameSpin(k, dq);
  Vec7 de;
  de[0] = k.e1.dot(dq.segment<3>(6) - dq.segment<3>(0));
  const Vec3 nodeSpin1 = beam.identityC1 ? Vec3(dq.segment<3>(3)) : Vec3(beam.C1.transpose() * dq.segment<3>(3));
  const Vec3 nodeSpin2 = beam.identityC2 ? Vec3(dq.segment<3>(9)) : Vec3(beam.C2.transpose() * dq.segment<3>(9));
  de.segment<3>(1) = k.Tinv[0] * (nodeSpin1 - k.R[0].transpose() * spin);
  de.segment<3>(4) = k.Tinv[1] * (nodeSpin2 - k.R[1].transpose() * spin);
  return de;
}

// f = B^T f_l without forming B: with m_i = Tinv_i^T f_l,i,
// X_i^T m_i = E_i^T C_i m_i - P^T R_i m_i (E_i picks node i's rotation).
Vec12 strainMapTranspose(const CorotationalBeam& beam, const Kinematics& k, const Vec7& fl) {
  const Vec3 m1 = k.Tinv[0].transpose() * fl.segment<3>(1);
  const Vec3 m2 = k.Tinv[1].transpose() * fl.segment<3>(4);
  Vec12 f = frameSpinTranspose(k, -(k.R[0] * m1 + k.R[1] * m2));
  f.segment<3>(0) -= fl[0] * k.e1;
  f.segment<3>(3) += beam.identityC1 ? m1 : Vec3(beam.C1 * m1);
  f.segment<3>(6) += fl[0] * k.e1;
  f.segment<3>(9) += beam.identityC2 ? m2 : Vec3(beam.C2 * m2);
  return f;
}

void tangentMaps(const CorotationalBeam& beam, Kinematics& k) {
  k.Pr = chordSpin(k);
  k.P.setZero();
  k.P.block<3, 3>(0, 0) = -k.Pr;
  k.P.block<3, 3>(0, 6) = k.Pr;
  for (int i = 0; i < 2; ++i) k.P.block<3, 3>(0, 3 + 6 * i) = k.e1 * k.twist[i].transpose();
  const Mat3 C[2] = {beam.C1, beam.C2};
  k.B.setZero();
  k.B.block<1, 3>(0, 0) = -k.e1.transpose();
  k.B.block<1, 3>(0, 6) = k.e1.transpose();
  for (int i = 0; i < 2; ++i) {
    // -R_i^T P from P = [-Pr, e1 twist_1^T, Pr, e1 twist_2^T] block by block
    const Mat3 RtPr = k.R[i].transpose() * k.Pr;
    const Vec3 Rte1 = k.R[i].transpose() * k.e1;
    k.X[i].block<3, 3>(0, 0) = RtPr;
    k.X[i].block<3, 3>(0, 6) = -RtPr;
    for (int j = 0; j < 2; ++j) k.X[i].block<3, 3>(0, 3 + 6 * j) = -Rte1 * k.twist[j].transpose();
    // R_i^T dw_i = C_i^T A_i^T A_i dtheta_i = C_i^T dtheta_i
    k.X[i].block<3, 3>(0, 3 + 6 * i) += C[i].transpose();
    k.B.middleRows<3>(1 + 3 * i) = k.Tinv[i] * k.X[i];
  }
}

// Derivatives of the frame quantities of tangentMaps along all twelve
// increments at once (one column per increment), varied term by term:
//   de_j = dw_r x e_j,  dq_i = dw_i x q_i,  dl = e1.(dr2 - dr1),
//   deta = (dqx - eta dqy) / qy,  dtwist_i = A_i^T dt_i - dtheta_i x twist_i.
// Node spins dw_i = A_i dtheta_i touch only node i's rotation columns: those
// products are taken on that 3 x 3 block alone.
struct FrameDerivatives {
  Mat3x12 dE1, dE2, dE3;
  Row12 dl, deta;
  Mat3x12 dTwist[2];
};

FrameDerivatives frameDerivatives(const Kinematics& k) {
  FrameDerivatives d;
  // -skew(e_j) P = [skew(e_j) Pr, -(e_j x e1) twist_1^T, -skew(e_j) Pr, -(e_j x e1) twist_2^T],
  // with e1 x e1 = 0, e2 x e1 = -e3, e3 x e1 = e2.
  auto spinOf = [&k](Mat3x12& dE, const Vec3& e, const Vec3& eCrossE1) {
    const Mat3 ePr = skew(e) * k.Pr;
    dE.block<3, 3>(0, 0) = ePr;
    dE.block<3, 3>(0, 6) = -ePr;
    for (int i = 0; i < 2; ++i) dE.block<3, 3>(0, 3 + 6 * i) = -eCrossE1 * k.twist[i].transpose();
  };
  spinOf(d.dE1, k.e1, Vec3::Zero());
  spinOf(d.dE2, k.e2, -k.e3);
  spinOf(d.dE3, k.e3, k.e2);
  d.dl.setZero();
  d.dl.segment<3>(0) = -k.e1.transpose();
  d.dl.segment<3>(6) = k.e1.transpose();
  const Mat3 dQ[2] = {-skew(k.q[0]) * k.A[0], -skew(k.q[1]) * k.A[1]};  // dq_i on node i's dtheta_i
  Row12 dqx = k.qMean.transpose() * d.dE1, dqy = k.qMean.transpose() * d.dE2;
  for (int i = 0; i < 2; ++i) {
    dqx.segment<3>(3 + 6 * i) += 0.5 * k.e1.transpose() * dQ[i];
    dqy.segment<3>(3 + 6 * i) += 0.5 * k.e2.transpose() * dQ[i];
  }
  d.deta = (dqx - k.eta * dqy) / k.qy;
  for (int i = 0; i < 2; ++i) {
    // t_i = q_i x e3 / (2 qy)
    Mat3x12 dT = -twistRow(k, i) * dqy / k.qy + skew(k.q[i]) * d.dE3 / (2.0 * k.qy);
    dT.block<3, 3>(0, 3 + 6 * i) -= skew(k.e3) * dQ[i] / (2.0 * k.qy);
    d.dTwist[i] = k.A[i].transpose() * dT;
    d.dTwist[i].block<3, 3>(0, 3 + 6 * i) += skew(k.twist[i]);
  }
  return d;
}

// d(Pr^T w) and d(Pr x) for fixed w, x, from
// l Pr = -eta e1 e3^T - e2 e3^T + e3 e2^T (and dl Pr from the 1/l).
Mat3x12 chordSpinTransposeDerivative(const Kinematics& k, const FrameDerivatives& d, const Vec3& w) {
  const double w1 = k.e1.dot(w), w2 = k.e2.dot(w), w3 = k.e3.dot(w);
  const Mat3x12 dLPrTw = -w1 * k.e3 * d.deta - k.eta * (k.e3 * (w.transpose() * d.dE1) + w1 * d.dE3) -
                         k.e3 * (w.transpose() * d.dE2) - w2 * d.dE3 + w3 * d.dE2 + k.e2 * (w.transpose() * d.dE3);
  return (dLPrTw - (k.Pr.transpose() * w) * d.dl) * k.inverseLength;
}

Mat3x12 chordSpinDerivative(const Kinematics& k, const FrameDerivatives& d, const Vec3& x) {
  const double x2 = k.e2.dot(x), x3 = k.e3.dot(x);
  const Mat3x12 dLPrx = -x3 * k.e1 * d.deta - k.eta * (x3 * d.dE1 + k.e1 * (x.transpose() * d.dE3)) - x3 * d.dE2 -
                        k.e2 * (x.transpose() * d.dE3) + k.e3 * (x.transpose() * d.dE2) + x2 * d.dE3;
  return (dLPrx - (k.Pr * x) * d.dl) * k.inverseLength;
}

// d(P^T w) (12 x 12) and d(P x) (3 x 12) of the compact form
// P = [-Pr, e1 twist_1^T, Pr, e1 twist_2^T].
Mat12 frameSpinTransposeDerivative(const Kinematics& k, const FrameDerivatives& d, const Vec3& w) {
  const Mat3x12 chord = chordSpinTransposeDerivative(k, d, w);
  const Row12 dAxial = w.transpose() * d.dE1;
  const double axial = k.e1.dot(w);
  Mat12 out;
  out << -chord, k.twist[0] * dAxial + axial * d.dTwist[0], chord, k.twist[1] * dAxial + axial * d.dTwist[1];
  return out;
}

Mat3x12 frameSpinDerivative(const Kinematics& k, const FrameDerivatives& d, const Vec12& x) {
  const Vec3 th[2] = {x.segment<3>(3), x.segment<3>(9)};
  return chordSpinDerivative(k, d, x.segment<3>(6) - x.segment<3>(0)) +
         d.dE1 * (k.twist[0].dot(th[0]) + k.twist[1].dot(th[1])) +
         k.e1 * (th[0].transpose() * d.dTwist[0] + th[1].transpose() * d.dTwist[1]);
}

// Geometric part of the tangent, d(B^T)/dq f_l; with damping also the
// position dependence of edot = B(q) v at fixed v. Both exact.
// dB = [-de1^T 0 de1^T 0; dT^-1_i X_i + T^-1_i dX_i] with
// dX_i = R_i^T (skew(dw_i) P - dP), contracted with f_l (and v) directly:
//   dB^T f_l = f_l,0 [-de1; 0; de1; 0] + sum_i (E_i^T C_i y_i - P^T R_i y_i)
//              + P^T sum_i (s_i x dw_i) - dP^T (s_1 + s_2),
// y_i = dT^-1_i^T f_l,i = J_i dtheta_i, s_i = R_i T^-1_i^T f_l,i, E_i picking
// node i's rotation.
void addGeometricStiffness(const CorotationalBeam& beam, const Kinematics& k, const Vec7& fl, const Vec12& v,
                           double dampingBeta, const Eigen::Matrix<double, 12, 7>& BtKl, Mat12& K) {
  const FrameDerivatives d = frameDerivatives(k);
  const Mat3 C[2] = {beam.C1, beam.C2};
  Mat3x12 dStrain[2], spin;  // dtheta_i = B_i dq; what P^T acts on
  Mat12 G = Mat12::Zero();
  spin.setZero();
  Vec3 sSum = Vec3::Zero();
  for (int i = 0; i < 2; ++i) {
    const Vec3 flRotation = fl.segment<3>(1 + 3 * i);
    const Vec3 s = k.R[i] * (k.Tinv[i].transpose() * flRotation);
    sSum += s;
    dStrain[i] = k.B.middleRows<3>(1 + 3 * i);
    const Mat3x12 Y = inverseTangentVariation(k.theta[i], k.tangentCoefficients[i], flRotation, true) * dStrain[i];
    if (i == 0 ? beam.identityC1 : beam.identityC2)
      G.middleRows<3>(3 + 6 * i) += Y;
    else
      G.middleRows<3>(3 + 6 * i) += C[i] * Y;
    spin -= k.R[i] * Y;
    spin.block<3, 3>(0, 3 + 6 * i) += skew(s) * k.A[i];
  }
  G.middleRows<3>(0) -= fl[0] * d.dE1;
  G.middleRows<3>(6) += fl[0] * d.dE1;
  // P^T spin = [-Pr^T spin; twist_1 (e1^T spin); Pr^T spin; twist_2 (e1^T spin)]
  const Mat3x12 PrTspin = k.Pr.transpose() * spin;
  const Row12 e1spin = k.e1.transpose() * spin;
  G.middleRows<3>(0) -= PrTspin;
  G.middleRows<3>(6) += PrTspin;
  G.middleRows<3>(3) += k.twist[0] * e1spin;
  G.middleRows<3>(9) += k.twist[1] * e1spin;
  K += G - frameSpinTransposeDerivative(k, d, sSum);
  if (dampingBeta == 0.0) return;
  // d(B v) = [(v2 - v1)^T de1; dT^-1_i X_i v + T^-1_i R_i^T (dw_i x P v - dP v)]
  const Vec3 spinRate = frameSpin(k, v);
  const Mat3x12 dSpinRate = frameSpinDerivative(k, d, v);
  Eigen::Matrix<double, 7, 12> dStrainRate;
  dStrainRate.row(0) = (v.segment<3>(6) - v.segment<3>(0)).transpose() * d.dE1;
  for (int i = 0; i < 2; ++i) {
    Mat3x12 dRelativeSpin = -dSpinRate;  // dw_i x P v - dP v
    dRelativeSpin.block<3, 3>(0, 3 + 6 * i) -= skew(spinRate) * k.A[i];
    dStrainRate.middleRows<3>(1 + 3 * i) =
        inverseTangentVariation(k.theta[i], k.tangentCoefficients[i], k.X[i] * v, false) * dStrain[i] +
        k.Tinv[i] * (k.R[i].transpose() * dRelativeSpin);
  }
  K += dampingBeta * BtKl.lazyProduct(dStrainRate);
}

// K_l B using the pattern of localTimoshenkoStiffness: axial (0), torsion
// (1, 4), bending (2, 5) and (3, 6) couple only within their pairs. For a
// 7 x 12 map or a 7-vector alike.
template <int Columns>
Eigen::Matrix<double, 7, Columns> localStiffnessTimes(const Mat7& Kl, const Eigen::Matrix<double, 7, Columns>& B) {
  Eigen::Matrix<double, 7, Columns> out;
  out.row(0) = Kl(0, 0) * B.row(0);
  for (int a = 1; a <= 3; ++a) {
    const int b = a + 3;
    out.row(a) = Kl(a, a) * B.row(a) + Kl(a, b) * B.row(b);
    out.row(b) = Kl(b, a) * B.row(a) + Kl(b, b) * B.row(b);
  }
  return out;
}

Vec7 localDeformationVector(const Kinematics& k) {
  Vec7 e;
  e << k.u, k.theta[0], k.theta[1];
  return e;
}

}  // namespace

namespace {

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

double archStrain(const Vec7& e, Vec7& gradient) { return archStrain<double>(e, gradient); }

// The element constants the internal force reads, for one element or, as
// Lanes, for four: K_l in the pairs of localStiffnessTimes (row i is
// diagonal[i] e_i + pair[i] e_partner(i), partner 1 <-> 4, 2 <-> 5,
// 3 <-> 6; pair[0] = 0).
template <class T>
struct ElementConstants {
  T L0, EA, damping, mass;
  T diagonal[7], pair[7];
};

ElementConstants<double> elementConstants(const CorotationalBeam& beam, double dampingBeta) {
  ElementConstants<double> k;
  k.L0 = beam.L0;
  k.EA = beam.section.EA;
  k.damping = dampingBeta;
  k.mass = 0.0;
  const Mat7& Kl = beam.localStiffness;
  for (int i = 0; i < 7; ++i) {
    k.diagonal[i] = Kl(i, i);
    k.pair[i] = i == 0 ? 0.0 : Kl(i, i <= 3 ? i + 3 : i - 3);
  }
  return k;
}

template <class T>
void localStiffnessTimes(const ElementConstants<T>& k, const T e[7], T out[7]) {
  out[0] = k.diagonal[0] * e[0];
  for (int a = 1; a <= 3; ++a) {
    const int b = a + 3;
    out[a] = k.diagonal[a] * e[a] + k.pair[a] * e[b];
    out[b] = k.pair[b] * e[a] + k.diagonal[b] * e[b];
  }
}

// localElasticForce on arrays (see there).
template <class T>
void localElasticForce(const ElementConstants<T>& k, const T e[7], T f[7]) {
  T g[7];
  const T q = archStrain<T>(e, g);
  const T N = k.EA * (e[0] / k.L0 + q);
  localStiffnessTimes(k, e, f);
  f[0] = N;
  for (int i = 1; i < 7; ++i) f[i] = f[i] + (N * k.L0) * g[i];  // g[0] = 0
}

}  // namespace

Vec7 localElasticForce(const CorotationalBeam& beam, const Vec7& e) {
  Vec7 f;
  localElasticForce(elementConstants(beam, 0.0), e.data(), f.data());
  return f;
}

namespace {

// K_t - K_l in its two parts: the arch strain's gradient, EA L0 (grad grad^T)
// with grad = [1/L0; g] (less EA/L0 at (0, 0), already in K_l), and the
// bowing's geometric stiffness N L0/30 [4 -1; -1 4] on each bending pair.
struct ArchTangent {
  Vec7 gradient;
  double EAL0 = 0.0, NL0 = 0.0;
};

ArchTangent archTangent(const CorotationalBeam& beam, const Vec7& e) {
  ArchTangent a;
  const double q = archStrain(e, a.gradient);
  const double EA = beam.section.EA, L0 = beam.L0;
  a.gradient[0] = 1.0 / L0;
  a.EAL0 = EA * L0;
  a.NL0 = EA * (e[0] / L0 + q) * L0;
  return a;
}

// K += the bowing's N L0/30 [4 -1; -1 4] on the pairs (a, a + 3), a = 2, 3:
// the same pairs as K_l's, so K_l plus it stays in localStiffnessTimes' form.
void addBowingStiffness(double NL0, Mat7& K) {
  for (int a = 2; a <= 3; ++a) {
    K(a, a) += NL0 * 4.0 / 30.0;
    K(a + 3, a + 3) += NL0 * 4.0 / 30.0;
    K(a, a + 3) -= NL0 / 30.0;
    K(a + 3, a) -= NL0 / 30.0;
  }
}

}  // namespace

Mat7 localTangentExcess(const CorotationalBeam& beam, const Vec7& e) {
  const ArchTangent a = archTangent(beam, e);
  Mat7 D = a.EAL0 * a.gradient * a.gradient.transpose();
  D(0, 0) = 0.0;  // EA / L0, already in K_l
  addBowingStiffness(a.NL0, D);
  return D;
}

double localStrainEnergy(const CorotationalBeam& beam, const Vec7& e) {
  Vec7 g;
  const double eps = e[0] / beam.L0 + archStrain(e, g);
  return 0.5 * e.dot(beam.localStiffness * e) - 0.5 * beam.section.EA / beam.L0 * e[0] * e[0] +
         0.5 * beam.section.EA * beam.L0 * eps * eps;
}

CorotationalBeam CorotationalBeam::fromReference(const NodePose& n1, const NodePose& n2,
                                                 const Vec3& sectionY,
                                                 const BeamSection& section) {
  const Vec3 x = n2.r - n1.r;
  CorotationalBeam beam;
  beam.L0 = x.norm();
  if (!(beam.L0 > 0.0) || !std::isfinite(beam.L0)) {
    throw std::invalid_argument("corotational beam: the two reference nodes coincide");
  }
  const Vec3 e1 = x / beam.L0;
  const Vec3 y = sectionY - sectionY.dot(e1) * e1;
  if (!(y.norm() > 1e-8 * sectionY.norm())) {
    throw std::invalid_argument(
        "corotational beam: sectionY is zero or parallel to the element axis");
  }
  Mat3 E0;
  E0 << e1, y.normalized(), e1.cross(y.normalized());
  beam.C1 = n1.A.transpose() * E0;
  beam.C2 = n2.A.transpose() * E0;
  beam.identityC1 = beam.C1 == Mat3::Identity();
  beam.identityC2 = beam.C2 == Mat3::Identity();
  beam.section = section;
  beam.localStiffness = localTimoshenkoStiffness(section, beam.L0);
  return beam;
}

LocalDeformation localDeformation(const CorotationalBeam& beam, const NodePose& n1,
                                  const NodePose& n2) {
  const Kinematics k = corotatedFrame(beam, n1, n2);
  LocalDeformation d;
  d.length = k.l;
  d.valid = k.valid;
  if (!k.valid) return d;
  d.frame << k.e1, k.e2, k.e3;
  d.u = k.u;
  d.theta1 = k.theta[0];
  d.theta2 = k.theta[1];
  return d;
}

namespace {

// f_l = elasticity + beta K_l edot_l, edot_l = B [v1; omega1; v2; omega2]
// (the damping stays proportional to the linear local stiffness).
Vec7 localForce(const CorotationalBeam& beam, const Kinematics& k, const Vec12& v, double dampingBeta) {
  const Mat7& Kl = beam.localStiffness;
  Vec7 fl = localElasticForce(beam, localDeformationVector(k));
  if (dampingBeta != 0.0) fl += dampingBeta * localStiffnessTimes(Kl, strainIncrement(beam, k, v));
  return fl;
}

Vec12 nodeVelocities(const NodeVelocity& v1, const NodeVelocity& v2) {
  Vec12 v;
  v << v1.v, v1.omega, v2.v, v2.omega;
  return v;
}

Vector3<double> fromEigen(const Vec3& a) { return {a.x(), a.y(), a.z()}; }
Vec3 toEigen(const Vector3<double>& a) { return Vec3(a.x, a.y, a.z); }
Matrix3<double> fromEigen(const Mat3& M) {
  return {{fromEigen(Vec3(M.col(0))), fromEigen(Vec3(M.col(1))), fromEigen(Vec3(M.col(2)))}};
}

}  // namespace

ElementState<double> elementState(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                                  const NodeVelocity& v1, const NodeVelocity& v2) {
  ElementState<double> s;
  s.R[0] = fromEigen(beam.identityC1 ? n1.A : Mat3(n1.A * beam.C1));
  s.R[1] = fromEigen(beam.identityC2 ? n2.A : Mat3(n2.A * beam.C2));
  s.chord = fromEigen(Vec3(n2.r - n1.r));
  s.chordRate = fromEigen(Vec3(v2.v - v1.v));
  s.spin[0] = fromEigen(beam.identityC1 ? v1.omega : Vec3(beam.C1.transpose() * v1.omega));
  s.spin[1] = fromEigen(beam.identityC2 ? v2.omega : Vec3(beam.C2.transpose() * v2.omega));
  return s;
}

// With the inertia's accelerations (gravity subtracted).
ElementState<double> elementState(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                                  const NodeVelocity& v1, const NodeVelocity& v2, const NodeAcceleration& a1,
                                  const NodeAcceleration& a2, const Vec3& gravity) {
  ElementState<double> s = elementState(beam, n1, n2, v1, v2);
  s.chordAcceleration = fromEigen(Vec3(a2.a - a1.a));
  s.spinRate[0] = fromEigen(beam.identityC1 ? a1.omegaDot : Vec3(beam.C1.transpose() * a1.omegaDot));
  s.spinRate[1] = fromEigen(beam.identityC2 ? a2.omegaDot : Vec3(beam.C2.transpose() * a2.omegaDot));
  s.acceleration[0] = fromEigen(Vec3(a1.a - gravity));
  s.acceleration[1] = fromEigen(Vec3(a2.a - gravity));
  return s;
}

// f = [force_1; C1 moment_1; force_2; C2 moment_2].
void storeForce(const CorotationalBeam& beam, const ElementForce<double>& out, Vec12& f) {
  const Vec3 m1 = toEigen(out.moment[0]), m2 = toEigen(out.moment[1]);
  f << toEigen(out.force[0]), beam.identityC1 ? m1 : Vec3(beam.C1 * m1), toEigen(out.force[1]),
      beam.identityC2 ? m2 : Vec3(beam.C2 * m2);
}

namespace {

// logSO3(Rr^T R), Rr = [e1 e2 e3]: for local rotations beyond the series,
// lane by lane.
Vector3<double> relativeLog(const Vector3<double>& e1, const Vector3<double>& e2, const Vector3<double>& e3,
                            const Matrix3<double>& R) {
  Mat3 Rr, A;
  Rr << toEigen(e1), toEigen(e2), toEigen(e3);
  A << toEigen(R.col[0]), toEigen(R.col[1]), toEigen(R.col[2]);
  return fromEigen(logSO3(Rr.transpose() * A));
}

Vector3<Lanes> relativeLog(const Vector3<Lanes>& e1, const Vector3<Lanes>& e2, const Vector3<Lanes>& e3,
                           const Matrix3<Lanes>& R) {
  Vector3<Lanes> out;
  for (int i = 0; i < Lanes::kCount; ++i)
    setLane(out, i, relativeLog(lane(e1, i), lane(e2, i), lane(e3, i), lane(R, i)));
  return out;
}

// Rotation vector of the small local rotation Rr^T R (the element's
// deformation), from the trace and the skew part alone: the series of
// math/rotation.cpp's logSO3 below 0.2 rad, without forming the product.
template <class T>
Vector3<T> localRotation(const Vector3<T>& e1, const Vector3<T>& e2, const Vector3<T>& e3, const Matrix3<T>& R) {
  const Vector3<T>&c0 = R.col[0], &c1 = R.col[1], &c2 = R.col[2];
  const T cosT = (dot(e1, c0) + dot(e2, c1) + dot(e3, c2) - T(1.0)) * T(0.5);
  const Vector3<T> w{T(0.5) * (dot(e3, c1) - dot(e2, c2)), T(0.5) * (dot(e1, c2) - dot(e3, c0)),
                     T(0.5) * (dot(e2, c0) - dot(e1, c1))};
  const T s2 = squaredNorm(w);
  if (!(allGreater(cosT, 0.0) && allLess(s2, 0.04))) return relativeLog(e1, e2, e3, R);
  static constexpr double c[11] = {1.0, 1.0 / 6.0, 3.0 / 40.0, 5.0 / 112.0, 35.0 / 1152.0, 63.0 / 2816.0,
                                   231.0 / 13312.0, 143.0 / 10240.0, 6435.0 / 557056.0, 12155.0 / 1245184.0,
                                   46189.0 / 5505024.0};
  // Below 1e-3 rad three terms reach 1e-19 (the usual case); above, the
  // series in two halves (Estrin) for a shorter dependency chain.
  if (allLess(s2, 1e-6)) return (T(c[0]) + s2 * (T(c[1]) + s2 * T(c[2]))) * w;
  const T s4 = s2 * s2, s10 = s4 * s4 * s2;
  const T low = (T(c[0]) + s2 * T(c[1])) + s4 * ((T(c[2]) + s2 * T(c[3])) + s4 * T(c[4]));
  const T high = (T(c[5]) + s2 * T(c[6])) + s4 * ((T(c[7]) + s2 * T(c[8])) + s4 * (T(c[9]) + s2 * T(c[10])));
  return (low + s10 * high) * w;
}

// e(t) of T^-1 (inverseTangentCoefficients) alone; beyond the short series
// lane by lane.
double inverseTangentEBeyondSeries(double t2) { return inverseTangentCoefficients(t2).e; }
Lanes inverseTangentEBeyondSeries(Lanes t2) {
  Lanes e;
  for (int i = 0; i < Lanes::kCount; ++i) e.set(i, inverseTangentCoefficients(t2[i]).e);
  return e;
}

template <class T>
T inverseTangentE(const Vector3<T>& theta) {
  const T t2 = squaredNorm(theta);
  if (allLess(t2, 1e-4))  // next term < 1e-17 relative
    return T(1.0 / 12.0) + t2 * (T(1.0 / 720.0) + t2 * T(1.0 / 30240.0));
  return inverseTangentEBeyondSeries(t2);
}

// T^-1 y and T^-T y without forming T^-1 = e theta theta^T + S/2 + (1 - e t^2) I.
template <class T>
Vector3<T> inverseTangentTimes(const Vector3<T>& theta, const T& e, const Vector3<T>& y, bool transposed) {
  const Vector3<T> half = T(0.5) * cross(theta, y);
  return (T(1.0) - e * squaredNorm(theta)) * y + (e * dot(theta, y)) * theta + (transposed ? -half : half);
}

// The same f as internalForces (corotatedFrame, localForce,
// strainMapTranspose), written for the residual's element loop: no
// Kinematics workspace, no tangent-operator matrices, products with the
// frame taken as dot products, the local rotations by localRotation.
// False when the corotated frame is undefined or the force not finite (in
// any lane).
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
  const Vector3<T> theta0 = localRotation(e1, e2, e3, R0), theta1 = localRotation(e1, e2, e3, R1);
  const T tangent0 = inverseTangentE(theta0), tangent1 = inverseTangentE(theta1);
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

}  // namespace

bool internalForceVector(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                         const NodeVelocity& v1, const NodeVelocity& v2, double dampingBeta, Vec12& f) {
  ElementForce<double> out;
  if (!elementForce(elementState(beam, n1, n2, v1, v2), elementConstants(beam, dampingBeta), out)) return false;
  storeForce(beam, out, f);
  return true;
}

namespace {

// Four elements side by side in vector lanes (math/lanes.hpp): gathered,
// computed, stored. Inlined into each of the two variants below.
[[gnu::always_inline]] inline bool elementForcesInLanes(int count, const ElementInputs elements[],
                                                        const Vec3& gravity, Vec12 f[]) {
  ElementState<Lanes> s;
  ElementConstants<Lanes> k;
  static const NodeAcceleration still;
  for (int i = 0; i < Lanes::kCount; ++i) {
    const ElementInputs& e = elements[std::min(i, count - 1)];  // spare lanes repeat the last element
    const bool inertia = e.mass > 0.0;
    const ElementState<double> one =
        elementState(*e.beam, *e.pose1, *e.pose2, *e.velocity1, *e.velocity2, inertia ? *e.acceleration1 : still,
                     inertia ? *e.acceleration2 : still, gravity);
    for (int j = 0; j < 2; ++j) {
      for (int c = 0; c < 3; ++c) setLane(s.R[j].col[c], i, one.R[j].col[c]);
      setLane(s.spin[j], i, one.spin[j]);
      setLane(s.spinRate[j], i, one.spinRate[j]);
      setLane(s.acceleration[j], i, one.acceleration[j]);
    }
    setLane(s.chord, i, one.chord);
    setLane(s.chordRate, i, one.chordRate);
    setLane(s.chordAcceleration, i, one.chordAcceleration);
    const ElementConstants<double> c = elementConstants(*e.beam, e.damping);
    k.L0.set(i, c.L0);
    k.EA.set(i, c.EA);
    k.damping.set(i, c.damping);
    k.mass.set(i, e.mass);
    for (int j = 0; j < 7; ++j) {
      k.diagonal[j].set(i, c.diagonal[j]);
      k.pair[j].set(i, c.pair[j]);
    }
  }
  ElementForce<Lanes> out;
  if (!elementForce(s, k, out)) return false;
  for (int i = 0; i < count; ++i)
    storeForce(*elements[i].beam,
               {{lane(out.force[0], i), lane(out.force[1], i)}, {lane(out.moment[0], i), lane(out.moment[1], i)}},
               f[i]);
  return true;
}

}  // namespace

// Flattened: every kernel function inlined. The baseline x86-64 variant
// does an operation on four lanes as two SSE2 instructions, the AVX2 one as
// one; AVX2 alone, without FMA: the same operations, rounded alike, so both
// give the same numbers to the bit (a fused multiply-add would not).
[[gnu::flatten]] bool elementForceVectorsBaseline(int count, const ElementInputs elements[], const Vec3& gravity,
                                                  Vec12 f[]) {
  return elementForcesInLanes(count, elements, gravity, f);
}

[[gnu::flatten]] __attribute__((target("avx2"))) bool elementForceVectorsAvx2(int count,
                                                                               const ElementInputs elements[],
                                                                               const Vec3& gravity, Vec12 f[]) {
  return elementForcesInLanes(count, elements, gravity, f);
}

bool hasAvx2() {
  static const bool avx2 = [] {
    __builtin_cpu_init();  // harmless if done; needed if asked before the library's constructors ran
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return avx2;
}

bool elementForceVectors(int count, const ElementInputs elements[], const Vec3& gravity, Vec12 f[]) {
  return hasAvx2() ? elementForceVectorsAvx2(count, elements, gravity, f)
                   : elementForceVectorsBaseline(count, elements, gravity, f);
}

BeamForces internalForces(const CorotationalBeam& beam, const NodePose& n1,
                          const NodePose& n2, const NodeVelocity& v1,
                          const NodeVelocity& v2, double dampingBeta, bool withTangent) {
  BeamForces out;
  Kinematics k = corotatedFrame(beam, n1, n2);
  if (!k.valid) return out;
  const Vec12 v = nodeVelocities(v1, v2);
  const Vec7 fl = localForce(beam, k, v, dampingBeta);
  out.f = strainMapTranspose(beam, k, fl);
  if (!withTangent) {
    out.valid = out.f.allFinite();
    return out;
  }
  tangentMaps(beam, k);
  // B^T K_t B with K_t = K_l + localTangentExcess taken apart (ArchTangent):
  // the bowing joins K_l's sparse pairs, the gradient part is a rank-one
  // update less the axial entry K_l already has. Small products:
  // coefficient-wise (lazyProduct), not Eigen's blocked GEMM.
  const ArchTangent arch = archTangent(beam, localDeformationVector(k));
  Mat7 pairs = beam.localStiffness;
  addBowingStiffness(arch.NL0, pairs);
  out.K = k.B.transpose().lazyProduct(localStiffnessTimes(pairs, k.B));
  const Vec12 gradient = k.B.transpose() * arch.gradient;
  const Vec12 axial = k.B.row(0).transpose();
  out.K.noalias() += arch.EAL0 * gradient * gradient.transpose();
  out.K.noalias() -= (arch.EAL0 * arch.gradient[0] * arch.gradient[0]) * axial * axial.transpose();
  Eigen::Matrix<double, 12, 7> BtKl = Eigen::Matrix<double, 12, 7>::Zero();  // damping only
  if (dampingBeta != 0.0) {
    BtKl = localStiffnessTimes(beam.localStiffness, k.B).transpose();
    out.C = dampingBeta * BtKl.lazyProduct(k.B);
  }
  addGeometricStiffness(beam, k, fl, v, dampingBeta, BtKl, out.K);
  out.valid = out.f.allFinite() && out.K.allFinite();
  return out;
}

SectionForces sectionForces(const CorotationalBeam& beam, const NodePose& n1,
                            const NodePose& n2, const Vec12& f) {
  const LocalDeformation d = localDeformation(beam, n1, n2);
  // Undefined corotated frame: fall back to node 1's copy of the element frame.
  const Mat3 Rt = (d.valid ? d.frame : Mat3(n1.A * beam.C1)).transpose();
  SectionForces s;
  // f holds what the nodes exert on the element: at x = l that is the
  // resultant of the part beyond; at x = 0 its opposite. Moments go from
  // node frame to world to element frame.
  s.force1 = -Rt * f.segment<3>(0);
  s.moment1 = -Rt * (n1.A * f.segment<3>(3));
  s.force2 = Rt * f.segment<3>(6);
  s.moment2 = Rt * (n2.A * f.segment<3>(9));
  return s;
}

NodalInertia lumpedNodalInertia(const CorotationalBeam& beam, int node) {
  if (node != 1 && node != 2) {
    throw std::invalid_argument("lumpedNodalInertia: node must be 1 or 2");
  }
  const Mat3& C = node == 1 ? beam.C1 : beam.C2;
  const double half = 0.5 * beam.L0;
  NodalInertia inertia;
  inertia.m = beam.section.rhoA * half;
  inertia.J = C * beam.section.rhoJ.asDiagonal() * C.transpose() * half;
  return inertia;
}

}  // namespace mfbd
