#include "integrator/generalized_alpha.hpp"

#include <cmath>
#include <limits>
#include <sstream>

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

// Consistent start: [M Phi_q^T; Phi_q 0] [vdot; lambda] = [-r(vdot = 0, lambda = 0); -gamma].
bool GeneralizedAlpha::initialize(Dynamics& system, IntegratorState& state, std::string& message) {
  const int n = system.velocityCount(), m = system.constraintCount();
  state.vdot = VectorXd::Zero(n);
  state.lambda = VectorXd::Zero(m);
  VectorXd r, phi;
  system.residual(state.t, state.q, state.v, state.vdot, state.lambda, r, phi);
  LinearSolver mass;
  const SparseMatrix S = iterationMatrix(system, state, 1.0, 0.0, 0.0);
  VectorXd rhs = VectorXd::Zero(S.rows());
  rhs.head(n) = -r;
  if (m > 0) rhs.segment(n, m) = -system.constraintAccelerationTerm(state.t, state.q, state.v);
  mass.analyzePattern(S, pivotOrder(system, 1.0));
  if (mass.factorize(S) != LinearSolver::Status::Ok) {
    message = "the mass matrix is singular at the initial configuration";
    return false;
  }
  VectorXd x = mass.solve(rhs);
  if (m > 0) {
    // Iterative refinement against the unregularised matrix removes the
    // regularisation's error from the multipliers (they are reaction outputs).
    const SparseMatrix exact = unregularized(system, S);
    for (int sweep = 0; sweep < 3; ++sweep) x += mass.solve(rhs - exact * x);
  }
  state.vdot = x.head(n);
  state.lambda = x.segment(n, m);
  state.a = state.vdot;
  if (!allFinite(state.vdot) || !allFinite(state.lambda)) {
    message = "initial accelerations are not finite";
    return false;
  }
  if (state.h <= 0.0) state.h = options_.hMax;
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
  const SparseMatrix S = newtonMatrix(system, s, s.h > 0.0 ? s.h : options_.hMax);
  LinearSolver solver;
  solver.analyzePattern(S, pivotOrder(system, 1.0));
  if (solver.factorize(S) != LinearSolver::Status::Ok) {
    message = "singular iteration matrix after the input change";
    return false;
  }
  VectorXd rhs = VectorXd::Zero(S.rows());
  rhs.head(n) = -r;
  const VectorXd jump = solver.solve(rhs);
  s.vdot += jump.head(n);
  s.a += jump.head(n);
  s.lambda += jump.segment(n, m);
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
  factoredStep_ = h;
  factoredAt_ = trial.q;
  substepsSinceFactorization_ = 0.0;
  elasticCoordinates_ = system.elasticCoordinates();
  correctionNoise_ = constraintNoise(system, system.velocityCount(), system.constraintCount(),
                                     assembledIterationMatrix().rows());
  return true;
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
// dv = gamma' dq with [S Phi_q^T; Phi_q 0] [dq; .] = [0; -violation /
// gamma'], through the factorised Newton matrix (S ~ M for the step: the
// least change in the mass metric, to O(h)).
void GeneralizedAlpha::projectVelocities(Dynamics& system, IntegratorState& trial, double gammaPrime) {
  const int n = system.velocityCount(), m = system.constraintCount();
  const VectorXd violation = system.velocityConstraints(trial.t, trial.q, trial.v);
  if (violation.size() != m) return;
  rhs_.setZero(assembledIterationMatrix().rows());
  rhs_.segment(n, m) = -violation / gammaPrime;
  system.turnWithRotations(factoredAt_, trial.q, rhs_, true);
  solver_.solve(rhs_, delta_);
  system.turnWithRotations(factoredAt_, trial.q, delta_, false);
  if (delta_.allFinite()) trial.v += gammaPrime * delta_.head(n);
}

bool GeneralizedAlpha::substep(Dynamics& system, IntegratorState& s, double h, std::string& why) {
  const int n = system.velocityCount(), m = system.constraintCount();
  const double betaPrime = (1.0 - alphaM_) / (beta_ * h * h * (1.0 - alphaF_));
  const double gammaPrime = gamma_ / (beta_ * h);
  const double aPerVdot = (1.0 - alphaF_) / (1.0 - alphaM_);

  if (freshStarts_ > 0) {
    --freshStarts_;
    factoredStep_ = 0.0;
  }
  // Predictor: vdot_{n+1} = vdot_n, with the world-frame accelerations of
  // spinning bodies' points turned as far as the bodies turn in h (the
  // centripetal acceleration turns with the body: F4's first Newton
  // correction 1.4e-4 -> 7e-6 m at n = 2, h = 8e-3). The trial state and
  // the vectors of the iteration are members: assigned, not allocated,
  // every substep.
  IntegratorState& trial = trial_;
  trial = s;
  trial.t = s.t + h;
  system.turnOverStep(s.q, s.v, h, trial.vdot);
  trial.a = ((1.0 - alphaF_) * trial.vdot + alphaF_ * s.vdot - alphaM_ * s.a) / (1.0 - alphaM_);
  trial.v = s.v + h * (1.0 - gamma_) * s.a + h * gamma_ * trial.a;
  VectorXd& hDeltaQ = hDeltaQ_;
  hDeltaQ = h * s.v + h * h * (0.5 - beta_) * s.a + h * h * beta_ * trial.a;
  system.retract(trial.q, hDeltaQ);

  VectorXd &r = r_, &phi = phi_, &rhs = rhs_, &delta = delta_;
  double previous = 0.0;
  // Corrections computed with the current factorization, if it was made in
  // this substep (-1: an earlier substep's matrix).
  int withFreshMatrix = -1;
  // The round-off floor of the corrections: a few ulps of the coordinates
  // where stiff forces read them (Dynamics::elasticCoordinates), the noise
  // the constraints' round-off makes (constraintNoise), and a few ulps of
  // the substep's own increment, to which the corrections add (a rigid
  // tree resolves far below its coordinates' ulps).
  const double epsilon = std::numeric_limits<double>::epsilon();
  const double coordinateUlps =
      256.0 * epsilon * std::max(1.0, s.q.scalars.size() ? s.q.scalars.cwiseAbs().maxCoeff() : 0.0);
  const double coordinateFloor = elasticCoordinates_ ? coordinateUlps : 0.0;
  // The tolerance holds for the error left in q (m, rad), v (per s) and
  // vdot (per s^2); see the convergence test below.
  const double target = options_.tolerance * std::min({1.0, 1.0 / gammaPrime, 1.0 / betaPrime});
  for (int k = 0; k < options_.maxIterations; ++k) {
    system.residual(trial.t, trial.q, trial.v, trial.vdot, trial.lambda, r, phi);
    if (!allFinite(r) || !allFinite(phi)) {
      why = "residual is not finite";
      return false;
    }
    // The last substep of a communication step, tEnd - t, equals h only up
    // to round-off: it keeps the matrix of h rather than refactorising.
    const bool fresh = !(std::abs(factoredStep_ - h) <= 1e-9 * h);
    if (fresh) {
      if (!factorize(system, trial, h)) {
        why = "singular iteration matrix";
        return false;
      }
      ++s.factorizations;
      withFreshMatrix = 0;
    }
    // The constraints are met to the tolerance or to their round-off.
    const double phiFloor = 64.0 * std::numeric_limits<double>::epsilon() * system.constraintLengthScale();
    rhs.setZero(assembledIterationMatrix().rows());
    rhs.head(n) = -r / betaPrime;
    rhs.segment(n, m) = -phi;
    // The matrix factorised at factoredAt_, turned with the rotations since
    // (Dynamics::turnWithRotations): a spinning beam's matrix stays good
    // for as long as its deformation and speed change little.
    system.turnWithRotations(factoredAt_, trial.q, rhs, true);
    solver_.solve(rhs, delta);
    system.turnWithRotations(factoredAt_, trial.q, delta, false);
    ++s.newtonIterations;
    if (withFreshMatrix >= 0) ++withFreshMatrix;
    // The update of q, v, vdot and a in one pass over the correction, with
    // its largest entry and a NaN check (0 d sums to 0 unless some d is not
    // finite): pendulum -2.5 %, double pendulum -4 % per substep.
    double size = 0.0, notFinite = 0.0;
    {
      const double* d = delta.data();
      double *dq = hDeltaQ.data(), *v = trial.v.data(), *vdot = trial.vdot.data(), *a = trial.a.data();
      const double aPerCorrection = aPerVdot * betaPrime;
      for (int i = 0; i < n; ++i) {
        const double di = d[i];
        dq[i] += di;
        v[i] += gammaPrime * di;
        vdot[i] += betaPrime * di;
        a[i] += aPerCorrection * di;
        size = std::max(size, std::abs(di));
        notFinite += 0.0 * di;
      }
    }
    if (notFinite != 0.0) {
      why = "Newton correction is not finite";
      return false;
    }
    trial.q = s.q;
    system.retract(trial.q, hDeltaQ);
    if (m > 0) trial.lambda += betaPrime * delta.segment(n, m);
    // Converged when the error left after this correction is small at
    // every level. With contraction rate rho it is about rho / (1 - rho)
    // times the correction (Hairer & Wanner IV.8), so never at the first.
    // A position error e left in q is an error gamma' e in v and beta' e
    // (~ e / (beta h^2)) in vdot, which acts on the next substeps as a force
    // error: the tolerance holds for q (m, rad), v (per s) and vdot (per
    // s^2), so the Newton error shrinks with h faster than the
    // discretisation error and the method keeps its order (a bound on q
    // alone left four_bar's energy error growing as h shrank: 1.5e-7 J at
    // h = 1e-4, 9e-6 J at 1e-5 over 1 s). Once two corrections in a row
    // are round-off noise (below the floor) their sizes say nothing more:
    // converged too (the error under the noise has contracted twice).
    const double rho = k > 0 ? size / previous : 1.0;
    if (k == 1 && withFreshMatrix < 0) firstRate_ = rho;
    const double floor =
        std::max({coordinateFloor, 4.0 * correctionNoise_, 16.0 * epsilon * hDeltaQ.cwiseAbs().maxCoeff()});
    // Where stiff forces read the coordinates, their round-off already
    // makes force noise of the tolerance's order: one correction below the
    // floor, or an error left below the tolerance in q, is converged there.
    const bool belowFloor = size <= floor && (elasticCoordinates_ || (k > 0 && previous <= floor));
    // Before a second correction, the rate this matrix showed in the
    // previous substep stands in for it (a loose tolerance then stops at
    // the first correction every other substep; the rate is never older
    // than one substep, as a kept matrix ages). Elastic systems keep the
    // old rule, never at the first correction.
    const double rate = k > 0 ? rho : withFreshMatrix < 0 && !elasticCoordinates_ ? lastRate_ : 1.0;
    const double remaining = rate < 1.0 ? rate / (1.0 - rate) * size : HUGE_VAL;
    const double resolved = elasticCoordinates_ ? std::max(target, options_.tolerance) : target;
    // A fresh matrix's corrections that stop contracting below a looser
    // floor (the coordinates' ulps, 16 times the constraint noise) are
    // noise too: the noise estimate is only an estimate (Bricard's
    // corrections hover at 2-4e-16 against an estimated 2e-16).
    const bool noise = k > 0 && withFreshMatrix >= 1 && rho > 0.5 &&
                       size <= std::max(coordinateUlps, 16.0 * correctionNoise_);
    const bool small = remaining <= resolved || size <= 0.01 * target || belowFloor || noise;
    if (small && (m == 0 || phi.cwiseAbs().maxCoeff() <= std::max(options_.tolerance, phiFloor))) {
      lastRate_ = k > 0 ? rho : 1.0;
      lastIterations_ = k + 1;
      substepsSinceFactorization_ += 1.0;
      trial.substeps = s.substeps + 1;
      trial.newtonIterations = s.newtonIterations;
      trial.factorizations = s.factorizations;
      trial.rejectedSubsteps = s.rejectedSubsteps;
      if (alphaM_ == alphaF_ && m > 0) projectVelocities(system, trial, gammaPrime);
      std::swap(s, trial);  // trial keeps s's buffers for the next substep
      return true;
    }
    // Modified Newton: a stale iteration matrix is refreshed when the
    // contraction slows, or when at its rate the error left would not be
    // resolved in the few iterations left (a rate of 0.2 from 1e-3 to
    // 1e-14 needs 16: a long communication step's matrix, kept over ten
    // substeps of a double pendulum, failed whole substeps that way; and
    // a rate of 0.05 that leaves 1e-16 m per substep of a double pendulum
    // at h = 1e-5 is a steady 3e-6 m/s^2 error in its accelerations:
    // four corrections at most, where the tolerance holds for vdot); a
    // fresh one that does not contract has failed. Corrections near the
    // round-off floor stay with the current matrix: there a refresh
    // (tangent and factorization, several iterations' worth) would save an
    // iteration at most, and their rate is half noise. Where stiff forces
    // read the coordinates the rate is judged only in the last few
    // iterations: earlier, a refresh for a merely slow rate costs more
    // than the iterations it saves wherever the tangent is expensive
    // (flexible four-bar: +35 % per substep).
    const int left = elasticCoordinates_ ? options_.maxIterations - 1 - k : 4;
    const bool tooSlow = left <= 4 && rho < 1.0 && std::pow(rho, left) * remaining > resolved;
    if (k > 0 && (size > 0.25 * previous || tooSlow) && size > (elasticCoordinates_ ? 10.0 : 1.0) * floor) {
      // Diverging: two corrections of this substep's own matrix, growing
      // (a correction right after a refresh is not compared with the stale
      // matrix's last one).
      if (withFreshMatrix >= 2 && size > previous) {
        std::ostringstream msg;
        msg << "Newton diverging (correction " << size << " after " << previous << ")";
        why = msg.str();
        factoredStep_ = 0.0;
        return false;
      }
      factoredStep_ = 0.0;  // refactorise at the next iteration
      // A matrix from an earlier substep that did not contract at all
      // (rate near 1 at the first check): the next few substeps start
      // with a fresh one rather than spend two corrections finding out
      // again (see freshStarts_).
      if (withFreshMatrix < 0 && k == 1 && size > 0.5 * previous) freshStarts_ = kFreshStarts;
    }
    previous = size;
  }
  std::ostringstream msg;
  msg << "Newton did not converge in " << options_.maxIterations << " iterations";
  why = msg.str();
  factoredStep_ = 0.0;
  return false;
}

}  // namespace mfbd
