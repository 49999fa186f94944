// What advances a Dynamics in time: generalized-alpha for dynamics, or load
// stepping to static equilibrium. Both share the substep loop: substeps of at
// most h_max, halved on failure down to h_min, grown back after successes;
// under error control sized by the local error estimate.
#pragma once
#include <string>

#include "integrator/dynamics.hpp"
#include "integrator/linear_solver.hpp"
#include "integrator/solver_options.hpp"

namespace mfbd {

struct IntegratorState {
  double t = 0.0;
  Configuration q;
  VectorXd v, vdot, a, lambda;  // a: generalized-alpha's algorithmic acceleration
  // Statics: dq/dt of the last load step (the secant predictor of the
  // next); empty when there is none (start, a failed step, inputs changed).
  VectorXd pathRate;
  // Dynamics: vdot and lambda at the start of the last accepted substep and
  // its size (0: none since the start or the last input jump), from which
  // the predictor extrapolates.
  VectorXd vdotBefore, lambdaBefore;
  double hBefore = 0.0;
  double h = 0.0;               // substep size to try next
  // Counters since the start of the run.
  long substeps = 0;
  long newtonIterations = 0;
  long factorizations = 0;
  long rejectedSubsteps = 0;

  template <class Archive>
  void visitState(Archive& ar) {
    ar(t, q, v, vdot, a, lambda, pathRate, h, substeps, newtonIterations, factorizations, rejectedSubsteps);
    ar(vdotBefore, lambdaBefore, hBefore);
  }
};

struct AdvanceResult {
  bool ok = true;
  double reachedTime = 0.0;  // on failure: how far substeps got before giving up
  std::string message;
  // Substeps rejected in this advance for their error estimate, and why the
  // last one was (for the log).
  long errorRejections = 0;
  std::string lastRejection;
};

class TimeStepper {
 public:
  explicit TimeStepper(const SolverOptions& options) : options_(options) {}
  virtual ~TimeStepper() = default;

  // A consistent start at state.t (accelerations, or equilibrium).
  virtual bool initialize(Dynamics& system, IntegratorState& state, std::string& message) = 0;

  // The inputs jumped at state.t (the state solves the equations of the old
  // ones): forget a substep taken past state.t with the old ones, and adjust
  // the integrator's history to the new ones (restartAfterInputJump).
  bool inputsJumped(Dynamics& system, IntegratorState& state, std::string& message) {
    ahead_.by = 0.0;
    return restartAfterInputJump(system, state, message);
  }
  // Substeps over `duration` from state.t, at most options().maxSubsteps
  // of them (tried ones, rejected included): the substep sizes depend on
  // the duration alone, not on state.t. On failure `state` is left at an
  // intermediate time: the caller restores the step start.
  // `inputsHeld`: the inputs keep their present values past the end (none
  // moves), so a stepper with a continuous extension takes substeps of its
  // own size, the last past the end, answers at the end from the extension,
  // and goes on from that substep's end in the next advance (a substep kept
  // so is forgotten by an advance whose inputs are not held, and by
  // inputsJumped).
  AdvanceResult advance(Dynamics& system, IntegratorState& state, double duration, bool inputsHeld = false);

  const SolverOptions& options() const { return options_; }

  // What influences the next substeps beyond IntegratorState: the kept
  // Newton matrix (recomputed on restore from what it was made of) and the
  // policy that decides when to refresh it.
  virtual void saveState(StateWriter& ar) {
    if (!keepsSubstepAhead()) ahead_.end = {};  // a forgotten one's buffers are not state
    ar(iteration_, ahead_.by, ahead_.end);
  }
  virtual void loadState(StateReader& ar);
  // Whether what loadState read has the shapes of `like` (the caller's
  // checked state): a substep kept past the state's time must.
  virtual bool fits(const IntegratorState& like) const;

  // The velocity jump that restores violated velocity constraints
  // Phi_q v + Phi_t = 0 (`violation` is their value): the impulse a drive
  // whose rate input jumped applies, M dv + Phi_q^T Lambda = 0. False if
  // the matrix is singular.
  static bool jumpVelocities(Dynamics& system, IntegratorState& state, const VectorXd& violation);
  // Consistent accelerations and multipliers at (t, q, v) into state.vdot
  // and state.lambda: [M Phi_q^T; Phi_q 0] [vdot; lambda] = [-r(vdot = 0,
  // lambda = 0); -gamma], a factorization of its own. False (with a
  // message) if the matrix is singular or the result not finite.
  static bool consistentAccelerations(Dynamics& system, IntegratorState& state, std::string& message);

