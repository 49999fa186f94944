// Data: all workspace of the algorithms, sized once from a Model.
#pragma once
#include <vector>

#include <Eigen/Core>

#include "model/model.hpp"

namespace mfbd {

using Matrix6X = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;

// World-frame kinematics of a body's centre-of-mass frame.
struct BodyKinematics {
  Vec3 position = Vec3::Zero();
  Mat3 orientation = Mat3::Identity();
  Vec3 velocity = Vec3::Zero();
  Vec3 angularVelocity = Vec3::Zero();
  Vec3 acceleration = Vec3::Zero();
  Vec3 angularAcceleration = Vec3::Zero();
};

struct JointKinematics {
  Mat3 childMarkerOrientation = Mat3::Identity();  // world
  Vec3 childMarkerOffset = Vec3::Zero();           // child centre of mass -> child marker, world
  Matrix6X motionSubspace;  // columns: [linear; angular] velocity of the child's centre of mass per joint rate
};

// A rigid body's (or subtree's) spatial inertia about the world origin O,
// world frame, in its ten numbers: mass m, first moment h = m c (c the
// centre of mass), rotational inertia J_O = J_c - m [c]x[c]x. The momentum
// of the twist [v_O; omega] is p = m v_O + omega x h, L_O = h x v_O + J_O
// omega (Featherstone 2008, ch. 2); inertias about one point simply add.
struct InertiaAtOrigin {
  double mass = 0.0;
  Vec3 firstMoment = Vec3::Zero();
  Mat3 rotational = Mat3::Zero();
  InertiaAtOrigin& operator+=(const InertiaAtOrigin& other) {
    mass += other.mass;
    firstMoment += other.firstMoment;
    rotational += other.rotational;
    return *this;
  }
};

struct Data {
  explicit Data(const Model& model);

  std::vector<BodyKinematics> body;
  std::vector<JointKinematics> joint;
  // Applied forces and torques on each body, world, about its centre of mass
  // (gravity and force elements), filled before the backward loop.
  std::vector<Vec3> appliedForce, appliedTorque;
  // Wrench the inboard joint passes to each body's subtree (about the body's
  // centre of mass, world): result of the backward Newton-Euler loop.
  std::vector<Vec3> subtreeForce, subtreeTorque;
  // Velocity transformation B: rows [6 i, 6 i + 6) give body i's
  // [velocity; angular velocity] (world, centre of mass) per joint rate.
  Eigen::MatrixXd velocityTransformation;
  // Each subtree's inertia about the world origin (workspace of
  // jointSpaceMassMatrix).
  std::vector<InertiaAtOrigin> compositeInertia;
};

}  // namespace mfbd
