// x'' + w^2 x = 0 as a one-DOF Dynamics (scalar coordinate): the smallest
// system with an exact solution, for the integrator's tests.
#pragma once
#include "integrator/dynamics.hpp"

namespace mfbd {

class Oscillator : public Dynamics {
 public:
  explicit Oscillator(double omega) : w2_(omega * omega) {}
  int velocityCount() const override { return 1; }
  int constraintCount() const override { return 0; }
  void retract(Configuration& q, const VectorXd& dq) const override { q.scalars += dq; }
  void residual(double, const Configuration& q, const VectorXd&, const VectorXd& vdot, const VectorXd&, VectorXd& r,
                VectorXd& phi) override {
    r = vdot + w2_ * q.scalars;
    phi.resize(0);
  }
  VectorXd constraintAccelerationTerm(double, const Configuration&, const VectorXd&) override { return {}; }
  void tangent(double, const Configuration&, const VectorXd&, const VectorXd&, const VectorXd&, double cM, double,
               double cK, Triplets& S, Triplets&) override {
    S.emplace_back(0, 0, cM + cK * w2_);
  }

 private:
  double w2_;
};

}  // namespace mfbd
