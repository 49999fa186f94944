#include "integrator/time_stepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "math/number_text.hpp"

namespace mfbd {

// Unknowns of the Newton matrix: velocities (n), multipliers (m), then the
// system's auxiliary unknowns (a), which its triplets index from n on.
int TimeStepper::newtonSize(const Dynamics& system, double cM) {
  return system.velocityCount() + system.constraintCount() + system.auxiliaryCount(cM);
}

namespace {
// A system index (velocities, then auxiliary unknowns) in the Newton matrix,
// where the m multipliers sit between the two (n velocities).
int newtonIndex(int n, int m, int index) { return index < n ? index : index + m; }
}  // namespace

std::vector<std::pair<int, int>> TimeStepper::pivotOrder(const Dynamics& system, double cM) {
  const int n = system.velocityCount(), m = system.constraintCount();
  std::vector<std::pair<int, int>> order = system.pivotOrder(cM);
  for (auto& [row, column] : order) row = newtonIndex(n, m, row), column = newtonIndex(n, m, column);
  return order;
}

void TimeStepper::iterationTriplets(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK,
                                    Triplets& all, Triplets& jacobian) {
  const int n = system.velocityCount(), m = system.constraintCount();
  all.clear();
  jacobian.clear();
  system.tangent(at.t, at.q, at.v, at.vdot, at.lambda, cM, cC, cK, all, jacobian);
  auto place = [n, m](int index) { return newtonIndex(n, m, index); };
  if (m > 0)
    for (auto& t : all) t = Eigen::Triplet<double>(place(t.row()), place(t.col()), t.value());
  all.reserve(all.size() + 2 * jacobian.size() + n + m);
  for (const auto& t : jacobian) {
    all.emplace_back(n + t.row(), place(t.col()), t.value());
    all.emplace_back(place(t.col()), n + t.row(), t.value());
  }
  // Every diagonal entry structurally present: the pattern stays the same.
  for (int i = 0; i < n; ++i) all.emplace_back(i, i, 0.0);
  // The constraint block gets -eps I, eps a 1e-8 fraction of the Schur
  // complement's scale |Phi_q|^2 / |S|: redundant constraints (Bricard) and
  // configurations where the constraint rank drops (a four-bar passing its
  // singular position) keep a solvable matrix; Newton still converges to
  // the exact constraints since the residual is exact.
  if (m > 0) {
    double sMax = 0.0, gMax = 0.0;
    for (const auto& t : all)
      if (t.row() == t.col() && (t.row() < n || t.row() >= n + m)) sMax = std::max(sMax, std::abs(t.value()));
    for (const auto& t : jacobian) gMax = std::max(gMax, std::abs(t.value()));
    const double eps = sMax > 0.0 ? 1e-8 * gMax * gMax / sMax : 1e-8;
    for (int i = n; i < n + m; ++i) all.emplace_back(i, i, -eps);
  }
}

// Rows left out as redundant are, to first order, a combination of the
// others, so they hold where the others do, within a hundred times the
// others' tolerance. Violated beyond that, the mechanism has left the
// configuration that made them redundant (it started at a singular one:
// the N-four-bar with its cranks on the x axis); they go back into the
// solve, regularised as any row whose rank drops.
bool TimeStepper::redundantRowsHold(Dynamics& system, std::string& why) const {
  const double floor = 64.0 * std::numeric_limits<double>::epsilon() * system.constraintLengthScale();
  const double violation = system.redundantViolation();
  if (!(violation > 100.0 * std::max(options_.tolerance, floor)) || !system.readmitRedundantRows()) return true;
  why = "constraint rows left out as redundant are violated by " + numberText(violation) + ": back in the solve";
  return false;
}

SparseMatrix TimeStepper::iterationMatrix(Dynamics& system, const IntegratorState& at, double cM, double cC,
                                          double cK) {
  const int size = newtonSize(system, cM);
  Triplets all, jacobian;
  iterationTriplets(system, at, cM, cC, cK, all, jacobian);
  SparseMatrix S(size, size);
  S.setFromTriplets(all.begin(), all.end());
  S.makeCompressed();
  return S;
}

SparseMatrix TimeStepper::unregularized(const Dynamics& system, SparseMatrix S) {
  const int n = system.velocityCount(), m = system.constraintCount();
  for (int i = n; i < n + m; ++i) S.coeffRef(i, i) = 0.0;
  return S;
}

bool TimeStepper::assembleIterationMatrix(Dynamics& system, const IntegratorState& at, double cM, double cC,
                                          double cK, SparseAssembly& into) {
  iterationTriplets(system, at, cM, cC, cK, iterationTriplets_, jacobianTriplets_);
  return into.assign(newtonSize(system, cM), iterationTriplets_);
}

Eigen::MatrixXd TimeStepper::denseJacobian(const Dynamics& system, const Triplets& jacobian) {
  const int n = system.velocityCount();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(system.constraintCount(), n);
  for (const auto& t : jacobian)
    if (t.col() < n) J(t.row(), t.col()) += t.value();
  return J;
}

void TimeStepper::loadState(StateReader& ar) {
  ar(iteration_, ahead_.by, ahead_.end);
  if (!iteration_.valid()) throw StateError("the saved Newton matrix's pattern is inconsistent");
}

bool TimeStepper::solveOnce(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK,
                            const VectorXd& rhs, int refinements, VectorXd& x) {
  LinearSolver solver;
  const SparseMatrix A = iterationMatrix(system, at, cM, cC, cK);
  solver.analyzePattern(A, pivotOrder(system, cM));
  if (solver.factorize(A) != LinearSolver::Status::Ok) return false;
  x = solver.solve(rhs);
  if (refinements > 0) {
    const SparseMatrix exact = unregularized(system, A);
    for (int sweep = 0; sweep < refinements; ++sweep) x += solver.solve(rhs - exact * x);
  }
  return true;
}

// [M Phi_q^T; Phi_q 0] [vdot; lambda] = [-r(vdot = 0, lambda = 0); -gamma].
bool TimeStepper::consistentAccelerations(Dynamics& system, IntegratorState& state, std::string& message) {
  const int n = system.velocityCount(), m = system.constraintCount();
  state.vdot = VectorXd::Zero(n);
  state.lambda = VectorXd::Zero(m);
  VectorXd r, phi;
  system.residual(state.t, state.q, state.v, state.vdot, state.lambda, r, phi);
  VectorXd rhs = VectorXd::Zero(newtonSize(system, 1.0));
  rhs.head(n) = -r;
  if (m > 0) rhs.segment(n, m) = -system.constraintAccelerationTerm(state.t, state.q, state.v);
  // Iterative refinement against the unregularised matrix removes the
  // regularisation's error from the multipliers (they are reaction outputs).
  VectorXd x;
  if (!solveOnce(system, state, 1.0, 0.0, 0.0, rhs, m > 0 ? 3 : 0, x)) {
    message = "the mass matrix is singular at the initial configuration";
    return false;
  }
  state.vdot = x.head(n);
  state.lambda = x.segment(n, m);
  if (!state.vdot.allFinite() || !state.lambda.allFinite()) {
    message = "initial accelerations are not finite";
    return false;
  }
  return true;
}

bool TimeStepper::jumpVelocities(Dynamics& system, IntegratorState& state, const VectorXd& violation) {
  const int n = system.velocityCount(), m = system.constraintCount();
  VectorXd rhs = VectorXd::Zero(newtonSize(system, 1.0));
  rhs.segment(n, m) = -violation;
  // Refinement against the unregularised matrix meets the constraints exactly.
  VectorXd x;
  if (!solveOnce(system, state, 1.0, 0.0, 0.0, rhs, 3, x) || !x.allFinite()) return false;
  state.v += x.head(n);
  return true;
}

// Step-size control (Hairer, Norsett & Wanner I.II.4): h_new = h (0.9 /
// ratio)^(1/k) for a ratio of estimate to allowed error that goes as h^k
// (stepControl(): error per unit step, k = p for a method of order p, 2 for
// generalized-alpha), within a factor 0.2 .. 5 per substep.
// An accepted substep keeps its size while the proposal lies within 1 ..
// keepBand times it: generalized-alpha keeps its Newton matrix only for the
// same h, and a refactorization per substep for a few per cent of step
// size would cost more than it saves.
double TimeStepper::stepFactor(double ratio, double low, double high) const {
  if (!(ratio > 0.0)) return high;
  const double k = stepControl().exponent;
  const double root = k == 2.0   ? std::sqrt(1.0 / ratio)
                      : k == 3.0 ? std::cbrt(1.0 / ratio)
                                 : std::pow(1.0 / ratio, 1.0 / k);
  return std::clamp(0.9 * root, low, high);
}

double TimeStepper::nextStep(double h, double step, double ratio) const {
  const double proposal = step * stepFactor(ratio, 0.2, 5.0);
  if (proposal < h) return proposal;
  if (proposal <= stepControl().keepBand * h) return h;
  return std::min(proposal, options_.hMax);
}

AdvanceResult TimeStepper::advance(Dynamics& system, IntegratorState& s, double duration, bool inputsHeld) {
  AdvanceResult result;
  const bool past = inputsHeld && continuousExtension();
  if (!past) ahead_.by = 0.0;
  if (keepsSubstepAhead() && duration <= ahead_.by) {
    if (answerAhead(system, s, s.t + duration, ahead_.by - duration, result)) ahead_.by -= duration;
    return result;
  }
  beginAdvance(system);
  // Time within the step is kept as the time elapsed since its start: a
  // small number, exact however large s.t is (at t = 1e10 a difference of
  // absolute times has a resolution of 2e-6 s).
  const double start = s.t;
  double elapsed = keepsSubstepAhead() ? resumeAhead(s) : 0.0;
  double h = std::min(s.h > 0.0 ? s.h : options_.hMax, options_.hMax);
  double tried = 0.0;  // substeps tried, rejected ones included
  int successes = 0;
  std::string rejected;  // why the last substep failed, until one succeeds
  // Every path returns `result` itself (returned in place, no copy).
  auto fail = [&](const std::string& message) {
    result.ok = false;
    result.reachedTime = s.t;
    result.message = message;
  };
  while (elapsed < duration) {
    // The rest in equal substeps of at most h (within round-off): no short
    // last one, and every substep of a run at constant h the same size, so
    // the Newton matrix of one serves the next (GeneralizedAlpha keeps it
    // only for the same h). The last one takes exactly what is left. Free
    // to pass the end, substeps of h: the communication points do not
    // shape them at all.
    const double remaining = duration - elapsed;
    const double count = std::max(1.0, std::ceil(remaining / h * (1.0 - 1e-9)));
    if (!(tried + count <= options_.maxSubsteps)) {
      fail(tooManySubsteps(rejected, duration, tried + count, h));
      return result;
    }
    const bool last = count == 1.0;
    const bool beyond = past && last && h > remaining * (1.0 + 1e-9);
    const double step = beyond || (past && !last) ? h : last ? remaining : remaining / count;
    if (beyond) substepStart_ = s;
    ++tried;
    std::string why;
    errorRatio_ = 0.0;
    errorRejected_ = false;
    if (substep(system, s, step, why)) {
      rejected.clear();
      restoreOrthogonality(s.q);
      if (errorControlled()) {
        h = nextStep(h, step, errorRatio_);
      } else if (++successes >= 2 && h < options_.hMax) {
        h = std::min(2.0 * h, options_.hMax);
        successes = 0;
      }
      if (beyond) {
        // Keep the substep, answer at the end from its extension.
        keepExtension(substepStart_, step);
        ahead_.by = elapsed + step - duration;
        ahead_.end = s;
        s.h = h;
        answerAhead(system, s, start + duration, ahead_.by, result);
        return result;
      }
      elapsed = last ? duration : elapsed + step;
      s.t = start + elapsed;
      continue;
    }
    successes = 0;
    h = afterRejection(s, step, why, result, rejected);
    if (h < options_.hMin) {
      fail(rejected);
      return result;
    }
  }
  ahead_.by = 0.0;
  s.t = start + duration;
  s.h = h;
  result.reachedTime = s.t;
  return result;
}

// Why an advance over `duration` gives up: the rest would need `needed`
// substeps of at most h, more than allowed (after `rejected`, if any).
std::string TimeStepper::tooManySubsteps(const std::string& rejected, double duration, double needed,
                                         double h) const {
  return rejected + (rejected.empty() ? "the step of " : "; the step of ") + numberText(duration) +
         " s would need " + numberText(needed) + " substeps of at most " + numberText(h) +
         " s, more than solver.max_substeps = " + numberText(options_.maxSubsteps);
}

// Goes on from the end of the substep kept past the last advance's end
// (the counters stay those of s, the latest); the time elapsed there.
double TimeStepper::resumeAhead(IntegratorState& s) const {
  const IntegratorState& e = ahead_.end;
  s.t += ahead_.by;
  s.q = e.q;
  s.v = e.v;
  s.vdot = e.vdot;
  s.lambda = e.lambda;
  s.a = e.a;
  return ahead_.by;
}

// A substep of size `step` failed for `why`: counted, described, and the
// size to try next (half, or as its error estimate says).
double TimeStepper::afterRejection(IntegratorState& s, double step, const std::string& why, AdvanceResult& result,
                                   std::string& rejected) const {
  ++s.rejectedSubsteps;
  if (errorRejected_) {
    ++result.errorRejections;
    result.lastRejection = "t = " + numberText(s.t) + ", h = " + numberText(step) + ": " + why;
  }
  rejected = "substep failed at t = " + numberText(s.t) + " with h = " + numberText(step) + " (h_min = " +
             numberText(options_.hMin) + "): " + why;
  if (!errorRejected_) return 0.5 * step;
  return step * (std::isfinite(errorRatio_) ? stepFactor(errorRatio_, 0.2, 0.9) : 0.2);
}

// s at time t from the kept substep's extension, which ends `beforeEnd`
// later. A failure forgets the kept substep: the caller restores a state
// the extension may no longer belong to.
bool TimeStepper::answerAhead(Dynamics& system, IntegratorState& s, double t, double beforeEnd, AdvanceResult& result) {
  std::string why;
  s.t = t;
  if (interpolate(system, s, beforeEnd, why)) {
    restoreOrthogonality(s.q);
    result.reachedTime = t;
    return true;
  }
  ahead_.by = 0.0;
  result.ok = false;
  result.reachedTime = t;
  result.message = "the continuous extension of the last substep failed at t = " + numberText(t) + ": " + why;
  return false;
}

bool TimeStepper::fits(const IntegratorState& like) const {
  if (ahead_.by == 0.0) return true;
  const IntegratorState& e = ahead_.end;
  return ahead_.by > 0.0 && std::isfinite(ahead_.by) && e.q.scalars.size() == like.q.scalars.size() &&
         e.q.rotations.size() == like.q.rotations.size() && e.v.size() == like.v.size() &&
         e.vdot.size() == like.v.size() && e.a.size() == like.v.size() && e.lambda.size() == like.lambda.size();
}

}  // namespace mfbd
