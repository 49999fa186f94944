// What an element's residual forces read and give, for one element
// (T = double) or four at a time (T = Lanes, math/lanes.hpp), in the frames
// of the nodes' copies of the element frame R_i = A_i C_i: a node's C_i is
// applied on the way in and out (elementState, storeForce). The internal
// force's kernel is in corotational_force.hpp, the consistent inertia's in
// consistent_mass.hpp.
#pragma once
#include "flex/corotational_beam.hpp"
#include "math/lanes.hpp"

namespace mfbd {

template <class T>
struct ElementState {
  Matrix3<T> R[2];       // A_i C_i
  Vector3<T> chord;      // r2 - r1
  Vector3<T> chordRate;  // v2 - v1
  Vector3<T> spin[2];    // C_i^T omega_i
  // for the inertia (mass > 0)
  Vector3<T> chordAcceleration;  // a2 - a1
  Vector3<T> spinRate[2];        // C_i^T omegadot_i
  Vector3<T> acceleration[2];    // a_i - g
};

template <class T>
struct ElementForce {
  Vector3<T> force[2];   // on node i (world)
  Vector3<T> moment[2];  // on node i, in R_i's frame (C_i times it: the node frame)
};

// One element's state; the second form with the inertia's accelerations
// (gravity subtracted).
ElementState<double> elementState(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                                  const NodeVelocity& v1, const NodeVelocity& v2);
ElementState<double> elementState(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                                  const NodeVelocity& v1, const NodeVelocity& v2, const NodeAcceleration& a1,
                                  const NodeAcceleration& a2, const Vec3& gravity);
// f = [force_1; C1 moment_1; force_2; C2 moment_2].
void storeForce(const CorotationalBeam& beam, const ElementForce<double>& out, Vec12& f);

}  // namespace mfbd
