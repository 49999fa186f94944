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
      velocityTransformation(Eigen::MatrixXd::Zero(6 * model.bodies.size(), model.rigidVelocityCount)),
      compositeInertia(model.bodies.size()) {}

namespace {

// What the rates add to a body over its parent: its velocity and the bias
// of its acceleration (the rate terms Sdot qdot + Xdot Y_parent),
//   a_i = a_p + alpha_p x dr + S qddot + bias,  alpha_i = alpha_p + S_w qddot + bias_w.
struct RateTerms {
  Vec3 velocity, angularVelocity, linearBias, angularBias;
};

// Hv, Hw: the joint's motion columns, qdot its rates (fixed-size blocks for a
// single-rate joint, see forwardBody). Slides: false where Hv and its rate
// terms vanish (revolute, spherical, fixed), whose slide terms are left out.
template <bool Slides, class Columns, class Rates>
RateTerms rateTerms(const JointMotion& m, const Columns& Hv, const Columns& Hw, const Vec3& parentVelocity,
                    const Vec3& parentOmega, const Mat3& AP, const Mat3& AC, const Vec3& pC, const Vec3& dr,
                    const Rates& qdot) {
  RateTerms t;
  const Vec3 wRel = AC * (Hw * qdot);
  t.angularVelocity = parentOmega + wRel;
  t.velocity = parentVelocity + parentOmega.cross(dr) + pC.cross(wRel);
  t.angularBias = t.angularVelocity.cross(wRel) + AC * m.HwDotQdot;
  t.linearBias = parentOmega.cross(t.velocity - parentVelocity) + t.angularVelocity.cross(pC).cross(wRel) +
                 pC.cross(t.angularBias);
  if constexpr (Slides) {
    const Vec3 vSlide = AP * (Hv * qdot);
    t.velocity += vSlide;
    t.linearBias += 2.0 * parentOmega.cross(vSlide) + AP * m.HvDotQdot;
  }
  return t;
}

// Body i of the forward recursion from its parent p. D is the joint's rate
// count where it is known at compile time (0: fixed; 1: revolute, prismatic; 3:
// spherical, planar; 6: free, every virtual body), Eigen::Dynamic otherwise:
// the same code, with the products fixed-size (single rate: pendulum 0.54
// -> 0.44 us per substep, double pendulum 3.2 -> 2.5). Flattened (every
// call inside inlined): with five instantiations GCC stopped inlining
// Eigen's small assignment loops into them (pendulum +7 %).
template <int D, bool Slides>
[[gnu::flatten]] void forwardBody(const Joint& jt, const Configuration& q, const VectorXd& v,
                                  const VectorXd& vdot, const BodyKinematics& p, BodyKinematics& c,
                                  JointKinematics& jk) {
  const int n = jt.dofs;
  const auto qdot = v.template segment<D>(jt.velocityOffset, n);
  const auto qddot = vdot.template segment<D>(jt.velocityOffset, n);
  const JointMotion m = jointMotion(jt, q, qdot);
  const auto Hv = m.Hv.template leftCols<D>(n);
  const auto Hw = m.Hw.template leftCols<D>(n);

  // Pose: parent marker P, child marker C = P * (d, R), body = C * childMarker^-1.
  const Mat3 AP = p.orientation * jt.parentMarker.orientation;
  const Mat3 AC = AP * m.rotation;
  c.orientation = AC * jt.childMarker.orientation.transpose();
  // Centre of mass -> child marker from AC, not from the orientation just
  // stored: read back in other vector packets than it was written in, it
  // stalls the loads (pendulum's forwardKinematics 70 -> 63 ns).
  const Vec3 pC = AC * (jt.childMarker.orientation.transpose() * jt.childMarker.position);
  c.position = p.position + p.orientation * jt.parentMarker.position - pC;
  if constexpr (Slides) c.position += AP * m.translation;  // zero for the others (75 -> 63 ns)

  // Motion subspace at the child's centre of mass, world frame.
  jk.childMarkerOrientation = AC;
  jk.childMarkerOffset = pC;
  jk.motionSubspace.resize(6, n);
  jk.motionSubspace.template bottomRows<3>() = AC * Hw;
  // pC x w by columns: skew(pC) built entry by entry stalls its product.
  for (int k = 0; k < n; ++k) {
    const Vec3 w = jk.motionSubspace.template block<3, 1>(3, k);
    jk.motionSubspace.template block<3, 1>(0, k) = pC.cross(w);
  }
  if constexpr (Slides) jk.motionSubspace.template topRows<3>() += AP * Hv;

  // Velocities Y_j = X Y_i + S qdot; accelerations Ydot_j = X Ydot_i + S qddot + bias.
  const Vec3 dr = c.position - p.position;
  const RateTerms t = rateTerms<Slides>(m, Hv, Hw, p.velocity, p.angularVelocity, AP, AC, pC, dr, qdot);
  c.velocity = t.velocity;
  c.angularVelocity = t.angularVelocity;
  const Vec3 angularRel = AC * (Hw * qddot);
  c.angularAcceleration = p.angularAcceleration + angularRel + t.angularBias;
  c.acceleration = p.acceleration + p.angularAcceleration.cross(dr) + pC.cross(angularRel) + t.linearBias;
  if constexpr (Slides) c.acceleration += AP * (Hv * qddot);
}

}  // namespace

