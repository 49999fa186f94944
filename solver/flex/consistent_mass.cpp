#include "flex/consistent_mass.hpp"

namespace mfbd {

namespace {

using Mat3x12 = Eigen::Matrix<double, 3, 12>;


// The chord c = r2 - r1 and its direction e = c / l with their rates:
// edot = P cdot / l and eddot = (P cddot - 2 edot ldot - e (edot . cdot)) / l,
// P = I - e e^T, ldot = e . cdot.
struct Chord {
  Vec3 e, cdot, cddot, eDot, eDdot;
  Mat3 P;
  double l = 0.0, lDot = 0.0, s = 0.0;  // s = edot . cdot
};

Chord chord(const NodePose& n1, const NodeVelocity& v1, const NodeAcceleration& a1, const NodePose& n2,
            const NodeVelocity& v2, const NodeAcceleration& a2) {
  Chord c;
  const Vec3 x = n2.r - n1.r;
  c.l = x.norm();
  c.e = x / c.l;
  c.P = Mat3::Identity() - c.e * c.e.transpose();
  c.cdot = v2.v - v1.v;
  c.cddot = a2.a - a1.a;
  c.eDot = c.P * c.cdot / c.l;
  c.lDot = c.e.dot(c.cdot);
  c.s = c.eDot.dot(c.cdot);
  c.eDdot = (c.P * c.cddot - 2.0 * c.lDot * c.eDot - c.s * c.e) / c.l;
  return c;
}

// What the inertia of the element needs from one node.
struct NodeTerms {
  Vec3 d;      // element axis in the node frame, C e1
  Vec3 local;  // L0 (omegadot x d + omega x (omega x d)), node frame: tddot L0 there
};

NodeTerms nodeTerms(const Mat3& C, double L0, const NodeVelocity& v, const NodeAcceleration& a) {
  const Vec3 d = C.col(0);
  return {d, L0 * (a.omegaDot.cross(d) + v.omega.cross(v.omega.cross(d)))};
}

// F = M_p (pddot - g_p) on [r1; r2; b1; b2] (world vectors; `mass` / 420 x kConsistentShape).
template <class Block>
std::array<Block, 4> shapeTimes(double mass, const std::array<Block, 4>& p) {
  const double m = mass / 420.0;
  std::array<Block, 4> F;
  for (int k = 0; k < 4; ++k)
    F[k] = m * (kConsistentShape[k][0] * p[0] + kConsistentShape[k][1] * p[1] + kConsistentShape[k][2] * p[2] +
                kConsistentShape[k][3] * p[3]);
  return F;
}

// The virtual displacements' map transposed, J^T F: dp = J dq with
//   dr_i, db_i = L0 A_i (dtheta_i x d_i) - (L0 / l) P (dr2 - dr1),
// so the forces are [F1 + k; L0 d1 x (A1^T G1); F2 - k; L0 d2 x (A2^T G2)],
// k = (L0 / l) P (G1 + G2). For 3-vectors or 3 x 12 blocks alike.
template <class Block>
Eigen::Matrix<double, 12, Block::ColsAtCompileTime> mapTranspose(const std::array<Block, 4>& F, double L0,
                                                                  const Chord& c, const Mat3 A[2], const Vec3 d[2]) {
  Eigen::Matrix<double, 12, Block::ColsAtCompileTime> f;
  const Block k = (L0 / c.l) * (c.P * (F[2] + F[3]));
  f.template middleRows<3>(0) = F[0] + k;
  f.template middleRows<3>(6) = F[1] - k;
  for (int i = 0; i < 2; ++i) f.template middleRows<3>(3 + 6 * i) = L0 * skew(d[i]) * (A[i].transpose() * F[2 + i]);
  return f;
}

}  // namespace

// The one-element use of addInertiaForce (the residual's kernel, four
// elements at a time in elementForceVectors).
Vec12 consistentInertiaForce(const CorotationalBeam& beam, double mass, const NodePose& n1, const NodeVelocity& v1,
                             const NodeAcceleration& a1, const NodePose& n2, const NodeVelocity& v2,
                             const NodeAcceleration& a2, const Vec3& gravity) {
  ElementForce<double> out{};
  addInertiaForce(elementState(beam, n1, n2, v1, v2, a1, a2, gravity), beam.L0, mass, out);
  Vec12 f;
  storeForce(beam, out, f);
  return f;
}

ConsistentInertia consistentInertia(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                    const NodeVelocity& v1, const NodeAcceleration& a1, const NodePose& n2,
                                    const NodeVelocity& v2, const NodeAcceleration& a2, const Vec3& gravity,
                                    double cM, double cC, double cK) {
  const double L0 = beam.L0;
  const Chord c = chord(n1, v1, a1, n2, v2, a2);
  const NodeTerms t[2] = {nodeTerms(beam.C1, L0, v1, a1), nodeTerms(beam.C2, L0, v2, a2)};
  const Mat3 A[2] = {n1.A, n2.A};
  const Vec3 d[2] = {t[0].d, t[1].d};
  const NodeVelocity* vel[2] = {&v1, &v2};
  const std::array<Vec3, 4> pddot{
      {a1.a - gravity, a2.a - gravity, n1.A * t[0].local - L0 * c.eDdot, n2.A * t[1].local - L0 * c.eDdot}};
  const std::array<Vec3, 4> F = shapeTimes(mass, pddot);
  ConsistentInertia out;
  out.f = mapTranspose(F, L0, c, A, d);

  // Derivatives of eddot (Chord's formula) with respect to cddot, cdot
  // and c, with D_edot = d edot / dc = -(ldot P / l + e edot^T + edot e^T) / l.
  const double l = c.l;
  const Mat3 dEdot = -(c.lDot / l * c.P + c.e * c.eDot.transpose() + c.eDot * c.e.transpose()) / l;
  const Mat3 eddotByCddot = c.P / l;
  const Mat3 eddotByCdot = -2.0 * (c.lDot / l * c.P + c.eDot * c.e.transpose() + c.e * c.eDot.transpose()) / l;
  const Mat3 eddotByC =
      -(c.e.dot(c.cddot) * c.P + c.e * (c.P * c.cddot).transpose() + c.P * c.cddot * c.e.transpose()) / (l * l) -
      2.0 * (c.lDot / l * dEdot + c.eDot * c.eDot.transpose() / l - c.lDot / (l * l) * c.eDot * c.e.transpose()) -
      (c.s / (l * l) * c.P + c.e * (c.cdot.transpose() * dEdot) / l - c.s / (l * l) * c.e * c.e.transpose());

  // cM d/d[a; omegadot] + cC d/d[v; omega] + cK d/d[dr; dtheta] of pddot,
  // 4 blocks of 3 x 12 over [r1; theta1; r2; theta2] (b_i = L0 (A_i d_i - e):
  // its chord part is the same in both bubbles). J^T M_p J of it is the
  // tangent, less the map's own turning (added below).
  std::array<Mat3x12, 4> J;
  for (Mat3x12& b : J) b.setZero();
  J[0].block<3, 3>(0, 0) = cM * Mat3::Identity();
  J[1].block<3, 3>(0, 6) = cM * Mat3::Identity();
  // -L0 eddot with c = r2 - r1: + on r1's columns, - on r2's.
  const Mat3 byChord = L0 * (cM * eddotByCddot + cC * eddotByCdot + cK * eddotByC);
  for (int i = 0; i < 2; ++i) {
    Mat3x12& b = J[2 + i];
    const Vec3& w = vel[i]->omega;
    b.block<3, 3>(0, 0) = byChord;
    b.block<3, 3>(0, 6) = -byChord;
    // L0 A (omegadot x d + omega x (omega x d)): W on omegadot, V on omega,
    // and -A skew(local) as the node turns.
    b.block<3, 3>(0, 3 + 6 * i) =
        A[i] * (-cM * L0 * skew(d[i]) +
                cC * L0 * (w * d[i].transpose() + w.dot(d[i]) * Mat3::Identity() - 2.0 * d[i] * w.transpose()) -
                cK * skew(t[i].local));
  }
  out.S = mapTranspose(shapeTimes(mass, J), L0, c, A, d);
  // The map itself turns: k = (L0 / l) P G (G = G1 + G2) with the chord,
  // d(P G / l)/dc = -((e . G) P + e G^T P + P G e^T) / l^2; and
  // L0 d_i x (A_i^T G_i) with node i.
  const Vec3 G = F[2] + F[3];
  if (cK == 0.0) return out;
  const Mat3 dk =
      -cK * L0 * (c.e.dot(G) * c.P + c.e * (c.P * G).transpose() + c.P * G * c.e.transpose()) / (l * l);
  out.S.block<3, 3>(0, 0) -= dk;
  out.S.block<3, 3>(0, 6) += dk;
  out.S.block<3, 3>(6, 0) += dk;
  out.S.block<3, 3>(6, 6) -= dk;
  for (int i = 0; i < 2; ++i)
    out.S.block<3, 3>(3 + 6 * i, 3 + 6 * i) += cK * L0 * skew(d[i]) * skew(A[i].transpose() * F[2 + i]);
  return out;
}

ConsistentEnergy consistentEnergy(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                  const NodeVelocity& v1, const NodePose& n2, const NodeVelocity& v2,
                                  const Vec3& gravity) {
  const double L0 = beam.L0;
  const Vec3 d1 = beam.C1.col(0), d2 = beam.C2.col(0);
  const Chord c = chord(n1, v1, {}, n2, v2, {});
  const std::array<Vec3, 4> pdot{{v1.v, v2.v, L0 * (n1.A * v1.omega.cross(d1) - c.eDot),
                                  L0 * (n2.A * v2.omega.cross(d2) - c.eDot)}};
  ConsistentEnergy e;
  for (int k = 0; k < 4; ++k)
    for (int m = 0; m < 4; ++m) e.kinetic += 0.5 * mass / 420.0 * kConsistentShape[k][m] * pdot[k].dot(pdot[m]);
  // int r = (r1 + r2) / 2 + (b1 - b2) / 12, b_i = L0 (A_i d_i - e)
  const Vec3 b1 = L0 * (n1.A * d1 - c.e), b2 = L0 * (n2.A * d2 - c.e);
  e.gravity = -mass * gravity.dot(0.5 * (n1.r + n2.r) + (b1 - b2) / 12.0);
  return e;
}

}  // namespace mfbd
