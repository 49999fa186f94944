#include "flex/corotational_beam.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flex/consistent_mass.hpp"
#include "flex/corotational_force.hpp"
#include "flex/element_state.hpp"

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
    k.Tinv[i] = tangentSO3Inverse(k.theta[i]);
    // dw_i = A_i dtheta_i, so e1.dw_r gets twistRow . A_i dtheta_i
    k.twist[i] = k.A[i].transpose() * twistRow(k, i);
  }
  // l - L0 without cancellation when l ~ L0
  k.u = (x.squaredNorm() - beam.L0 * beam.L0) / (k.l + beam.L0);
  k.valid = std::isfinite(k.u) && k.theta[0].allFinite() && k.theta[1].allFinite();
  return k;
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
    const Mat3x12 Y = tangentSO3InverseDerivative(k.theta[i], flRotation, true) * dStrain[i];
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
  const Vec3 spinRate = k.P * v;
  const Mat3x12 dSpinRate = frameSpinDerivative(k, d, v);
  Eigen::Matrix<double, 7, 12> dStrainRate;
  dStrainRate.row(0) = (v.segment<3>(6) - v.segment<3>(0)).transpose() * d.dE1;
  for (int i = 0; i < 2; ++i) {
    Mat3x12 dRelativeSpin = -dSpinRate;  // dw_i x P v - dP v
    dRelativeSpin.block<3, 3>(0, 3 + 6 * i) -= skew(spinRate) * k.A[i];
    dStrainRate.middleRows<3>(1 + 3 * i) =
        tangentSO3InverseDerivative(k.theta[i], k.X[i] * v, false) * dStrain[i] +
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

double archStrain(const Vec7& e, Vec7& gradient) { return mfbd::archStrain<double>(e, gradient); }

}  // namespace

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

// The local force f_l = elasticity + beta K_l edot_l, edot_l = B v (the
// damping stays proportional to the linear local stiffness), from the
// formed B (tangentMaps): the tangent's geometric part needs it.
Vec7 localForce(const CorotationalBeam& beam, const Kinematics& k, const Vec12& v, double dampingBeta) {
  Vec7 fl = localElasticForce(beam, localDeformationVector(k));
  if (dampingBeta != 0.0) fl += dampingBeta * localStiffnessTimes<1>(beam.localStiffness, k.B * v);
  return fl;
}

Vec12 nodeVelocities(const NodeVelocity& v1, const NodeVelocity& v2) {
  Vec12 v;
  v << v1.v, v1.omega, v2.v, v2.omega;
  return v;
}

}  // namespace

bool internalForceVector(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                         const NodeVelocity& v1, const NodeVelocity& v2, double dampingBeta, Vec12& f) {
  ElementForce<double> out;
  if (!elementForce(elementState(beam, n1, n2, v1, v2), elementConstants(beam, dampingBeta), out)) return false;
  storeForce(beam, out, f);
  return true;
}

BeamTangent internalForceTangent(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                                 const NodeVelocity& v1, const NodeVelocity& v2, double dampingBeta) {
  BeamTangent out;
  Kinematics k = corotatedFrame(beam, n1, n2);
  if (!k.valid) return out;
  tangentMaps(beam, k);
  const Vec12 v = nodeVelocities(v1, v2);
  const Vec7 fl = localForce(beam, k, v, dampingBeta);
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
  out.valid = out.K.allFinite();
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