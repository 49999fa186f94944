#include "rigid/force_elements.hpp"

namespace mfbd {

namespace {

struct MarkerState {
  Vec3 position, velocity, omega, comToMarker;
  Mat3 orientation;
};

// World pose and velocity of a marker; ground markers are fixed.
MarkerState markerState(const Marker& m, const Data& data) {
  MarkerState s;
  if (m.body == kGroundIndex) {
    s.position = m.position;
    s.orientation = m.orientation;
    s.velocity.setZero();
    s.omega.setZero();
    s.comToMarker.setZero();
    return s;
  }
  const BodyKinematics& b = data.body[m.body];
  s.comToMarker = b.orientation * m.position;
  s.position = b.position + s.comToMarker;
  s.orientation = b.orientation * m.orientation;
  s.omega = b.angularVelocity;
  s.velocity = b.velocity + b.angularVelocity.cross(s.comToMarker);
  return s;
}

// A force f at a marker, and a pure torque n, as a wrench about the marker
// body's centre of mass.
Vec6 wrenchAt(const MarkerState& s, const Vec3& f, const Vec3& n) {
  Vec6 w;
  w << f, s.comToMarker.cross(f) + n;
  return w;
}

}  // namespace

SpringState springState(const ForceElement& e, const VectorXd& inputs, const Data& data) {
  const MarkerState a = markerState(e.marker1, data), b = markerState(e.marker2, data);
  const Vec3 d = b.position - a.position;
  SpringState s;
  s.length = d.norm();
  const Vec3 u = s.length > 1e-12 ? Vec3(d / s.length) : Vec3::Zero();
  s.rate = u.dot(b.velocity - a.velocity);
  s.force = e.stiffness * (s.length - e.freeLength) + e.damping * s.rate;
  if (e.inputOffset >= 0) s.force += inputs[e.inputOffset];
  return s;
}

ForceElementWrenches forceElementWrenches(const ForceElement& e, const VectorXd& inputs, double t, const Data& data) {
  ForceElementWrenches w;
  const MarkerState a = markerState(e.marker1, data);
  switch (e.kind) {
    case ForceElement::Kind::SpringDamper: {
      // Tension pulls the markers together along the line between them.
      const MarkerState b = markerState(e.marker2, data);
      const SpringState s = springState(e, inputs, data);
      const Vec3 d = b.position - a.position;
      const Vec3 u = s.length > 1e-12 ? Vec3(d / s.length) : Vec3::Zero();
      w.onBody1 = wrenchAt(a, s.force * u, Vec3::Zero());
      w.onBody2 = wrenchAt(b, -s.force * u, Vec3::Zero());
      break;
    }
    case ForceElement::Kind::Bushing: {
      // Relative translation and rotation vector of marker 2 in marker 1's
      // frame; force and torque of the bushing on body 2, opposite on 1.
      const MarkerState b = markerState(e.marker2, data);
      const Mat3& A = a.orientation;
      Vec6 deformation, rate;
      deformation << A.transpose() * (b.position - a.position), logSO3(A.transpose() * b.orientation);
      rate << A.transpose() * (b.velocity - a.velocity - a.omega.cross(b.position - a.position)),
          A.transpose() * (b.omega - a.omega);
      const Vec6 local = -(e.bushingStiffness.cwiseProduct(deformation) + e.bushingDamping.cwiseProduct(rate));
      const Vec3 f = A * local.head<3>(), n = A * local.tail<3>();
      w.onBody2 = wrenchAt(b, f, n);
      // Reaction on body 1 at marker 2's point: -f there, -n.
      if (e.marker1.body != kGroundIndex)
        w.onBody1 << -f, -(b.position - data.body[e.marker1.body].position).cross(f) - n;
      break;
    }
    case ForceElement::Kind::AppliedForce: {
      const double scale = e.inputOffset < 0 ? e.scale(t) : 0.0;
      Vec3 f = e.inputOffset < 0 ? Vec3(scale * e.force) : Vec3(inputs.segment<3>(e.inputOffset));
      Vec3 n = e.inputOffset < 0 ? Vec3(scale * e.torque) : Vec3(inputs.segment<3>(e.inputOffset + 3));
      if (e.bodyFrame) {
        f = a.orientation * f;
        n = a.orientation * n;
      }
      w.onBody1 = wrenchAt(a, f, n);
      break;
    }
  }
  return w;
}

void applyForceElements(const std::vector<ForceElement>& elements, const VectorXd& inputs, double t, Data& data) {
  for (const ForceElement& e : elements) {
    const ForceElementWrenches w = forceElementWrenches(e, inputs, t, data);
    for (const auto& [body, wrench] : {std::pair{e.marker1.body, w.onBody1}, std::pair{e.marker2.body, w.onBody2}}) {
      if (body == kGroundIndex) continue;
      data.appliedForce[body] += wrench.head<3>();
      data.appliedTorque[body] += wrench.tail<3>();
    }
  }
}

}  // namespace mfbd
