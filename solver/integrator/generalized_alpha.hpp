// Generalized-alpha for constrained systems on a Lie group (Arnold & Bruls
// 2007; Bruls, Cardona & Arnold 2012), index-3 constraints, with the
// iteration matrix scaled by 1/beta' (Bottasso, Bauchau & Cardona 2007) so it
// stays well conditioned as h -> 0:
//   [ M + (gamma'/beta') C + K/beta'   Phi_q^T ] [ dq          ]   [ -r/beta' ]
//   [ Phi_q                            0       ] [ dlambda/beta'] = [ -Phi     ]
// Modified Newton: the factorised matrix is kept across substeps, turned with
// the bodies that rotated since (Dynamics::turnWithRotations), and refreshed
// when the contraction slows (see substep and beginAdvance).
// Newton failure halves the substep down to h_min; the caller keeps the state
// of the step start and reports a discarded step.
#pragma once
#include <algorithm>

#include "integrator/time_stepper.hpp"

namespace mfbd {

class GeneralizedAlpha : public TimeStepper {
 public:
  explicit GeneralizedAlpha(const SolverOptions& options);

  // Consistent initial accelerations (M vdot = Q at t) and a = vdot.
  bool initialize(Dynamics& system, IntegratorState& state, std::string& message) override;
  // Accelerations, a and multipliers jump by the substep's own response to
  // the jump of the forces (see the .cpp).
  bool restartAfterInputJump(Dynamics& system, IntegratorState& state, std::string& message) override;
  // The (regularised) Newton matrix that a substep of size h factorizes at
  // state `at`: for diagnostics (condition number against h).
  SparseMatrix newtonMatrix(Dynamics& system, const IntegratorState& at, double h) const;

  void saveState(StateWriter& ar) override {
    TimeStepper::saveState(ar);
    visitState(ar);
  }
  void loadState(StateReader& ar) override {
    TimeStepper::loadState(ar);
    visitState(ar);
  }

 protected:
  bool substep(Dynamics& system, IntegratorState& state, double h, std::string& why) override;
  // At a communication point (where inputs may have jumped) a fresh
  // iteration matrix when it pays: the last substep took k corrections
  // where a fresh matrix takes two; the k - 2 extra ones (a residual and a
  // solve each) recur over the next substeps until the matrix is refreshed
  // anyway, counted as kRefreshHorizon of them, against a tangent of
  // tangentCost() residuals. A double pendulum (cost 3) then refreshes
  // whenever k > 2, a beam mesh (16) when k > 6, an 81-joint tree with 40
  // loops (82) hardly ever. Where the kept matrix itself has gone stale
  // (its contraction at the first check above kStaleRate: a beam whose spin
  // speeds up, with its centrifugal stiffening), a fresh one will serve
  // about as long as this one did, so the horizon is half the substeps it
  // served; corrections that come from the predictor's nonlinearity (a
  // ringing cantilever: contraction 1e-4) do not go away with a fresh
  // matrix and keep the short horizon (F4 at 2 elements: 4.7 -> 3.0
  // corrections per substep, -23 % time; F3 unchanged). The rule depends
  // on the run alone, so a run replays bit for bit.
  void beginAdvance(const Dynamics& system) override {
    const double horizon =
        firstRate_ > kStaleRate ? std::max(kRefreshHorizon, 0.5 * substepsSinceFactorization_) : kRefreshHorizon;
    if (horizon * (lastIterations_ - 2) > system.tangentCost()) factoredStep_ = 0.0;
  }
  static constexpr double kRefreshHorizon = 4.0;
  static constexpr double kStaleRate = 1e-3;

 private:
  bool factorize(Dynamics& system, const IntegratorState& trial, double h);
  // Factors of M, C and K in the scaled Newton matrix: 1, gamma'/beta', 1/beta'.
  struct MatrixFactors {
    double cM, cC, cK;
  };
  MatrixFactors matrixFactors(double h) const;
  double constraintNoise(const Dynamics& system, int n, int m, int size) const;
  void projectVelocities(Dynamics& system, IntegratorState& trial, double gammaPrime);

  double alphaM_, alphaF_, gamma_, beta_;
  LinearSolver solver_;
  double factoredStep_ = 0.0;  // substep size of the current factorization; 0 = none
  double correctionNoise_ = 0.0;  // of the current factorization (constraintNoise)
  bool elasticCoordinates_ = true;  // of the system (Dynamics::elasticCoordinates)
  Configuration factoredAt_;  // configuration of the current factorization (turnWithRotations)
  IntegratorState trial_;  // substep workspace (see substep)
  VectorXd hDeltaQ_, r_, phi_, rhs_, delta_;
  // Substeps still to start with a fresh matrix after an earlier
  // substep's matrix failed to contract: a system whose Newton matrix
  // changes too fast for modified Newton (the flexible four-bar with its
  // defect: 0.3 % entry changes per substep, a 50 times larger first
  // correction) then pays a tangent per substep but no wasted corrections;
  // every kFreshStarts + 1 substeps the kept matrix is tried again.
  int freshStarts_ = 0;
  static constexpr int kFreshStarts = 4;
  double lastIterations_ = 1e9;  // Newton iterations of the last accepted substep (none yet: many)
  double substepsSinceFactorization_ = 0.0;  // accepted since the current factorization
  double firstRate_ = 0.0;
  double lastRate_ = 1.0;  // contraction at the last check of the previous substep (1: unknown)
  double keptRate_ = 1.0;  // contraction of the current factorization at its last check (1: not yet known)  // contraction at the first check of the last substep with a kept matrix

  // Members that carry over from one substep to the next (the rest is
  // workspace or constant): one line each.
  template <class Archive>
  void visitState(Archive& ar) {
    ar(factoredStep_, correctionNoise_, elasticCoordinates_, factoredAt_);
    ar(freshStarts_, lastIterations_, substepsSinceFactorization_, firstRate_, lastRate_, keptRate_);
    solver_.saveOrLoad(ar);
  }
};

}  // namespace mfbd
