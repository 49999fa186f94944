// What a System's constraint and force code reads of its Model and Data:
// the joint constraint between a joint's two markers, and the pose and
// twist of a body's centre-of-mass frame (ground: identity, at rest).
// Internal to system*.cpp.
#pragma once
#include "coupling/joint_constraint.hpp"
#include "model/data.hpp"
#include "model/model.hpp"

namespace mfbd {

inline JointConstraint constraintOf(const Joint& j) {
  return {j.type, {j.parentMarker.position, j.parentMarker.orientation},
          {j.childMarker.position, j.childMarker.orientation}};
}

// Pose of a body's centre-of-mass frame; ground is the identity.
inline BodyPose poseOf(const Data& data, int body) {
  if (body == kGroundIndex) return {Vec3::Zero(), Mat3::Identity()};
  return {data.body[body].position, data.body[body].orientation};
}

inline BodyTwist twistOf(const Data& data, int body) {
  if (body == kGroundIndex) return {Vec3::Zero(), Vec3::Zero()};
  return {data.body[body].velocity, data.body[body].angularVelocity};
}

}  // namespace mfbd
