#include "integrator/generalized_alpha.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "math/number_text.hpp"

namespace mfbd {

GeneralizedAlpha::GeneralizedAlpha(const SolverOptions& options) : TimeStepper(options) {
  const double rho = options.rhoInf;
  alphaM_ = (2.0 * rho - 1.0) / (rho + 1.0);
  alphaF_ = rho / (rho + 1.0);
  gamma_ = 0.5 + alphaF_ - alphaM_;
  beta_ = 0.25 * (gamma_ + 0.5) * (gamma_ + 0.5);
}

namespace {
bool allFinite(const VectorXd& x) { return x.allFinite(); }
}  // namespace

bool GeneralizedAlpha::initialize(Dynamics& system, IntegratorState& state, std::string& message) {
  if (!consistentAccelerations(system, state, message)) return false;
  state.a = state.vdot;
  state.hBefore = 0.0;
  if (state.h <= 0.0) state.h = options_.hMax;
  motion_.displacement.setZero(system.velocityCount());
  motion_.low = motion_.high = motion_.displacement;
  slowSum_ = fastSum_ = ErrorSum();
  return true;
}

// After the inputs jump, the residual of the state is -(the jump of the
// forces). The accelerations jump by what the next substep's Newton matrix
// makes of it, [S Phi_q^T; Phi_q 0] [dvdot; dlambda] = [-r; 0] with
// S = M + (gamma'/beta') C + K/beta': in modes slow for the step (K/beta' <<
// M) that is the jump of M^-1 f that a restart a = vdot would give, removing
// the O(h) error of the old input's acceleration; in modes too stiff for the
// step (omega h >> 1) it is a small static response, where a = vdot would
// put f/m into the h^2 terms of the next step (a joint torque on a flexible
// node of tiny rotary inertia: 1e7 rad/s^2, radians per step).
bool GeneralizedAlpha::restartAfterInputJump(Dynamics& system, IntegratorState& s, std::string& message) {
  const int n = system.velocityCount(), m = system.constraintCount();
  VectorXd r, phi;
  system.residual(s.t, s.q, s.v, s.vdot, s.lambda, r, phi);
  if (!allFinite(r)) {
    message = "residual is not finite after the input change";
    return false;
  }
  const MatrixFactors c = matrixFactors(s.h > 0.0 ? s.h : options_.hMax);
  VectorXd rhs = VectorXd::Zero(newtonSize(system, c.cM));
  rhs.head(n) = -r;
  VectorXd jump;
  if (!solveOnce(system, s, c.cM, c.cC, c.cK, rhs, 0, jump)) {
    message = "singular iteration matrix after the input change";
    return false;
  }
  s.vdot += jump.head(n);
  s.a += jump.head(n);
  s.lambda += jump.segment(n, m);
  s.hBefore = 0.0;  // the accelerations jumped: nothing to extrapolate from
  return true;
}

GeneralizedAlpha::MatrixFactors GeneralizedAlpha::matrixFactors(double h) const {
  const double betaPrime = (1.0 - alphaM_) / (beta_ * h * h * (1.0 - alphaF_));
  const double gammaPrime = gamma_ / (beta_ * h);
  return {1.0, gammaPrime / betaPrime, 1.0 / betaPrime};
}

SparseMatrix GeneralizedAlpha::newtonMatrix(Dynamics& system, const IntegratorState& at, double h) const {
  const MatrixFactors c = matrixFactors(h);
  return iterationMatrix(system, at, c.cM, c.cC, c.cK);
}

bool GeneralizedAlpha::factorize(Dynamics& system, const IntegratorState& trial, double h) {
  const MatrixFactors c = matrixFactors(h);
  if (assembleIterationMatrix(system, trial, c.cM, c.cC, c.cK))
    solver_.analyzePattern(assembledIterationMatrix(), pivotOrder(system, c.cM));
  if (solver_.factorize(assembledIterationMatrix()) != LinearSolver::Status::Ok) return false;
  // S_c (errorRatio) is made again with a fresh Newton matrix once the
  // motion has gone on by h_max since it was made: while the Newton matrix
  // is kept, so is S_c.
  if (splitsError() && !(std::abs(trial.t - cutoffOrigin_.t) < options_.hMax)) factorizeCutoff(system, trial);
  NewtonMemory& memory = refresh_.memory;
  memory.origin.t = trial.t;
  memory.origin.q = trial.q;
  memory.origin.v = trial.v;
  memory.origin.vdot = trial.vdot;
  memory.origin.lambda = trial.lambda;
  memory.elasticCoordinates = system.elasticCoordinates();
  memory.correctionNoise = constraintNoise(system, system.velocityCount(), system.constraintCount(),
                                           assembledIterationMatrix().rows());
  return true;
}

void GeneralizedAlpha::loadState(StateReader& ar) {
  TimeStepper::loadState(ar);
  visitState(ar);
  if (!cutoffMatrix_.valid()) throw StateError("the saved cutoff matrix's pattern is inconsistent");
}

void GeneralizedAlpha::solveTurned(const Dynamics& system, const LinearSolver& A, const Configuration& origin,
                                   const Configuration& q, VectorXd& b, VectorXd& x) const {
  system.turnWithRotations(origin, q, b, true);
  A.solve(b, x);
  system.turnWithRotations(origin, q, x, false);
}

bool GeneralizedAlpha::restoreNewtonMemory(Dynamics& system, const NewtonMemory& memory) {
  refresh_.memory = memory;
  if (memory.factoredStep <= 0.0) return true;
  IntegratorState at;
  at.t = memory.origin.t;
  at.q = memory.origin.q;
  at.v = memory.origin.v;
  at.vdot = memory.origin.vdot;
  at.lambda = memory.origin.lambda;
  if (factorize(system, at, memory.factoredStep)) return true;
  refresh_.failed();
  return false;
}

// The correction that the round-off of the constraint rows alone produces
// through the factorised matrix: Newton corrections of that size are noise,
// not progress. It grows with the matrix's conditioning, e.g. as a
// closed-loop mechanism nears a singular configuration, where a fixed
// floor would reject converged steps. Estimated by one solve with a
// pseudo-random sign pattern of the rows' round-off level.
double GeneralizedAlpha::constraintNoise(const Dynamics& system, int n, int m, int size) const {
  if (m == 0) return 0.0;
  const double level = 2.0 * std::numeric_limits<double>::epsilon() * system.constraintLengthScale();
  VectorXd rhs = VectorXd::Zero(size);
  unsigned pattern = 12345u;
  for (int i = 0; i < m; ++i) {
    pattern = pattern * 1103515245u + 12345u;
    rhs[n + i] = (pattern >> 16) & 1u ? level : -level;
  }
  const double noise = solver_.solve(rhs).head(n).cwiseAbs().maxCoeff();
  return std::isfinite(noise) ? noise : 0.0;
}

// Without numerical damping (rho_inf = 1) index-3 generalized-alpha is
// only weakly stable in the constraint directions: the velocity-level
// violation Phi_q v + Phi_t is not damped and drifts (four_bar at rho_inf
// = 1: energy error 3.7e-4 J at 5 s, 0.57 J at 15 s, Newton failing at
// 16.4 s). There each accepted substep removes it: the velocity change
// dv = gamma' dq with [S Phi_q^T; Phi_q 0] [dq; mu] = [0; -violation /
// gamma'] at the substep's end, S = M + (gamma'/beta') C + K/beta' (the
// least change in the metric of the scheme's own matrix).
// The factorised matrix may be kept from an earlier substep: its S and
// Phi_q are those of its origin, and the projection it gives is oblique,
// off by the matrix's age. That error does not shrink as Newton
// converges, and it moves energy in and out at every substep (Bricard at
// h = 1e-3 with a matrix kept for some ten substeps: energy drift 3.3e-7
// m g L, against 6.7e-8 with a fresh one). So the second sweep refines
// against the matrix at the substep's end: its force rows carry
// -(S dq + Phi_q^T mu) of the first sweep's projection, taken as the
// residual's change along the Newton direction (one residual, the base
// residual one more: the converged Newton iterate leaves one of the
// Newton tolerance's size); its constraint rows the violation left.
void GeneralizedAlpha::projectVelocities(Dynamics& system, const IntegratorState& start, IntegratorState& trial,
                                         double gammaPrime, double betaPrime) {
  const int n = system.velocityCount(), m = system.constraintCount();
  const bool keptMatrix = refresh_.memory.origin.t != trial.t;
  projection_.setZero(n + m);
  for (int sweep = 0; sweep < 2; ++sweep) {
    const VectorXd violation = system.velocityConstraints(trial.t, trial.q, trial.v);
    if (violation.size() != m) return;
    rhs_.setZero(assembledIterationMatrix().rows());
    rhs_.segment(n, m) = -violation / gammaPrime;
    if (sweep > 0 && keptMatrix) matrixTimesProjection(system, start, trial, gammaPrime, betaPrime);
    solveTurned(system, solver_, refresh_.memory.origin.q, trial.q, rhs_, delta_);
    if (!delta_.allFinite()) return;
    projection_ += delta_.head(n + m);
    trial.v += gammaPrime * delta_.head(n);
  }
}

// rhs_'s force rows -(S dq + Phi_q^T mu) for the projection (dq, mu) so
// far, at the trial: the residual's change over a step e (dq, mu) along
// the Newton direction (q by e dq, v by gamma' e dq, vdot by beta' e dq,
// lambda by beta' e mu) is beta' e (S dq + Phi_q^T mu). The step moves the
// coordinates by 1e-8 (the square root of the round-off): truncation and
// round-off about 1e-8 of the product.
void GeneralizedAlpha::matrixTimesProjection(Dynamics& system, const IntegratorState& start,
                                             const IntegratorState& trial, double gammaPrime, double betaPrime) {
  const int n = system.velocityCount(), m = system.constraintCount();
  const double largest = projection_.head(n).cwiseAbs().maxCoeff();
  if (!(largest > 0.0)) return;
  const double e = 1e-8 / largest;
  system.residual(trial.t, trial.q, trial.v, trial.vdot, trial.lambda, base_, phi_);
  movedIncrement_ = hDeltaQ_ + e * projection_.head(n);
  moved_.q = start.q;
  system.retract(moved_.q, movedIncrement_);
  moved_.v = trial.v + (gammaPrime * e) * projection_.head(n);
  moved_.vdot = trial.vdot + (betaPrime * e) * projection_.head(n);
  moved_.lambda = trial.lambda + (betaPrime * e) * projection_.tail(m);
  system.residual(trial.t, moved_.q, moved_.v, moved_.vdot, moved_.lambda, r_, phi_);
  rhs_.head(n) = (base_ - r_) / (betaPrime * e);
}

// The Newton problem of one substep: corrections dq of the increment h
// Delta q, with v, vdot, a and the multipliers following through gamma',
// beta' (Arnold & Bruls 2007). Its vectors are GeneralizedAlpha's members:
// assigned, not allocated, every substep.
class SubstepNewton : public NewtonSystem {
 public:
  SubstepNewton(GeneralizedAlpha& ga, Dynamics& system, const IntegratorState& start, IntegratorState& trial,
                double h)
      : ga_(ga), system_(system), start_(start), trial_(trial), n_(system.velocityCount()),
        m_(system.constraintCount()) {
    betaPrime_ = (1.0 - ga.alphaM_) / (ga.beta_ * h * h * (1.0 - ga.alphaF_));
    gammaPrime_ = ga.gamma_ / (ga.beta_ * h);
  }
  double gammaPrime() const { return gammaPrime_; }
  double betaPrime() const { return betaPrime_; }

