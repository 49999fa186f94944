// The joint library: for each joint kind, the relative motion of the child
// marker frame C with respect to the parent marker frame P as a function of
// the joint's coordinates and rates:
//   orientation of C in P       R(q)
//   origin of C in P            d(q)
//   translation rate (P frame)  ddot   = Hv(q) qdot
//   angular rate (C frame)      omega  = Hw(q) qdot
// and the rate terms Hvdot qdot, Hwdot qdot of the acceleration recursion.
// Joint frame axes: revolute/prismatic/cylindrical act along z; planar moves
// in x-y and turns about z; universal turns about x, then about the new y.
#pragma once
#include <Eigen/Core>

#include "math/configuration.hpp"
#include "scene/scene.hpp"

namespace mfbd {

using Matrix3X = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, 6>;

struct JointMotion {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
  Matrix3X Hv;  // 3 x dofs
  Matrix3X Hw;  // 3 x dofs
  Vec3 HvDotQdot = Vec3::Zero();
  Vec3 HwDotQdot = Vec3::Zero();
};

struct Joint;

// The joint's coordinates are read from q (its scalars and/or its stored
// rotation), its rates from qdot = v.segment(velocityOffset, dofs).
JointMotion jointMotion(const Joint& joint, const Configuration& q, const Eigen::Ref<const VectorXd>& qdot);

}  // namespace mfbd
