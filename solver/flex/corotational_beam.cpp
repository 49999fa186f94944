#include "flex/corotational_beam.hpp"

#include <cmath>
#include <stdexcept>

namespace mfbd {

namespace {

using Mat3x12 = Eigen::Matrix<double, 3, 12>;
using Mat7x12 = Eigen::Matrix<double, 7, 12>;

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
// Derivative of the inverse tangent T^-1(theta) = I + S/2 + e(t) S^2
// (S = skew(theta), t = |theta|, e = (1 - (t/2) cot(t/2)) / t^2, see
// math/rotation.cpp) in the direction dtheta:
//   dT^-1 = skew(dtheta)/2 + e (skew(dtheta) S + S skew(dtheta))
//           + (e'(t)/t) (theta . dtheta) S^2.
// The closed forms of e and e'/t cancel badly for small t (e'/t loses ~1e-9
// at t = 0.3); below 0.3 use the Taylor series, e = sum_n |B_2n|/(2n)! t^(2n-2)
// (from x cot x), truncated where the next term is below 1e-12 relative.
// ---------------------------------------------------------------------------
Mat3 inverseTangentDerivative(const Vec3& theta, const Vec3& dtheta) {
  const double t = theta.norm(), t2 = t * t;
  double e, dEoverT;
  if (t < 0.3) {
    const double c[5] = {1.0 / 720.0, 1.0 / 30240.0, 1.0 / 1209600.0, 1.0 / 47900160.0,
                         691.0 / 1307674368000.0};  // t^2 .. t^10 of e
    e = 1.0 / 12.0 + t2 * (c[0] + t2 * (c[1] + t2 * (c[2] + t2 * (c[3] + t2 * c[4]))));
    dEoverT = 2 * c[0] + t2 * (4 * c[1] + t2 * (6 * c[2] + t2 * (8 * c[3] + t2 * 10 * c[4])));
  } else {
    const double cotHalf = 1.0 / std::tan(0.5 * t), sinHalf = std::sin(0.5 * t);
    e = (1.0 - 0.5 * t * cotHalf) / t2;
    dEoverT = -2.0 / (t2 * t2) + cotHalf / (2.0 * t2 * t) + 1.0 / (4.0 * t2 * sinHalf * sinHalf);
  }
  const Mat3 S = skew(theta), dS = skew(dtheta);
  return 0.5 * dS + e * (dS * S + S * dS) + dEoverT * theta.dot(dtheta) * S * S;
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
  double l = 0.0;
  Vec3 q[2], qMean;
  double qx = 0.0, qy = 0.0, eta = 0.0;  // qMean = qx e1 + qy e2, eta = qx/qy
  Vec3 theta[2];                         // local rotations log(Rr^T R_i)
  Mat3 Tinv[2];
  double u = 0.0;  // elongation
  // Tangent maps, all acting on dq = [dr1; dtheta1; dr2; dtheta2]:
  Mat3x12 P;     // spin of the corotated frame (world), dw_r = P dq
  Mat3x12 X[2];  // R_i^T (dw_i - dw_r) = X_i dq, so dtheta_i = Tinv_i X_i dq
  Mat7x12 B;     // de_l = B dq
};

Kinematics corotatedFrame(const CorotationalBeam& beam, const NodePose& n1,
                          const NodePose& n2) {
  Kinematics k;
  k.A[0] = n1.A;
  k.A[1] = n2.A;
  k.R[0] = n1.A * beam.C1;
  k.R[1] = n2.A * beam.C2;
  const Vec3 x = n2.r - n1.r;
  k.l = x.norm();
  if (!(k.l > 1e-9 * beam.L0)) return k;
  k.e1 = x / k.l;
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
  }
  // l - L0 without cancellation when l ~ L0
  k.u = (x.squaredNorm() - beam.L0 * beam.L0) / (k.l + beam.L0);
  k.valid = std::isfinite(k.u) && k.theta[0].allFinite() && k.theta[1].allFinite();
  return k;
}

// Chord part of the frame spin, dw_r = Pr (dr2 - dr1) + ...: the components
// e2.dw_r = -e3.(dr2-dr1)/l, e3.dw_r = e2.(dr2-dr1)/l of the chord's rotation
// and the chord part -eta e3.(dr2-dr1)/l of the twist e1.dw_r.
Mat3 chordSpin(const Vec3& e1, const Vec3& e2, const Vec3& e3, double eta, double l) {
  return (-eta * e1 * e3.transpose() - e2 * e3.transpose() + e3 * e2.transpose()) / l;
}

// Twist part of the frame spin: e1.dw_r gets (q_i x e3).dw_i / (2 qy) from
// node i's world spin dw_i (rotation of q's projection about e1).
Vec3 twistRow(const Kinematics& k, int i) { return k.q[i].cross(k.e3) / (2.0 * k.qy); }

void tangentMaps(const CorotationalBeam& beam, Kinematics& k) {
  const Mat3 Pr = chordSpin(k.e1, k.e2, k.e3, k.eta, k.l);
  k.P.setZero();
  k.P.block<3, 3>(0, 0) = -Pr;
  k.P.block<3, 3>(0, 6) = Pr;
  for (int i = 0; i < 2; ++i) {
    // dw_i = A_i dtheta_i
    k.P.block<3, 3>(0, 3 + 6 * i) = k.e1 * (k.A[i].transpose() * twistRow(k, i)).transpose();
  }
  const Mat3 C[2] = {beam.C1, beam.C2};
  k.B.setZero();
  k.B.block<1, 3>(0, 0) = -k.e1.transpose();
  k.B.block<1, 3>(0, 6) = k.e1.transpose();
  for (int i = 0; i < 2; ++i) {
    // R_i^T dw_i = C_i^T A_i^T A_i dtheta_i = C_i^T dtheta_i
    k.X[i] = -k.R[i].transpose() * k.P;
    k.X[i].block<3, 3>(0, 3 + 6 * i) += C[i].transpose();
    k.B.middleRows<3>(1 + 3 * i) = k.Tinv[i] * k.X[i];
  }
}

// Directional derivative of B along the increment dq (same increments as the
// tangent), obtained by varying every quantity in tangentMaps.
Mat7x12 strainMapVariation(const Kinematics& k, const Vec12& dq) {
  const Vec3 dr = dq.segment<3>(6) - dq.segment<3>(0);
  const Vec3 dth[2] = {dq.segment<3>(3), dq.segment<3>(9)};
  const Vec3 dw[2] = {k.A[0] * dth[0], k.A[1] * dth[1]};
  const Vec3 dwr = k.P * dq;
  const Vec3 de1 = dwr.cross(k.e1), de2 = dwr.cross(k.e2), de3 = dwr.cross(k.e3);
  const double dl = k.e1.dot(dr);
  const Vec3 dqi[2] = {dw[0].cross(k.q[0]), dw[1].cross(k.q[1])};
  const Vec3 dqMean = 0.5 * (dqi[0] + dqi[1]);
  const double dqx = dqMean.dot(k.e1) + k.qMean.dot(de1);
  const double dqy = dqMean.dot(k.e2) + k.qMean.dot(de2);
  const double deta = (dqx - k.eta * dqy) / k.qy;

  // l Pr = -eta e1 e3^T - e2 e3^T + e3 e2^T, varied term by term
  const Mat3 dE13 = de1 * k.e3.transpose() + k.e1 * de3.transpose();
  const Mat3 dE23 = de2 * k.e3.transpose() + k.e2 * de3.transpose();
  const Mat3 dPr = (-dl * chordSpin(k.e1, k.e2, k.e3, k.eta, k.l) -
                    deta * k.e1 * k.e3.transpose() - k.eta * dE13 - dE23 + dE23.transpose()) / k.l;
  Mat3x12 dP = Mat3x12::Zero();
  dP.block<3, 3>(0, 0) = -dPr;
  dP.block<3, 3>(0, 6) = dPr;
  for (int i = 0; i < 2; ++i) {
    const Vec3 t = twistRow(k, i);
    const Vec3 dt =
        -dqy / k.qy * t + (dqi[i].cross(k.e3) + k.q[i].cross(de3)) / (2.0 * k.qy);
    const Vec3 AtT = k.A[i].transpose() * t;
    // d(A^T t) = A^T dt - skew(dtheta) A^T t   (dA = A skew(dtheta))
    const Vec3 dAtT = k.A[i].transpose() * dt - dth[i].cross(AtT);
    dP.block<3, 3>(0, 3 + 6 * i) = de1 * AtT.transpose() + k.e1 * dAtT.transpose();
  }

  Mat7x12 dB = Mat7x12::Zero();
  dB.block<1, 3>(0, 0) = -de1.transpose();
  dB.block<1, 3>(0, 6) = de1.transpose();
  for (int i = 0; i < 2; ++i) {
    // X_i = C_i^T E_i - R_i^T P, dR_i^T = -R_i^T skew(dw_i)
    const Mat3x12 dX = k.R[i].transpose() * (skew(dw[i]) * k.P - dP);
    const Vec3 dtheta = k.B.middleRows<3>(1 + 3 * i) * dq;
    dB.middleRows<3>(1 + 3 * i) =
        inverseTangentDerivative(k.theta[i], dtheta) * k.X[i] + k.Tinv[i] * dX;
  }
  return dB;
}

Vec7 localDeformationVector(const Kinematics& k) {
  Vec7 e;
  e << k.u, k.theta[0], k.theta[1];
  return e;
}

}  // namespace

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