 protected:
  // The inputs jumped at state.t: nothing by default.
  virtual bool restartAfterInputJump(Dynamics&, IntegratorState&, std::string&) { return true; }
  // One substep of size h from s.t; false (with a reason) leaves s unchanged.
  virtual bool substep(Dynamics& system, IntegratorState& s, double h, std::string& why) = 0;
  // A continuous extension (dense output) of an accepted substep: a stepper
  // with one keeps the substep just taken from `start` with size h
  // (keepExtension), and answers from it at `beforeEnd` before that
  // substep's end (interpolate: s's t is set, q, v, vdot, lambda and a
  // filled, consistent with the constraints).
  virtual bool continuousExtension() const { return false; }
  bool keepsSubstepAhead() const { return ahead_.by > 0.0; }
  virtual void keepExtension(const IntegratorState& /*start*/, double /*h*/) {}
  virtual bool interpolate(Dynamics&, IntegratorState&, double /*beforeEnd*/, std::string& why) {
    why = "no continuous extension";
    return false;
  }
  virtual void beginAdvance(const Dynamics& /*system*/) {}
  // Whether substeps are sized by their error estimate (substep then sets
  // errorRatio_, the estimate over the tolerance, and rejects a substep
  // above it with errorRejected_).
  virtual bool errorControlled() const { return false; }
  // How the step-size controller reads the estimate: it goes as
  // h^exponent on smooth motion (order p + 1 for a local error of a method
  // of order p), and an accepted substep keeps its size while the proposal
  // lies within 1 .. keepBand times it (a kept size keeps a Newton matrix).
  struct StepControl {
    double exponent = 3.0, keepBand = 1.25;
  };
  virtual StepControl stepControl() const { return {}; }
  double errorRatio_ = 0.0;
  bool errorRejected_ = false;
  // The local error a substep of size h may make under error control (error
  // per unit step, SolverOptions): tol L h / horizon.
  double allowedLocalError(double h) const {
    return options_.errorTolerance * options_.errorScale * h / options_.errorHorizon;
  }

  // Whether the constraint rows left out as redundant hold at a state where
  // the others are met (see the .cpp); if not, they are back in the solve
  // and `why` says so: the substep is to be tried again.
  bool redundantRowsHold(Dynamics& system, std::string& why) const;

  // The Newton matrix [S Phi_q^T; Phi_q -eps I] from the system's tangent,
  // auxiliary unknowns last.
  static SparseMatrix iterationMatrix(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK);
  // The same without the regularisation (eps = 0): the multipliers'
  // diagonal holds nothing else, so it is set to zero (no second tangent).
  static SparseMatrix unregularized(const Dynamics& system, SparseMatrix S);
  // Builds the Newton matrix at `at`, factorises it (a factorization of its
  // own), solves for rhs and refines the solution `refinements` times
  // against the unregularised matrix. False if the matrix is singular.
  static bool solveOnce(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK,
                        const VectorXd& rhs, int refinements, VectorXd& x);
  // The same (regularised) matrix into assembledIterationMatrix(), reusing
  // the pattern and the triplet storage of the previous call; true when the
  // pattern is new and needs a symbolic analysis.
  bool assembleIterationMatrix(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK) {
    return assembleIterationMatrix(system, at, cM, cC, cK, iteration_);
  }
  // The same into another assembly (a second matrix kept beside it).
  bool assembleIterationMatrix(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK,
                               SparseAssembly& into);
  // Rows of the Newton matrix with mass factor cM: velocities, multipliers
  // (from velocityCount() on) and the system's auxiliary unknowns.
  static int newtonSize(const Dynamics& system, double cM);
  // The system's pivot order (Dynamics::pivotOrder) in the matrix's indices.
  static std::vector<std::pair<int, int>> pivotOrder(const Dynamics& system, double cM);
  const SparseMatrix& assembledIterationMatrix() const { return iteration_.matrix(); }
  // Phi_q of the last assembleIterationMatrix, dense (constraintCount x velocityCount).
  Eigen::MatrixXd assembledJacobian(const Dynamics& system) const { return denseJacobian(system, jacobianTriplets_); }
  static Eigen::MatrixXd denseJacobian(const Dynamics& system, const Triplets& jacobian);

  SolverOptions options_;

 private:
  // The next substep size after an accepted one of size `step` whose error
  // estimate was `ratio` times the tolerance; h the size tried.
  double nextStep(double h, double step, double ratio) const;
  // The factor 0.9 ratio^(-1/exponent) of the elementary controller, within [low, high].
  double stepFactor(double ratio, double low, double high) const;
  static void iterationTriplets(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK,
                                Triplets& all, Triplets& jacobian);

  Triplets iterationTriplets_, jacobianTriplets_;
  SparseAssembly iteration_;
  // The last substep of an advance taken past its end: its end state,
  // `by` seconds past the state's time (0: none; forgotten by setting it
  // to 0, so the end state's buffers serve the next one).
  struct Ahead {
    double by = 0.0;
    IntegratorState end;
  } ahead_;
  IntegratorState substepStart_;  // advance's workspace: the start of a substep taken past the end
  bool answerAhead(Dynamics& system, IntegratorState& s, double t, double beforeEnd, AdvanceResult& result);
  double resumeAhead(IntegratorState& s) const;
  std::string tooManySubsteps(const std::string& rejected, double duration, double needed, double h) const;
  double afterRejection(IntegratorState& s, double step, const std::string& why, AdvanceResult& result,
                        std::string& rejected) const;
};

}  // namespace mfbd