  bool evaluate(NewtonIterate& it, std::string& why) override {
    system_.residual(trial_.t, trial_.q, trial_.v, trial_.vdot, trial_.lambda, ga_.r_, ga_.phi_);
    if (!allFinite(ga_.r_) || !allFinite(ga_.phi_)) {
      why = "residual is not finite";
      return false;
    }
    it.violation = m_ > 0 ? ga_.phi_.cwiseAbs().maxCoeff() : 0.0;
    it.violationFloor = 64.0 * std::numeric_limits<double>::epsilon() * system_.constraintLengthScale();
    return true;
  }

  bool factorize(double h, std::string& why) override {
    if (!ga_.factorize(system_, trial_, h)) {
      why = "singular iteration matrix";
      return false;
    }
    ++trial_.factorizations;
    return true;
  }

  // The matrix factorised at the origin, turned with the rotations since
  // (Dynamics::turnWithRotations): a spinning beam's matrix stays good for
  // as long as its deformation and speed change little. The update of q, v,
  // vdot and a in one pass over the correction, with its largest entry and
  // a NaN check (0 d sums to 0 unless some d is not finite).
  double correct() override {
    VectorXd &rhs = ga_.rhs_, &delta = ga_.delta_;
    rhs.setZero(ga_.assembledIterationMatrix().rows());
    rhs.head(n_) = -ga_.r_ / betaPrime_;
    rhs.segment(n_, m_) = -ga_.phi_;
    ga_.solveTurned(system_, ga_.solver_, ga_.refresh_.memory.origin.q, trial_.q, rhs, delta);
    ++trial_.newtonIterations;
    double size = 0.0, notFinite = 0.0;
    const double* d = delta.data();
    double *dq = ga_.hDeltaQ_.data(), *v = trial_.v.data(), *vdot = trial_.vdot.data(), *a = trial_.a.data();
    const double aPerCorrection = (1.0 - ga_.alphaF_) / (1.0 - ga_.alphaM_) * betaPrime_;
    for (int i = 0; i < n_; ++i) {
      const double di = d[i];
      dq[i] += di;
      v[i] += gammaPrime_ * di;
      vdot[i] += betaPrime_ * di;
      a[i] += aPerCorrection * di;
      size = std::max(size, std::abs(di));
      notFinite += 0.0 * di;
    }
    if (notFinite != 0.0) return std::numeric_limits<double>::quiet_NaN();
    trial_.q = start_.q;
    system_.retract(trial_.q, ga_.hDeltaQ_);
    if (m_ > 0) trial_.lambda += betaPrime_ * delta.segment(n_, m_);
    return size;
  }

