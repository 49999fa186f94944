// Generalized-alpha for constrained systems on a Lie group (Arnold & Bruls
// 2007; Bruls, Cardona & Arnold 2012), index-3 constraints, with the
// iteration matrix scaled by 1/beta' (Bottasso, Bauchau & Cardona 2007) so it
// stays well conditioned as h -> 0:
//   [ M + (gamma'/beta') C + K/beta'   Phi_q^T ] [ dq          ]   [ -r/beta' ]
//   [ Phi_q                            0       ] [ dlambda/beta'] = [ -Phi     ]
// Modified Newton: the factorised matrix is kept across substeps, turned with
// the bodies that rotated since (Dynamics::turnWithRotations), and refreshed
// when the contraction slows (MatrixRefreshPolicy, integrator/newton.cpp).
// Newton failure halves the substep down to h_min; the caller keeps the state
// of the step start and reports a discarded step.
#pragma once
#include <algorithm>
#include <limits>

#include "integrator/newton.hpp"
#include "integrator/time_stepper.hpp"

namespace mfbd {

class GeneralizedAlpha : public TimeStepper {
 public:
  explicit GeneralizedAlpha(const SolverOptions& options);

  // Consistent initial accelerations (M vdot = Q at t) and a = vdot.
  bool initialize(Dynamics& system, IntegratorState& state, std::string& message) override;
  // The (regularised) Newton matrix that a substep of size h factorizes at
  // state `at`: for diagnostics (condition number against h).
  SparseMatrix newtonMatrix(Dynamics& system, const IntegratorState& at, double h) const;

  void saveState(StateWriter& ar) override {
    TimeStepper::saveState(ar);
    visitState(ar);
  }
  void loadState(StateReader& ar) override;
  // The memory of the Newton iteration, everything of it that influences
  // the next substep (for FMU state). Restoring refactorises the kept
  // matrix at its origin; false if that matrix is singular.
  const NewtonMemory& newtonMemory() const { return refresh_.memory; }
  bool restoreNewtonMemory(Dynamics& system, const NewtonMemory& memory);

 protected:
  // Accelerations, a and multipliers jump by the substep's own response to
  // the jump of the forces (see the .cpp).
  bool restartAfterInputJump(Dynamics& system, IntegratorState& state, std::string& message) override;
  bool substep(Dynamics& system, IntegratorState& state, double h, std::string& why) override;
  void beginAdvance(const Dynamics& system) override {
    refresh_.beginAdvance(system.tangentCost());
    flexibleBodies_ = system.flexibleBodies();
  }
  bool errorControlled() const override { return options_.errorTolerance > 0.0; }
  // The estimate goes as h^3, held per unit step (h^2 against the error
  // allowed) in the modes that add up (see errorRatio).
  StepControl stepControl() const override { return {2.0, 1.25}; }

 private:
  friend class SubstepNewton;
  bool factorize(Dynamics& system, const IntegratorState& trial, double h);
  double localError(const IntegratorState& s, const IntegratorState& trial, double h);
  double errorRatio(Dynamics& system, const IntegratorState& trial, double h, double local);
  // Error control with flexible bodies splits the local error by the Newton
  // matrix at h_max, S_c (errorRatio).
  bool splitsError() const { return errorControlled() && flexibleBodies_; }
  bool factorizeCutoff(Dynamics& system, const IntegratorState& at);
  // x = A^-1 b for a matrix A factorised at `origin`, turned with the
  // rotations from there to q (b is overwritten).
  void solveTurned(const Dynamics& system, const LinearSolver& A, const Configuration& origin,
                   const Configuration& q, VectorXd& b, VectorXd& x) const;
  void predict(Dynamics& system, const IntegratorState& s, double h, IntegratorState& trial);
  // Factors of M, C and K in the scaled Newton matrix: 1, gamma'/beta', 1/beta'.
  struct MatrixFactors {
    double cM, cC, cK;
  };
  MatrixFactors matrixFactors(double h) const;
  double constraintNoise(const Dynamics& system, int n, int m, int size) const;
  void projectVelocities(Dynamics& system, const IntegratorState& start, IntegratorState& trial, double gammaPrime,
                         double betaPrime);
  void matrixTimesProjection(Dynamics& system, const IntegratorState& start, const IntegratorState& trial,
                             double gammaPrime, double betaPrime);