void forwardKinematics(const Model& model, Data& data, const Configuration& q, const VectorXd& v,
                       const VectorXd& vdot) {
  const BodyKinematics ground;
  for (int i = 0; i < int(model.bodies.size()); ++i) {
    const Body& b = model.bodies[i];
    const Joint& jt = model.joints[b.inboardJoint];
    const BodyKinematics& p = b.parent == kGroundIndex ? ground : data.body[b.parent];
    BodyKinematics& c = data.body[i];
    JointKinematics& jk = data.joint[b.inboardJoint];
    switch (jt.dofs) {
      case 0: forwardBody<0, false>(jt, q, v, vdot, p, c, jk); break;
      case 1:
        if (jt.type == JointType::Revolute) forwardBody<1, false>(jt, q, v, vdot, p, c, jk);
        else forwardBody<1, true>(jt, q, v, vdot, p, c, jk);
        break;
      case 3:
        if (jt.type == JointType::Spherical) forwardBody<3, false>(jt, q, v, vdot, p, c, jk);
        else forwardBody<3, true>(jt, q, v, vdot, p, c, jk);
        break;
      case 6: forwardBody<6, true>(jt, q, v, vdot, p, c, jk); break;
      default: forwardBody<Eigen::Dynamic, true>(jt, q, v, vdot, p, c, jk);
    }
  }
}