 private:
  GeneralizedAlpha& ga_;
  Dynamics& system_;
  const IntegratorState& start_;
  IntegratorState& trial_;
  int n_, m_;
  double betaPrime_, gammaPrime_;
};

// Local error estimate of the substep, in the position coordinates (m,
// rad) of the chart at its start (Geradin & Cardona 2001, ch. 7, for the
// Newmark family): the substep's increment h v_n + h^2 ((1/2 - beta) a_n +
// beta a_{n+1}) against a Taylor increment one order higher, h v_n + h^2
// (vdot_n / 3 + vdot_{n+1} / 6) (the third derivative taken as the
// difference of the accelerations at the ends over h), so
//   e = h^2 [(1/2 - beta) a_n + beta a_{n+1} - vdot_n / 3 - vdot_{n+1} / 6],
// O(h^3) on smooth motion. Stiff modes that the step does not resolve show
// in it as large differences of the accelerations at the two ends. No
// estimate in the velocities: a_n carries an offset of order h_{n-1} from
// vdot_n (the algorithmic acceleration lags by (alpha_m - alpha_f) h_{n-1}),
// which an estimate of order h would see after every change of step size
// however small the substep.
double GeneralizedAlpha::localError(const IntegratorState& s, const IntegratorState& trial, double h) {
  if (s.vdot.size() == 0) return 0.0;
  localError_ = h * h * ((0.5 - beta_) * s.a + beta_ * trial.a - s.vdot / 3.0 - trial.vdot / 6.0);
  return localError_.cwiseAbs().maxCoeff();
}

// The estimate against the error allowed. Held per unit step (tol L h / T):
// local errors add up over the run, so the error reached follows the
// tolerance. With flexible bodies the estimate also holds modes the
// substep is not meant to resolve (a beam's axial and shear modes, up to
// 1e8 rad/s): held per unit step they would be resolved (flexible_four_bar
// needed substeps of 1e-7 s), and their errors do not add up, the
// numerical damping (rho_inf < 1) removes them. So the estimate e is split
// by the Newton matrix at h_max, S_c = M + (gamma'/beta') C + K/beta':
// e_slow = S_c^-1 M e keeps the modes slower than about 1 / h_max (each
// mode scaled by 1 / (1 + beta h_max^2 omega^2)) and is held per unit step,
// relaxed as far as the errors are seen to cancel (propagateErrors); the
// rest per step (tol L). h_max is where the user says the motion of
// interest ends; a split at the substep's own size would pass every mode
// as h shrinks and resolve them all. M e is the residual's change with
// vdot by e; the solve is constrained, so e_slow respects the joints. S_c
// does not depend on h: it is made again with a fresh Newton matrix once
// the motion has gone on by h_max, its own step (factorize), and turned
// with the rotations in between as the Newton matrix is. Where S_c is
// singular (a beam buckling under a step of h_max) the whole estimate is
// held per step.
// Errors add up only as far as the motion goes: an oscillation's phase
// error is at most twice its amplitude. So a coordinate whose motion since
// the start has stayed within a range of tol L holds all its estimate per
// step (F3's tip pulse of 1.3e-4 L at tolerance 1e-3 took 6,454 substeps
// of its 10 s where 1,000 of h_max are as right). The motion is the sum
// of the substeps' chart increments (MotionRange).
double GeneralizedAlpha::errorRatio(Dynamics& system, const IntegratorState& trial, double h, double local) {
  const double perStep = options_.errorTolerance * options_.errorScale;
  if (!splitsError()) return local / allowedLocalError(h);
  if (localError_.size() == 0) return 0.0;
  const int n = system.velocityCount();
  baseResidual_ = false;
  // Unless split below, all of the estimate is fast.
  slowError_.setZero(n);
  fastError_ = localError_;
  if (std::isnan(cutoffOrigin_.t) && !factorizeCutoff(system, trial)) return local / perStep;
  // Nothing has moved by tol L yet: all of the estimate is held per step,
  // and the split would not change the ratio.
  if (!somethingMoved(n)) return local / perStep;
  if (!(local > 0.0)) return 0.0;
  // The residual is linear in vdot, so M e is its change by s e over s,
  // with s e as large as vdot. By e itself, far smaller than vdot at tight
  // tolerances, the change drowned in the residual's rounding, and the slow
  // part came out as noise that no substep size reduced (F5 at 1e-6:
  // discarded after a storm of rejected substeps at 2e-8 s).
  int exponent = 0;
  std::frexp((trial.vdot.cwiseAbs().maxCoeff() + 1.0) / local, &exponent);
  const double s = std::ldexp(1.0, exponent);  // frexp, ldexp: no newer glibc symbols than 2.17
  VectorXd& vdot = slowError_;  // workspace until the solve
  vdot = trial.vdot + s * localError_;
  system.residual(trial.t, trial.q, trial.v, vdot, trial.lambda, massTimesError_, phi_);
  system.residual(trial.t, trial.q, trial.v, trial.vdot, trial.lambda, base_, phiBase_);
  baseResidual_ = true;
  rhs_.setZero(cutoffMatrix_.matrix().rows());
  rhs_.head(n) = (massTimesError_ - base_) / s;
  solveTurned(system, cutoff_, cutoffOrigin_.q, trial.q, rhs_, delta_);
  slowError_ = delta_.head(n);
  for (int i = 0; i < n; ++i) {
    if (moved(i))
      fastError_[i] = localError_[i] - slowError_[i];
    else
      slowError_[i] = 0.0;
  }
  const double cancellation = std::min(slowSum_.cancellation(), fastSum_.cancellation());
  const double allowedSlow = std::min(perStep, allowedLocalError(h) * cancellation);
  return std::max(slowError_.cwiseAbs().maxCoeff() / allowedSlow, fastError_.cwiseAbs().maxCoeff() / perStep);
}

bool GeneralizedAlpha::moved(int i) const {
  return motion_.high[i] - motion_.low[i] > options_.errorTolerance * options_.errorScale;
}

bool GeneralizedAlpha::somethingMoved(int n) const {
  if (motion_.displacement.size() != n) return false;
  for (int i = 0; i < n; ++i)
    if (moved(i)) return true;
  return false;
}

double GeneralizedAlpha::largestMoving(const VectorXd& x) const {
  double largest = 0.0;
  for (int i = 0; i < x.size(); ++i)
    if (moved(i)) largest = std::max(largest, std::abs(x[i]));
  return largest;
}

// Per unit step assumes that the slow errors add up over the run. Those
// of a free motion do (a beam's free vibration: the phase error grows),
// those of a forced response do not: the error that a drive's motion
// leaves in a beam's bending mode (F4's spin-up, F5's crank) rings in that
// mode, bounded by about the local error over omega h, and per unit step
// resolved it far below the tolerance (F4 on 2 elements at 1e-3: 8,189
// substeps for 20 s, where 738 held per step ended 0.57 tol L off). So
// each part of the estimate, slow and fast, is summed along the motion,
// G, as the integrator carries any perturbation: each accepted substep
// propagates G through the substep linearized about the motion (a Newton
// iteration of the substep from G, residual differences along a scaled G,
// solved with the kept Newton matrix until the error left falls below
// 1e-3 of G, at most three corrections) and adds its own part. The slow
// part is held per unit step times how many times less than the sum of
// their sizes the errors have added up to (ErrorSum::cancellation), never
// above per step.
// Where G grows with the sum (resonance, an unstable motion, a
// propagation that did not converge) that is 1: per unit step. The
// fast part's own cancellation bounds it too: modes faster than 1 / h_max
// that the substeps resolve keep their errors, held per step (F4 sampled
// with h_max = 0.2 s: 8.9 times the tolerance at 1e-8 relaxed by the slow
// part's cancellation alone, 3.0 times by both). The fast part itself is
// held per step: per unit step it would resolve the modes rho_inf damps.
void GeneralizedAlpha::propagateErrors(Dynamics& system, const IntegratorState& trial, double h) {
  if (!baseResidual_) system.residual(trial.t, trial.q, trial.v, trial.vdot, trial.lambda, base_, phiBase_);
  for (auto [g, added] : {std::pair{&slowSum_, &slowError_}, std::pair{&fastSum_, &fastError_}}) {
    propagate(system, trial, h, *g);
    g->q += *added;
    g->linearSum += largestMoving(*added);
    g->largest = std::max(g->largest, largestMoving(g->q));
    if (!g->q.allFinite()) *g = ErrorSum();  // propagated nothing right: per unit step again
  }
}

void GeneralizedAlpha::propagate(Dynamics& system, const IntegratorState& trial, double h, ErrorSum& g) {
  const int n = system.velocityCount(), m = system.constraintCount();
  if (g.q.size() != n || g.lambda.size() != m) {
    g = ErrorSum();
    g.q.setZero(n);
    g.v = g.a = g.vdot = g.q;
    g.lambda.setZero(m);
    return;
  }
  // The predictor (vdot kept), as for the substep itself.
  predictedA_ = (g.vdot - alphaM_ * g.a) / (1.0 - alphaM_);
  g.q += h * g.v + h * h * ((0.5 - beta_) * g.a + beta_ * predictedA_);
  g.v += h * ((1.0 - gamma_) * g.a + gamma_ * predictedA_);
  g.a = predictedA_;
  const double betaPrime = (1.0 - alphaM_) / (beta_ * h * h * (1.0 - alphaF_));
  const double gammaPrime = gamma_ / (beta_ * h);
  double previous = 0.0;
  for (int correction = 0; correction < 3; ++correction) {
    const double size = g.q.cwiseAbs().maxCoeff();
    if (!(size > 0.0)) return;
    // Moved by 1e-7 L along G: well above the residual's rounding, well
    // inside its linear range.
    const double e = 1e-7 * options_.errorScale / size;
    moved_.q = trial.q;
    movedIncrement_ = e * g.q;
    system.retract(moved_.q, movedIncrement_);
    moved_.v = trial.v + e * g.v;
    moved_.vdot = trial.vdot + e * g.vdot;
    moved_.lambda = trial.lambda + e * g.lambda;
    system.residual(trial.t, moved_.q, moved_.v, moved_.vdot, moved_.lambda, r_, phi_);
    rhs_.setZero(assembledIterationMatrix().rows());
    rhs_.head(n) = (base_ - r_) / (e * betaPrime);
    rhs_.segment(n, m) = (phiBase_ - phi_) / e;
    solveTurned(system, solver_, refresh_.memory.origin.q, trial.q, rhs_, delta_);
    if (!delta_.allFinite()) return;
    g.q += delta_.head(n);
    g.v += gammaPrime * delta_.head(n);
    g.vdot += betaPrime * delta_.head(n);
    g.a += (1.0 - alphaF_) / (1.0 - alphaM_) * betaPrime * delta_.head(n);
    g.lambda += betaPrime * delta_.segment(n, m);
    // Converged when the error left, rate / (1 - rate) times the
    // correction as for the substep's own Newton (ErrorLeftTest), is below
    // 1e-3 of G; at the first correction, with no rate yet, the correction.
    const double corrected = delta_.head(n).cwiseAbs().maxCoeff();
    const double rate = correction > 0 ? corrected / previous : 0.0;
    const double left = correction == 0 ? corrected : rate < 1.0 ? rate / (1.0 - rate) * corrected : HUGE_VAL;
    if (left <= 1e-3 * size) return;
    previous = corrected;
  }
}

bool GeneralizedAlpha::factorizeCutoff(Dynamics& system, const IntegratorState& at) {
  const MatrixFactors k = matrixFactors(options_.hMax);
  if (assembleIterationMatrix(system, at, k.cM, k.cC, k.cK, cutoffMatrix_))
    cutoff_.analyzePattern(cutoffMatrix_.matrix(), pivotOrder(system, k.cM));
  cutoffOrigin_.t = at.t;
  cutoffOrigin_.q = at.q;
  if (cutoff_.factorize(cutoffMatrix_.matrix()) == LinearSolver::Status::Ok) return true;
  cutoffOrigin_.t = std::numeric_limits<double>::quiet_NaN();  // made again at the next substep
  return false;
}

// Predictor of vdot and lambda at the substep's end. Rigid systems: linear
// extrapolation from the last two substeps' starts, vdot_n + h/h_{n-1}
// (vdot_n - vdot_{n-1}), which leaves an O(h^2) first correction of vdot
// where vdot_{n+1} = vdot_n leaves O(h) (Newton then starts closer, and
// the matrix kept across substeps contracts the rest in fewer
// corrections). Where stiff forces read the coordinates the accelerations
// ring at frequencies the step does not resolve, and the extrapolation
// would amplify the ringing: vdot_n, with the world-frame accelerations of
// spinning bodies' points turned as far as the bodies turn in h (the
// centripetal acceleration turns with the body: F4's first Newton
// correction 1.4e-4 -> 7e-6 m at n = 2, h = 8e-3).
void GeneralizedAlpha::predict(Dynamics& system, const IntegratorState& s, double h, IntegratorState& trial) {
  const bool history = s.hBefore > 0.0 && s.vdotBefore.size() == s.vdot.size() &&
                       s.lambdaBefore.size() == s.lambda.size();
  if (history && !system.elasticCoordinates()) {
    const double ratio = h / s.hBefore;
    trial.vdot = s.vdot + ratio * (s.vdot - s.vdotBefore);
    trial.lambda = s.lambda + ratio * (s.lambda - s.lambdaBefore);
  } else {
    trial.vdot = s.vdot;
    trial.lambda = s.lambda;
    system.turnOverStep(s.q, s.v, h, trial.vdot);
  }
  trial.a = ((1.0 - alphaF_) * trial.vdot + alphaF_ * s.vdot - alphaM_ * s.a) / (1.0 - alphaM_);
  trial.v = s.v + h * (1.0 - gamma_) * s.a + h * gamma_ * trial.a;
  hDeltaQ_ = h * s.v + h * h * (0.5 - beta_) * s.a + h * h * beta_ * trial.a;
  system.retract(trial.q, hDeltaQ_);
}

bool GeneralizedAlpha::substep(Dynamics& system, IntegratorState& s, double h, std::string& why) {
  // The trial starts from s in what predict() does not set; the history
  // is replaced when the substep is accepted.
  IntegratorState& trial = trial_;
  trial.t = s.t + h;
  trial.q = s.q;
  trial.pathRate = s.pathRate;
  trial.h = s.h;
  trial.newtonIterations = s.newtonIterations;
  trial.factorizations = s.factorizations;
  predict(system, s, h, trial);

  SubstepNewton problem(*this, system, s, trial, h);
  // The tolerance holds for the error left in q (m, rad), v (per s) and
  // vdot (per s^2): see ErrorLeftTest. Under error control it may follow
  // the error tolerance: a hundredth of the local error allowed per unit
  // step, also where the discretisation error is held per step (Newton's
  // errors are not damped away: they add up as a drift).
  const double tolerance = options_.newtonFollowsError && errorControlled()
                               ? std::max(options_.tolerance, 1e-2 * allowedLocalError(h))
                               : options_.tolerance;
  const double target = tolerance * std::min({1.0, 1.0 / problem.gammaPrime(), 1.0 / problem.betaPrime()});
  const double coordinateScale = s.q.scalars.size() ? s.q.scalars.cwiseAbs().maxCoeff() : 0.0;
  const ErrorLeftTest test(tolerance, target, coordinateScale, refresh_.memory, hDeltaQ_);
  const bool converged = solveNewton(problem, test, refresh_, h, options_.maxIterations, "converge", why);
  // The counters of the tries count, accepted or not.
  s.newtonIterations = trial.newtonIterations;
  s.factorizations = trial.factorizations;
  if (!converged) return false;
  if (!redundantRowsHold(system, why)) {
    refresh_.failed();  // the matrix lacks the rows now back
    return false;
  }
  const double local = localError(s, trial, h);
  refresh_.addDiscretisationError(local);
  if (errorControlled()) {
    errorRatio_ = errorRatio(system, trial, h, local);
    if (!(errorRatio_ <= 1.0)) {
      errorRejected_ = true;
      why = "local error estimate " + numberText(errorRatio_) + " times the tolerance";
      return false;
    }
    if (splitsError()) {
      motion_.add(hDeltaQ_);
      if (somethingMoved(system.velocityCount())) propagateErrors(system, trial, h);
    }
  }
  trial.substeps = s.substeps + 1;
  // s becomes the workspace (swapped below): its vdot and lambda move into
  // the history rather than being copied.
  trial.vdotBefore.swap(s.vdot);
  trial.lambdaBefore.swap(s.lambda);
  trial.hBefore = h;
  trial.rejectedSubsteps = s.rejectedSubsteps;
  if (alphaM_ == alphaF_ && system.constraintCount() > 0)
    projectVelocities(system, s, trial, problem.gammaPrime(), problem.betaPrime());
  std::swap(s, trial);  // trial keeps s's buffers for the next substep
  return true;
}

}  // namespace mfbd
