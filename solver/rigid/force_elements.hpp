// Force elements between bodies, written against markers (points and frames
// fixed in bodies): a translational spring-damper-actuator, a 6-DOF bushing,
// and an applied force and torque (given functions of time or FMI inputs). Each turns the two
// markers' poses and velocities into wrenches on the bodies (world, about
// each body's centre of mass). Rotational spring-dampers act in joint space
// (joint forces, like joint damping).
#pragma once
#include <string>
#include <vector>

#include "model/data.hpp"

namespace mfbd {

// The wrenches [force; torque] of one element on its two markers' bodies
// (world, about each centre of mass; zero on ground, and on body 2 of an
// applied force), after forwardKinematics.
struct ForceElementWrenches {
  Vec6 onBody1 = Vec6::Zero(), onBody2 = Vec6::Zero();
};
ForceElementWrenches forceElementWrenches(const ForceElement& e, const VectorXd& inputs, double t, const Data& data);

// Adds every element's wrenches to data.appliedForce / appliedTorque (after
// forwardKinematics); `inputs` holds the force-element inputs, t is the time
// of the applied forces given as functions of time.
void applyForceElements(const std::vector<ForceElement>& elements, const VectorXd& inputs, double t, Data& data);

// Length, rate and tension of a spring-damper (for outputs).
struct SpringState {
  double length = 0.0, rate = 0.0, force = 0.0;
};
SpringState springState(const ForceElement& e, const VectorXd& inputs, const Data& data);

}  // namespace mfbd
