// Generalized-alpha for constrained systems on a Lie group (Arnold & Bruls
// 2007; Bruls, Cardona & Arnold 2012), index-3 constraints, with the
// iteration matrix scaled by 1/beta' (Bottasso, Bauchau & Cardona 2007) so it
// stays well conditioned as h -> 0:
//   [ M + (gamma'/beta') C + K/beta'   Phi_q^T ] [ dq          ]   [ -r/beta' ]
//   [ Phi_q                            0       ] [ dlambda/beta'] = [ -Phi     ]
// Newton failure halves the substep down to h_min; the caller keeps the state
// of the step start and reports a discarded step.
#pragma once
#include "integrator/dynamics.hpp"
#include "integrator/linear_solver.hpp"
#include "scene/scene.hpp"

namespace mfbd {

struct IntegratorState {
  double t = 0.0;
  Configuration q;
  VectorXd v, vdot, a, lambda;  // a: the algorithmic acceleration of the method
  double h = 0.0;               // substep size to try next
  // Counters since the start of the run.
  long substeps = 0;
  long newtonIterations = 0;
  long factorizations = 0;
  long rejectedSubsteps = 0;
};

struct AdvanceResult {
  bool ok = true;
  double reachedTime = 0.0;  // on failure: how far substeps got before giving up
  std::string message;
};

class GeneralizedAlpha {
 public:
  explicit GeneralizedAlpha(const SolverOptions& options);

  // Consistent initial accelerations (M vdot = Q at t) and a = vdot.
  bool initialize(Dynamics& system, IntegratorState& state, std::string& message);

  // Implicit substeps from state.t to tEnd. On failure `state` is left at an
  // intermediate time: the caller restores the step start.
  AdvanceResult advance(Dynamics& system, IntegratorState& state, double tEnd);

  const SolverOptions& options() const { return options_; }

 private:
  bool substep(Dynamics& system, IntegratorState& state, double h, std::string& why);
  bool factorize(Dynamics& system, const IntegratorState& trial, double h);

  SolverOptions options_;
  double alphaM_, alphaF_, gamma_, beta_;
  LinearSolver solver_;
  int patternSize_ = -1;
  double factoredStep_ = 0.0;  // substep size of the current factorization; 0 = none
};

}  // namespace mfbd
