#include "rigid/joint_motion.hpp"

#include <cmath>

#include "model/model.hpp"

namespace mfbd {

namespace {
// Rotation by `angle` about the coordinate axis `k` (0, 1, 2: x, y, z) of the
// joint frame: one sincos, no general exponential map (the revolute joint's
// rotation is a fifth of a one-body substep's work through expSO3).
Mat3 rotationAbout(int k, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  const int i = (k + 1) % 3, j = (k + 2) % 3;
  // Written as whole columns (c e_i + s e_j, -s e_i + c e_j, e_k): the
  // products that read R in vector packets stall on entries stored one by
  // one (forwardKinematics of a pendulum 87 -> 70 ns with the motion
  // subspace's cross products, see forwardBody).
  const Mat3 I = Mat3::Identity();
  Mat3 R;
  R.col(i) = c * I.col(i) + s * I.col(j);
  R.col(j) = c * I.col(j) - s * I.col(i);
  R.col(k) = I.col(k);
  return R;
}
}  // namespace

JointMotion jointMotion(const Joint& joint, const Configuration& q, const Eigen::Ref<const VectorXd>& qdot) {
  JointMotion m;
  m.Hv = Matrix3X::Zero(3, joint.dofs);
  m.Hw = Matrix3X::Zero(3, joint.dofs);
  const auto s = [&](int i) { return q.scalars[joint.scalarOffset + i]; };
  const Vec3 ex = Vec3::UnitX(), ey = Vec3::UnitY(), ez = Vec3::UnitZ();
  switch (joint.type) {
    case JointType::Revolute:
      m.rotation = rotationAbout(2, s(0));
      m.Hw.col(0) = ez;
      break;
    case JointType::Prismatic:
      m.translation = ez * s(0);
      m.Hv.col(0) = ez;
      break;
    case JointType::Cylindrical:  // coordinates: angle, slide
      m.rotation = rotationAbout(2, s(0));
      m.translation = ez * s(1);
      m.Hw.col(0) = ez;
      m.Hv.col(1) = ez;
      break;
    case JointType::Universal: {  // R = Rx(a) Ry(b); omega_C = Ry(b)^T ex adot + ey bdot
      const Mat3 Ry = rotationAbout(1, s(1));
      m.rotation = rotationAbout(0, s(0)) * Ry;
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
      m.rotation = rotationAbout(2, s(2));
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
