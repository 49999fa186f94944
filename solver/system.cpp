#include "system.hpp"

#include <limits>

#include "rigid/recursive_dynamics.hpp"

namespace mfbd {

System::System(Model model)
    : model_(std::move(model)),
      data_(model_),
      jointInputs_(VectorXd::Zero(model_.jointInputCount)),
      flexibleInputs_(VectorXd::Zero(model_.flexible.inputCount)) {
  drives_.startAngle.assign(model_.flexible.drives.size(), 0.0);
}

void System::retract(Configuration& q, const VectorXd& dq) const { mfbd::retract(model_.blocks, q, dq); }

void System::endStep(double t) {
  for (std::size_t d = 0; d < drives_.startAngle.size(); ++d)
    drives_.startAngle[d] = drives_.angle(model_.flexible, flexibleInputs_, int(d), t);
  drives_.stepStart = t;
}

// tau = actuator inputs - viscous joint damping, along each joint's DOFs.
void System::jointForces(const VectorXd& v, VectorXd& tau) const {
  tau.setZero(model_.rigidVelocityCount);
  for (const Joint& j : model_.joints) {
    auto t = tau.segment(j.velocityOffset, j.dofs);
    t = -j.damping * v.segment(j.velocityOffset, j.dofs);
    if (j.actuated) t += jointInputs_.segment(j.inputOffset, j.dofs);
  }
}

void System::rigidResidual(const Configuration& q, const VectorXd& v, const VectorXd& vdot, VectorXd& r) {
  forwardKinematics(model_, data_, q, v, vdot);
  for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
    data_.appliedForce[i] = model_.bodies[i].mass * model_.gravity;
    data_.appliedTorque[i].setZero();
  }
  jointForces(v, tau_);
  backwardNewtonEuler(model_, data_, tau_, r);
}

void System::residual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                      const VectorXd& /*lambda*/, VectorXd& r, VectorXd& phi) {
  r.setZero(model_.velocityCount);
  phi.resize(0);
  if (!model_.bodies.empty()) {
    rigidResidual(q, v, vdot, rigid_);
    r.head(model_.rigidVelocityCount) = rigid_;
  }
  if (!model_.flexible.empty()) {
    flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleInputs_, nodes_);
    const bool inertia = model_.analysis == Analysis::Dynamic;
    if (!flexibleResidual(model_.flexible, nodes_, model_.gravity, flexibleInputs_, t, inertia, r))
      r.setConstant(std::numeric_limits<double>::quiet_NaN());  // a failed iterate: the step is retried smaller
  }
}

// Mass block analytic (B^T M B); velocity and configuration derivatives by
// finite differences of the rigid residual, for now. Every entry of the
// block is emitted, zeros included, so the sparsity pattern never changes.
void System::rigidTangent(const Configuration& q, const VectorXd& v, const VectorXd& vdot, double cM, double cC,
                          double cK, Triplets& iteration) {
  const int n = model_.rigidVelocityCount;
  forwardKinematics(model_, data_, q, v, vdot);
  computeVelocityTransformation(model_, data_);
  Eigen::MatrixXd S = cM * jointSpaceMassMatrix(model_, data_);
  if (cC != 0.0 || cK != 0.0) {
    VectorXd r0, r1;
    rigidResidual(q, v, vdot, r0);
    const double eps = 1e-7;
    for (int i = 0; i < n; ++i) {
      // Perturb q by eps e_i and v by (cC/cK) eps e_i: (r1 - r0)/eps = K e_i + (cC/cK) C e_i.
      VectorXd dq = VectorXd::Zero(model_.velocityCount);
      dq[i] = eps;
      Configuration qp = q;
      VectorXd vp = v;
      if (cK != 0.0) {
        retract(qp, dq);
        vp[i] += cC / cK * eps;
      } else {
        vp[i] += eps;
      }
      rigidResidual(qp, vp, vdot, r1);
      S.col(i) += (cK != 0.0 ? cK : cC) * (r1 - r0) / eps;
    }
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) iteration.emplace_back(i, j, S(i, j));
}

void System::tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                     const VectorXd& /*lambda*/, double cM, double cC, double cK, Triplets& iteration,
                     Triplets& /*constraintJacobian*/) {
  if (!model_.bodies.empty()) rigidTangent(q, v, vdot, cM, cC, cK, iteration);
  if (!model_.flexible.empty()) {
    flexibleNodeStates(model_.flexible, q, v, vdot, t, drives_, flexibleInputs_, nodes_);
    const bool inertia = model_.analysis == Analysis::Dynamic;
    flexibleTangent(model_.flexible, nodes_, flexibleInputs_, t, inertia ? cM : 0.0, inertia ? cC : 0.0, cK,
                    iteration);
  }
}

void System::evaluate(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot) {
  VectorXd r, phi;
  residual(t, q, v, vdot, VectorXd(), r, phi);
}

}  // namespace mfbd