BiasRateDerivatives biasRateDerivatives(const Model& model, const Data& data, const Configuration& q,
                                        const VectorXd& v, int body) {
  const Body& b = model.bodies[body];
  const Joint& jt = model.joints[b.inboardJoint];
  const BodyKinematics ground;
  const BodyKinematics& p = b.parent == kGroundIndex ? ground : data.body[b.parent];
  const BodyKinematics& c = data.body[body];
  const Mat3 AP = p.orientation * jt.parentMarker.orientation;
  const Mat3 AC = data.joint[b.inboardJoint].childMarkerOrientation;
  const Vec3 pC = data.joint[b.inboardJoint].childMarkerOffset;
  const Vec3 dr = c.position - p.position;
  VectorXd qdot = v.segment(jt.velocityOffset, jt.dofs);
  auto bias = [&](const Vec3& parentVelocity, const Vec3& parentOmega, const VectorXd& rates) {
    const JointMotion m = jointMotion(jt, q, rates);
    const RateTerms t = rateTerms<true>(m, m.Hv, m.Hw, parentVelocity, parentOmega, AP, AC, pC, dr, rates);
    Vec6 out;
    out << t.linearBias, t.angularBias;
    return out;
  };
  // Central differences: the bias is quadratic in the rates, so they are
  // exact up to round-off.
  const double scale = std::max({1.0, p.velocity.norm(), p.angularVelocity.norm(), qdot.cwiseAbs().maxCoeff()});
  const double eps = 1e-6 * scale;
  BiasRateDerivatives d;
  d.parent.setZero();
  d.rates.resize(6, jt.dofs);
  if (b.parent != kGroundIndex)
    for (int k = 0; k < 6; ++k) {
      Vec3 dv = Vec3::Zero(), dw = Vec3::Zero();
      (k < 3 ? dv[k] : dw[k - 3]) = eps;
      d.parent.col(k) = (bias(p.velocity + dv, p.angularVelocity + dw, qdot) -
                         bias(p.velocity - dv, p.angularVelocity - dw, qdot)) / (2.0 * eps);
    }
  for (int k = 0; k < jt.dofs; ++k) {
    VectorXd plus = qdot, minus = qdot;
    plus[k] += eps;
    minus[k] -= eps;
    d.rates.col(k) = (bias(p.velocity, p.angularVelocity, plus) - bias(p.velocity, p.angularVelocity, minus)) / (2.0 * eps);
  }
  return d;
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

// Flattened like forwardBody: its small Eigen products inlined.
[[gnu::flatten]] void backwardNewtonEuler(const Model& model, Data& data, const VectorXd& jointForces,
                                          VectorXd& residual) {
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

namespace {

// A joint's motion subspace as twists [v_O; omega] of the point of its child
// body at the world origin O (v_O = v_c + c x omega): one reference point
// for every body, so that inertias of a subtree simply add.
Matrix6X motionAtOrigin(const Data& data, int body, int joint) {
  Matrix6X S = data.joint[joint].motionSubspace;
  const Vec3& c = data.body[body].position;
  for (int k = 0; k < S.cols(); ++k) S.block<3, 1>(0, k) += c.cross(S.block<3, 1>(3, k));
  return S;
}

InertiaAtOrigin inertiaAtOrigin(const Body& b, const BodyKinematics& k) {
  const Vec3& c = k.position;
  InertiaAtOrigin I;
  I.mass = b.mass;
  I.firstMoment = b.mass * c;
  // J_c - m [c]x[c]x = J_c + m (|c|^2 1 - c c^T)
  I.rotational = k.orientation * b.inertia * k.orientation.transpose() +
                 b.mass * (c.squaredNorm() * Mat3::Identity() - c * c.transpose());
  return I;
}

// The momenta [p; L_O] of the twists in S's columns.
Matrix6X momenta(const InertiaAtOrigin& I, const Matrix6X& S) {
  Matrix6X F(6, S.cols());
  for (int k = 0; k < S.cols(); ++k) {
    const Vec3 v = S.block<3, 1>(0, k), w = S.block<3, 1>(3, k);
    F.block<3, 1>(0, k) = I.mass * v + w.cross(I.firstMoment);
    F.block<3, 1>(3, k) = I.firstMoment.cross(v) + I.rotational * w;
  }
  return F;
}

}  // namespace

// Composite rigid bodies (Walker & Orin; Featherstone): the inertia of each
// subtree, accumulated tip to root, gives M_ki = S_k^T Ic_i S_i for joint k
// on the path from body i to ground; O(n d) for depth d, where B^T M B
// with a dense B costs O(n^2 d).
void jointSpaceMassMatrix(const Model& model, Data& data, Eigen::MatrixXd& M) {
  const int nb = int(model.bodies.size());
  std::vector<InertiaAtOrigin>& composite = data.compositeInertia;
  for (int i = 0; i < nb; ++i) composite[i] = inertiaAtOrigin(model.bodies[i], data.body[i]);
  for (int i = nb - 1; i >= 0; --i)
    if (model.bodies[i].parent != kGroundIndex) composite[model.bodies[i].parent] += composite[i];
  M.setZero(model.rigidVelocityCount, model.rigidVelocityCount);
  for (int i = 0; i < nb; ++i) {
    const Joint& ji = model.joints[model.bodies[i].inboardJoint];
    if (ji.dofs == 0) continue;
    const Matrix6X Si = motionAtOrigin(data, i, model.bodies[i].inboardJoint);
    const Matrix6X F = momenta(composite[i], Si);  // wrench per joint acceleration of the subtree
    M.block(ji.velocityOffset, ji.velocityOffset, ji.dofs, ji.dofs) = Si.transpose() * F;
    for (int k = model.bodies[i].parent; k != kGroundIndex; k = model.bodies[k].parent) {
      const Joint& jk = model.joints[model.bodies[k].inboardJoint];
      if (jk.dofs == 0) continue;
      // At most 6 x 6: on the stack.
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, 6> Mki =
          motionAtOrigin(data, k, model.bodies[k].inboardJoint).transpose() * F;
      M.block(jk.velocityOffset, ji.velocityOffset, jk.dofs, ji.dofs) = Mki;
      M.block(ji.velocityOffset, jk.velocityOffset, ji.dofs, jk.dofs) = Mki.transpose();
    }
  }
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
