// Static analysis: each substep solves equilibrium r(q, 0, 0, t) = 0 at the
// loads of its end time by Newton on the tangent stiffness, starting from the
// previous equilibrium (load stepping); a failed solve halves the load step.
#pragma once
#include "integrator/time_stepper.hpp"

namespace mfbd {

class StaticEquilibrium : public TimeStepper {
 public:
  explicit StaticEquilibrium(const SolverOptions& options) : TimeStepper(options) {}
  // Equilibrium at state.t.
  bool initialize(Dynamics& system, IntegratorState& state, std::string& message) override;

 protected:
  bool substep(Dynamics& system, IntegratorState& s, double h, std::string& why) override;

 private:
  bool solve(Dynamics& system, IntegratorState& s, std::string& why);
  LinearSolver solver_;
  int patternSize_ = -1;
};

}  // namespace mfbd
