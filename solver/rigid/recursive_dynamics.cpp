#include "rigid/recursive_dynamics.hpp"

#include "rigid/joint_motion.hpp"

namespace mfbd {

Data::Data(const Model& model)
    : body(model.bodies.size()),
      joint(model.joints.size()),
      appliedForce(model.bodies.size(), Vec3::Zero()),
      appliedTorque(model.bodies.size(), Vec3::Zero()),
      subtreeForce(model.bodies.size(), Vec3::Zero()),
      subtreeTorque(model.bodies.size(), Vec3::Zero()),
      velocityTransformation(Eigen::MatrixXd::Zero(6 * model.bodies.size(), model.rigidVelocityCount)) {}

void forwardKinematics(const Model& model, Data& data, const Configuration& q, const VectorXd& v,
                       const VectorXd& vdot) {
  const BodyKinematics ground;
  for (int i = 0; i < int(model.bodies.size()); ++i) {
    const Body& b = model.bodies[i];
    const Joint& jt = model.joints[b.inboardJoint];
    const BodyKinematics& p = b.parent == kGroundIndex ? ground : data.body[b.parent];
    BodyKinematics& c = data.body[i];
    JointKinematics& jk = data.joint[b.inboardJoint];

    const auto qdot = v.segment(jt.velocityOffset, jt.dofs);
    const auto qddot = vdot.segment(jt.velocityOffset, jt.dofs);
    const JointMotion m = jointMotion(jt, q, qdot);

    // Pose: parent marker P, child marker C = P * (d, R), body = C * childMarker^-1.
    const Mat3 AP = p.orientation * jt.parentMarker.orientation;
    const Mat3 AC = AP * m.rotation;
    c.orientation = AC * jt.childMarker.orientation.transpose();
    const Vec3 pC = c.orientation * jt.childMarker.position;  // centre of mass -> child marker
    c.position = p.position + p.orientation * jt.parentMarker.position + AP * m.translation - pC;

    // Motion subspace at the child's centre of mass, world frame.
    jk.childMarkerOrientation = AC;
    jk.childMarkerOffset = pC;
    jk.motionSubspace.resize(6, jt.dofs);
    jk.motionSubspace.bottomRows<3>() = AC * m.Hw;
    jk.motionSubspace.topRows<3>() = AP * m.Hv + skew(pC) * jk.motionSubspace.bottomRows<3>();

    // Velocities: Y_j = X Y_i + S qdot.
    const Vec3 dr = c.position - p.position;
    const Vec3 wRel = AC * (m.Hw * qdot);
    const Vec3 vSlide = AP * (m.Hv * qdot);
    c.angularVelocity = p.angularVelocity + wRel;
    c.velocity = p.velocity + p.angularVelocity.cross(dr) + vSlide + pC.cross(wRel);

    // Accelerations: Ydot_j = X Ydot_i + S qddot + (Sdot qdot + Xdot Y_i).
    const Vec3 angularBias = c.angularVelocity.cross(wRel) + AC * m.HwDotQdot;
    const Vec3 linearBias = p.angularVelocity.cross(vSlide) + AP * m.HvDotQdot +
                            c.angularVelocity.cross(pC).cross(wRel) + pC.cross(angularBias);
    const Vec3 angularRel = AC * (m.Hw * qddot);
    c.angularAcceleration = p.angularAcceleration + angularRel + angularBias;
    c.acceleration = p.acceleration + p.angularAcceleration.cross(dr) +
                     p.angularVelocity.cross(c.velocity - p.velocity) + AP * (m.Hv * qddot) +
                     pC.cross(angularRel) + linearBias;
  }
}

void computeVelocityTransformation(const Model& model, Data& data) {
  Eigen::MatrixXd& B = data.velocityTransformation;
  B.setZero(6 * model.bodies.size(), model.rigidVelocityCount);
  for (int i = 0; i < int(model.bodies.size()); ++i) {
    const Body& b = model.bodies[i];
    const Joint& jt = model.joints[b.inboardJoint];
    if (b.parent != kGroundIndex) {
      // Rigid transfer from the parent's centre of mass: v_i = v_p + w_p x dr.
      const Vec3 dr = data.body[i].position - data.body[b.parent].position;
      B.middleRows<3>(6 * i) = B.middleRows<3>(6 * b.parent) - skew(dr) * B.middleRows<3>(6 * b.parent + 3);
      B.middleRows<3>(6 * i + 3) = B.middleRows<3>(6 * b.parent + 3);
    }
    B.block(6 * i, jt.velocityOffset, 6, jt.dofs) += data.joint[b.inboardJoint].motionSubspace;
  }
}

void backwardNewtonEuler(const Model& model, Data& data, const VectorXd& jointForces, VectorXd& residual) {
  residual.setZero(model.rigidVelocityCount);
  const int n = int(model.bodies.size());
  for (int i = 0; i < n; ++i) {
    const Body& b = model.bodies[i];
    const BodyKinematics& k = data.body[i];
    const Mat3 J = k.orientation * b.inertia * k.orientation.transpose();
    data.subtreeForce[i] = b.mass * k.acceleration - data.appliedForce[i];
    data.subtreeTorque[i] =
        J * k.angularAcceleration + k.angularVelocity.cross(J * k.angularVelocity) - data.appliedTorque[i];
  }
  for (int i = n - 1; i >= 0; --i) {
    const Body& b = model.bodies[i];
    const Joint& jt = model.joints[b.inboardJoint];
    const Matrix6X& S = data.joint[b.inboardJoint].motionSubspace;
    residual.segment(jt.velocityOffset, jt.dofs) =
        S.topRows<3>().transpose() * data.subtreeForce[i] + S.bottomRows<3>().transpose() * data.subtreeTorque[i] -
        jointForces.segment(jt.velocityOffset, jt.dofs);
    if (b.parent != kGroundIndex) {
      const Vec3 dr = data.body[i].position - data.body[b.parent].position;
      data.subtreeForce[b.parent] += data.subtreeForce[i];
      data.subtreeTorque[b.parent] += data.subtreeTorque[i] + dr.cross(data.subtreeForce[i]);
    }
  }
}

Eigen::MatrixXd jointSpaceMassMatrix(const Model& model, const Data& data) {
  const Eigen::MatrixXd& B = data.velocityTransformation;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(model.rigidVelocityCount, model.rigidVelocityCount);
  for (int i = 0; i < int(model.bodies.size()); ++i) {
    const Body& b = model.bodies[i];
    const Mat3& A = data.body[i].orientation;
    const auto Bv = B.middleRows<3>(6 * i);
    const auto Bw = B.middleRows<3>(6 * i + 3);
    M.noalias() += b.mass * Bv.transpose() * Bv;
    M.noalias() += Bw.transpose() * (A * b.inertia * A.transpose()) * Bw;
  }
  return M;
}

void jointReaction(const Model& model, const Data& data, int joint, Vec3& force, Vec3& torque) {
  int child = -1;
  for (int i = 0; i < int(model.bodies.size()) && child < 0; ++i)
    if (model.bodies[i].inboardJoint == joint) child = i;
  const JointKinematics& jk = data.joint[joint];
  const Vec3& F = data.subtreeForce[child];
  // Moment about the child marker origin, at pC from the centre of mass.
  const Vec3 N = data.subtreeTorque[child] - jk.childMarkerOffset.cross(F);
  force = jk.childMarkerOrientation.transpose() * F;
  torque = jk.childMarkerOrientation.transpose() * N;
}

}  // namespace mfbd
