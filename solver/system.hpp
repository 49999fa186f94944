// System: the mechanical system as the integrator sees it (Dynamics), built
// from a Model. Today: a rigid tree in joint coordinates with gravity, joint
// damping and joint-force inputs.
#pragma once
#include "integrator/dynamics.hpp"
#include "model/data.hpp"

namespace mfbd {

class System : public Dynamics {
 public:
  explicit System(Model model);

  const Model& model() const { return model_; }
  Model& tunableModel() { return model_; }  // for tunable parameters only
  const Data& data() const { return data_; }

  // Generalized joint-force inputs (torques/forces along actuated DOFs).
  VectorXd& jointInputs() { return jointInputs_; }
  const VectorXd& jointInputs() const { return jointInputs_; }

  int velocityCount() const override { return model_.velocityCount; }
  int constraintCount() const override { return 0; }
  void retract(Configuration& q, const VectorXd& dq) const override;
  void residual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda,
                VectorXd& r, VectorXd& phi) override;
  void tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda,
               double cM, double cC, double cK, Triplets& iteration, Triplets& constraintJacobian) override;

  // Kinematics and joint reactions of a state into data() (for outputs).
  void evaluate(const Configuration& q, const VectorXd& v, const VectorXd& vdot);

 private:
  void jointForces(const VectorXd& v, VectorXd& tau) const;
  void appliedForces();

  Model model_;
  Data data_;
  VectorXd jointInputs_;
  VectorXd tau_;
};

}  // namespace mfbd
