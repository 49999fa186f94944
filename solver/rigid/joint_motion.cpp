#include "rigid/joint_motion.hpp"

#include "model/model.hpp"

namespace mfbd {

namespace {
Mat3 rotationAbout(const Vec3& axis, double angle) { return expSO3(axis * angle); }
}  // namespace

JointMotion jointMotion(const Joint& joint, const Configuration& q, const Eigen::Ref<const VectorXd>& qdot) {
  JointMotion m;
  m.Hv = Matrix3X::Zero(3, joint.dofs);
  m.Hw = Matrix3X::Zero(3, joint.dofs);
  const auto s = [&](int i) { return q.scalars[joint.scalarOffset + i]; };
  const Vec3 ex = Vec3::UnitX(), ey = Vec3::UnitY(), ez = Vec3::UnitZ();
  switch (joint.type) {
    case JointType::Revolute:
      m.rotation = rotationAbout(ez, s(0));
      m.Hw.col(0) = ez;
      break;
    case JointType::Prismatic:
      m.translation = ez * s(0);
      m.Hv.col(0) = ez;
      break;
    case JointType::Cylindrical:  // coordinates: angle, slide
      m.rotation = rotationAbout(ez, s(0));
      m.translation = ez * s(1);
      m.Hw.col(0) = ez;
      m.Hv.col(1) = ez;
      break;
    case JointType::Universal: {  // R = Rx(a) Ry(b); omega_C = Ry(b)^T ex adot + ey bdot
      const Mat3 Ry = rotationAbout(ey, s(1));
      m.rotation = rotationAbout(ex, s(0)) * Ry;
      m.Hw.col(0) = Ry.transpose() * ex;
      m.Hw.col(1) = ey;
      // d/dt (Ry^T ex) = -(ey bdot) x (Ry^T ex)
      m.HwDotQdot = -(ey * qdot[1]).cross(m.Hw.col(0)) * qdot[0];
      break;
    }
    case JointType::Spherical:
      m.rotation = q.rotations[joint.rotation];
      m.Hw = Mat3::Identity();
      break;
    case JointType::Planar:  // coordinates: x, y, angle
      m.rotation = rotationAbout(ez, s(2));
      m.translation = Vec3(s(0), s(1), 0.0);
      m.Hv.col(0) = ex;
      m.Hv.col(1) = ey;
      m.Hw.col(2) = ez;
      break;
    case JointType::Fixed:
      break;
    case JointType::Free:  // translation in P (scalars), rotation stored; rates [ddot; omega_C]
      m.translation = Vec3(s(0), s(1), s(2));
      m.rotation = q.rotations[joint.rotation];
      m.Hv.leftCols<3>() = Mat3::Identity();
      m.Hw.rightCols<3>() = Mat3::Identity();
      break;
  }
  return m;
}

}  // namespace mfbd
