// Static analysis: each substep solves equilibrium r(q, 0, 0, t) = 0 at the
// loads of its end time by Newton on the tangent stiffness (load stepping);
// a failed solve halves the load step. Newton starts from the previous
// equilibrium moved on along the path as in the last load step (secant
// predictor, q_n o exp(h pathRate)): on a smooth path that saves about one
// iteration per step (F1: 6 -> 5); after a failed step it is left out.
#pragma once
#include "integrator/time_stepper.hpp"

namespace mfbd {

class StaticEquilibrium : public TimeStepper {
 public:
  explicit StaticEquilibrium(const SolverOptions& options) : TimeStepper(options) {}
  // Equilibrium at state.t.
  bool initialize(Dynamics& system, IntegratorState& state, std::string& message) override;
  void saveState(StateWriter& ar) override {
    TimeStepper::saveState(ar);
    solver_.saveState(ar);
  }
  void loadState(StateReader& ar) override {
    TimeStepper::loadState(ar);
    solver_.loadState(ar);
  }

 protected:
  bool substep(Dynamics& system, IntegratorState& s, double h, std::string& why) override;

 private:
  // Newton from s.q; `increment` accumulates the corrections.
  bool solve(Dynamics& system, IntegratorState& s, VectorXd& increment, std::string& why);
  LinearSolver solver_;
};

}  // namespace mfbd
