#include "flex/consistent_mass.hpp"

namespace mfbd {

namespace {

// int_0^1 N N^T dxi of the Hermite functions on [r1; s1; r2; s2], times 420.
constexpr double kHermite[4][4] = {{156, 22, 54, -13}, {22, 4, 13, -3}, {54, 13, 156, -22}, {-13, -3, -22, 4}};

// What the inertia of the element needs from one node.
struct NodeTerms {
  Vec3 d;      // element axis in the node frame, C e1
  Vec3 sddot;  // L0 A (omegadot x d + omega x (omega x d)), world
  Vec3 b;      // the same in the node frame
};

NodeTerms nodeTerms(const Mat3& C, double L0, const NodePose& n, const NodeVelocity& v, const NodeAcceleration& a) {
  NodeTerms t;
  t.d = C.col(0);
  t.b = L0 * (a.omegaDot.cross(t.d) + v.omega.cross(v.omega.cross(t.d)));
  t.sddot = n.A * t.b;
  return t;
}

// F = M_p (pddot - g_p), the four world vectors on [r1; s1; r2; s2].
std::array<Vec3, 4> pForces(double mass, const Vec3& a1, const Vec3& s1, const Vec3& a2, const Vec3& s2,
                            const Vec3& gravity) {
  const std::array<Vec3, 4> p{{a1 - gravity, s1, a2 - gravity, s2}};
  std::array<Vec3, 4> F;
  const double m = mass / 420.0;
  for (int k = 0; k < 4; ++k)
    F[k] = m * (kHermite[k][0] * p[0] + kHermite[k][1] * p[1] + kHermite[k][2] * p[2] + kHermite[k][3] * p[3]);
  return F;
}

// f = W^T F: forces on the positions; on the rotations L0 d x (A^T F_s).
Vec12 generalized(const std::array<Vec3, 4>& F, double L0, const NodePose& n1, const Vec3& d1, const NodePose& n2,
                  const Vec3& d2) {
  Vec12 f;
  f.segment<3>(0) = F[0];
  f.segment<3>(3) = L0 * d1.cross(n1.A.transpose() * F[1]);
  f.segment<3>(6) = F[2];
  f.segment<3>(9) = L0 * d2.cross(n2.A.transpose() * F[3]);
  return f;
}

}  // namespace

Vec12 consistentInertiaForce(const CorotationalBeam& beam, double mass, const NodePose& n1, const NodeVelocity& v1,
                             const NodeAcceleration& a1, const NodePose& n2, const NodeVelocity& v2,
                             const NodeAcceleration& a2, const Vec3& gravity) {
  const NodeTerms t1 = nodeTerms(beam.C1, beam.L0, n1, v1, a1), t2 = nodeTerms(beam.C2, beam.L0, n2, v2, a2);
  return generalized(pForces(mass, a1.a, t1.sddot, a2.a, t2.sddot, gravity), beam.L0, n1, t1.d, n2, t2.d);
}

ConsistentInertia consistentInertia(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                    const NodeVelocity& v1, const NodeAcceleration& a1, const NodePose& n2,
                                    const NodeVelocity& v2, const NodeAcceleration& a2, const Vec3& gravity) {
  const double L0 = beam.L0;
  const NodeTerms t[2] = {nodeTerms(beam.C1, L0, n1, v1, a1), nodeTerms(beam.C2, L0, n2, v2, a2)};
  const NodePose* pose[2] = {&n1, &n2};
  const NodeVelocity* vel[2] = {&v1, &v2};
  const std::array<Vec3, 4> F = pForces(mass, a1.a, t[0].sddot, a2.a, t[1].sddot, gravity);
  ConsistentInertia out;
  out.f = generalized(F, L0, n1, t[0].d, n2, t[1].d);

  // Per node: W = d sdot / d omega = -L0 A skew(d); V = d sddot / d omega
  // = L0 A (omega d^T + (omega . d) I - 2 d omega^T); Q = d sddot / d theta
  // = -A skew(b) (the node turning under its own slope's acceleration).
  Mat3 W[2], V[2], Q[2];
  for (int i = 0; i < 2; ++i) {
    const Mat3& A = pose[i]->A;
    const Vec3& d = t[i].d;
    const Vec3& w = vel[i]->omega;
    W[i] = -L0 * A * skew(d);
    V[i] = L0 * A * (w * d.transpose() + w.dot(d) * Mat3::Identity() - 2.0 * d * w.transpose());
    Q[i] = -A * skew(t[i].b);
  }
  const double m = mass / 420.0;
  for (int i = 0; i < 2; ++i) {
    const int ri = 6 * i, ti = 6 * i + 3;
    for (int j = 0; j < 2; ++j) {
      const int rj = 6 * j, tj = 6 * j + 3;
      const double rr = m * kHermite[2 * i][2 * j], rs = m * kHermite[2 * i][2 * j + 1];
      const double sr = m * kHermite[2 * i + 1][2 * j], ss = m * kHermite[2 * i + 1][2 * j + 1];
      out.M.block<3, 3>(ri, rj) = rr * Mat3::Identity();
      out.M.block<3, 3>(ri, tj) = rs * W[j];
      out.M.block<3, 3>(ti, rj) = sr * W[i].transpose();
      out.M.block<3, 3>(ti, tj) = ss * W[i].transpose() * W[j];
      out.C.block<3, 3>(ri, tj) = rs * V[j];
      out.C.block<3, 3>(ti, tj) = ss * W[i].transpose() * V[j];
      out.K.block<3, 3>(ri, tj) = rs * Q[j];
      out.K.block<3, 3>(ti, tj) = ss * W[i].transpose() * Q[j];
    }
    // W^T itself turns with the node: d(L0 d x (A^T F_s))/dtheta.
    out.K.block<3, 3>(ti, ti) += L0 * skew(t[i].d) * skew(pose[i]->A.transpose() * F[2 * i + 1]);
  }
  return out;
}

ConsistentEnergy consistentEnergy(const CorotationalBeam& beam, double mass, const NodePose& n1,
                                  const NodeVelocity& v1, const NodePose& n2, const NodeVelocity& v2,
                                  const Vec3& gravity) {
  const double L0 = beam.L0;
  const Vec3 d1 = beam.C1.col(0), d2 = beam.C2.col(0);
  const std::array<Vec3, 4> pdot{{v1.v, L0 * (n1.A * v1.omega.cross(d1)), v2.v, L0 * (n2.A * v2.omega.cross(d2))}};
  ConsistentEnergy e;
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) e.kinetic += 0.5 * mass / 420.0 * kHermite[k][l] * pdot[k].dot(pdot[l]);
  const Vec3 s1 = L0 * (n1.A * d1), s2 = L0 * (n2.A * d2);
  e.gravity = -mass * gravity.dot(0.5 * (n1.r + n2.r) + (s1 - s2) / 12.0);
  return e;
}

}  // namespace mfbd
