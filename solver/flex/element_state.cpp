#include "flex/element_state.hpp"

namespace mfbd {

namespace {

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

}  // namespace mfbd