  double alphaM_, alphaF_, gamma_, beta_;
  bool flexibleBodies_ = false;  // in the system advanced (beginAdvance)
  LinearSolver solver_;
  // S_c (splitsError), factorised at cutoffOrigin_ (t NaN: not yet).
  SparseAssembly cutoffMatrix_;
  LinearSolver cutoff_;
  struct {
    double t = std::numeric_limits<double>::quiet_NaN();
    Configuration q;
  } cutoffOrigin_;
  VectorXd localError_, massTimesError_, slowError_;  // errorRatio's workspace
  // How far each coordinate has moved since initialize: the sum of the
  // accepted substeps' chart increments and the range it has covered
  // (errorRatio). Angles of rotations summed so are not a rotation's
  // angle, but they bound its motion.
  struct MotionRange {
    VectorXd displacement, low, high;
    void add(const VectorXd& increment) {
      displacement += increment;
      low = low.cwiseMin(displacement);
      high = high.cwiseMax(displacement);
    }
  } motion_;
  // A part of the local errors, slow or fast, summed along the motion: G
  // in positions with its rates, accelerations and multipliers
  // (propagateErrors). linearSum: what the part's local errors add up to if
  // none cancels (the premise of holding them per unit step); largest: the
  // most that G has reached. Both over the coordinates that have moved.
  struct ErrorSum {
    VectorXd q, v, a, vdot, lambda;
    double linearSum = 0.0, largest = 0.0;
    // How many times less than their sum the part's errors have added up to.
    double cancellation() const { return largest > 0.0 ? std::max(1.0, linearSum / largest) : 1.0; }
  } slowSum_, fastSum_;
  void propagateErrors(Dynamics& system, const IntegratorState& trial, double h);
  void propagate(Dynamics& system, const IntegratorState& trial, double h, ErrorSum& sum);
  // Whether coordinate i, or any of the n, has moved by tol L since the
  // start (MotionRange); the largest entry of x over those that have.
  bool moved(int i) const;
  bool somethingMoved(int n) const;
  double largestMoving(const VectorXd& x) const;
  VectorXd fastError_, predictedA_, phiBase_;  // errorRatio's and propagate's workspace
  bool baseResidual_ = false;  // base_, phiBase_ hold the residual at the trial (errorRatio)
  MatrixRefreshPolicy refresh_;
  IntegratorState trial_;  // substep workspace (see substep)
  VectorXd hDeltaQ_, r_, phi_, rhs_, delta_;
  // projectVelocities' workspace: (dq, mu) so far, the residual at the
  // trial, and the trial moved along the Newton direction (with the
  // substep's increment to get there).
  VectorXd projection_, base_, movedIncrement_;
  IntegratorState moved_;

  // Members that carry over from one substep to the next (the rest is
  // workspace or constant): the Newton memory member by member, and the
  // matrices the linear solver factorized (refactorized when first used).
  template <class Archive>
  void visitState(Archive& ar) {
    NewtonMemory& m = refresh_.memory;
    ar(m.factoredStep, m.origin.t, m.origin.q, m.origin.v, m.origin.vdot, m.origin.lambda);
    ar(m.correctionNoise, m.elasticCoordinates, m.freshStarts, m.lastIterations, m.substepsSinceFactorization);
    ar(m.firstRate, m.lastRate, m.newtonErrorLeft, m.discretisationError);
    solver_.saveOrLoad(ar);
    ar(cutoffMatrix_, cutoffOrigin_.t, cutoffOrigin_.q, motion_.displacement, motion_.low, motion_.high);
    for (ErrorSum* g : {&slowSum_, &fastSum_}) ar(g->q, g->v, g->a, g->vdot, g->lambda, g->linearSum, g->largest);
    cutoff_.saveOrLoad(ar);
  }
};

}  // namespace mfbd