BeamForces internalForces(const CorotationalBeam& beam, const NodePose& n1,
                          const NodePose& n2, const NodeVelocity& v1,
                          const NodeVelocity& v2, double dampingBeta, bool withTangent) {
  BeamForces out;
  Kinematics k = corotatedFrame(beam, n1, n2);
  if (!k.valid) return out;
  tangentMaps(beam, k);
  const Mat7& Kl = beam.localStiffness;
  Vec12 v;
  v << v1.v, v1.omega, v2.v, v2.omega;
  const Vec7 eDot = k.B * v;  // rates of the local deformations
  const Vec7 fl = Kl * localDeformationVector(k) + dampingBeta * (Kl * eDot);
  out.f = k.B.transpose() * fl;
  if (!withTangent) {
    out.valid = out.f.allFinite();
    return out;
  }
  const Eigen::Matrix<double, 12, 7> BtKl = k.B.transpose() * Kl;
  out.C = dampingBeta * BtKl * k.B;
  out.K = BtKl * k.B;
  // Geometric part d(B^T)/dq f_l, column by column; with damping also the
  // position dependence of edot = B(q) v at fixed v. Both exact.
  for (int c = 0; c < 12; ++c) {
    const Mat7x12 dB = strainMapVariation(k, Vec12::Unit(c));
    out.K.col(c) += dB.transpose() * fl;
    if (dampingBeta != 0.0) out.K.col(c) += dampingBeta * BtKl * (dB * v);
  }
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
