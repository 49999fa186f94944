#include "system.hpp"

#include "rigid/recursive_dynamics.hpp"

namespace mfbd {

System::System(Model model) : model_(std::move(model)), data_(model_), jointInputs_(VectorXd::Zero(model_.jointInputCount)) {}

void System::retract(Configuration& q, const VectorXd& dq) const { mfbd::retract(model_.blocks, q, dq); }

// tau = actuator inputs - viscous joint damping, along each joint's DOFs.
void System::jointForces(const VectorXd& v, VectorXd& tau) const {
  tau.setZero(model_.velocityCount);
  for (const Joint& j : model_.joints) {
    auto t = tau.segment(j.velocityOffset, j.dofs);
    t = -j.damping * v.segment(j.velocityOffset, j.dofs);
    if (j.actuated) t += jointInputs_.segment(j.inputOffset, j.dofs);
  }
}

void System::appliedForces() {
  for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
    data_.appliedForce[i] = model_.bodies[i].mass * model_.gravity;
    data_.appliedTorque[i].setZero();
  }
}

void System::residual(double /*t*/, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                      const VectorXd& /*lambda*/, VectorXd& r, VectorXd& phi) {
  forwardKinematics(model_, data_, q, v, vdot);
  appliedForces();
  jointForces(v, tau_);
  backwardNewtonEuler(model_, data_, tau_, r);
  phi.resize(0);
}

// Mass block analytic (B^T M B); the velocity and configuration derivatives
// by finite differences of the residual along the retraction, for now.
void System::tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                     const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                     Triplets& /*constraintJacobian*/) {
  const int n = model_.velocityCount;
  forwardKinematics(model_, data_, q, v, vdot);
  computeVelocityTransformation(model_, data_);
  const Eigen::MatrixXd M = jointSpaceMassMatrix(model_, data_);
  Eigen::MatrixXd S = cM * M;
  if (cC != 0.0 || cK != 0.0) {
    VectorXd r0, r1, phi;
    residual(t, q, v, vdot, lambda, r0, phi);
    for (int i = 0; i < n; ++i) {
      const double eps = 1e-7;
      VectorXd dq = VectorXd::Zero(n);
      dq[i] = eps;
      Configuration qp = q;
      retract(qp, cK != 0.0 ? dq : VectorXd::Zero(n));
      const VectorXd vp = v + (cK != 0.0 ? cC / cK : 1.0) * dq;
      residual(t, qp, vp, vdot, lambda, r1, phi);
      // (r1 - r0)/eps = K e_i + (cC/cK) C e_i, scaled back by cK.
      S.col(i) += (cK != 0.0 ? cK : cC) * (r1 - r0) / eps;
    }
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (S(i, j) != 0.0) iteration.emplace_back(i, j, S(i, j));
}

void System::evaluate(const Configuration& q, const VectorXd& v, const VectorXd& vdot) {
  VectorXd r, phi;
  residual(0.0, q, v, vdot, VectorXd(), r, phi);
}

}  // namespace mfbd
