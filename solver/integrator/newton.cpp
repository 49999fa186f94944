#include "integrator/newton.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mfbd {

namespace {
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
}

Assessment CorrectionSizeTest::assess(const NewtonIterate& it, const NewtonMemory&) const {
  Assessment a;
  a.rho = it.k > 0 ? it.size / it.previous : 1.0;
  a.remaining = it.size;
  a.resolved = tolerance_;
  a.converged = it.size <= tolerance_ && it.violation <= tolerance_;
  return a;
}

// The round-off floor of the corrections: a few ulps of the coordinates
// where stiff forces read them (Dynamics::elasticCoordinates), the noise the
// constraints' round-off makes (constraintNoise), and a few ulps of the
// substep's own increment, to which the corrections add (a rigid tree
// resolves far below its coordinates' ulps).
ErrorLeftTest::ErrorLeftTest(double tolerance, double target, double coordinateScale, const NewtonMemory& memory,
                             const VectorXd& increment)
    : tolerance_(tolerance), target_(target), increment_(increment) {
  coordinateUlps_ = 256.0 * kEpsilon * std::max(1.0, coordinateScale);
  coordinateFloor_ = memory.elasticCoordinates ? coordinateUlps_ : 0.0;
}

// Converged when the error left after this correction is small at every
// level. With contraction rate rho it is about rho / (1 - rho) times the
// correction (Hairer & Wanner IV.8), so never at the first. A position
// error e left in q is an error gamma' e in v and beta' e (~ e / (beta h^2))
// in vdot, which acts on the next substeps as a force error: the target
// holds for q (m, rad), v (per s) and vdot (per s^2), so the Newton error
// shrinks with h faster than the discretisation error and the method keeps
// its order (a bound on q alone left four_bar's energy error growing as h
// shrank). Once two corrections in a row are round-off noise (below the
// floor) their sizes say nothing more: converged too (the error under the
// noise has contracted twice). The constraints are met to the tolerance or
// to their round-off.
Assessment ErrorLeftTest::assess(const NewtonIterate& it, const NewtonMemory& memory) const {
  const bool elastic = memory.elasticCoordinates;
  Assessment a;
  a.rho = it.k > 0 ? it.size / it.previous : 1.0;
  a.floor = std::max({coordinateFloor_, 4.0 * memory.correctionNoise,
                      16.0 * kEpsilon * increment_.cwiseAbs().maxCoeff()});
  // Where stiff forces read the coordinates, their round-off already makes
  // force noise of the tolerance's order: one correction below the floor,
  // or an error left below the tolerance in q, is converged there.
  const bool belowFloor = it.size <= a.floor && (elastic || (it.k > 0 && it.previous <= a.floor));
  // Before a second correction, the rate this matrix showed in the previous
  // substep stands in for it (a loose tolerance then stops at the first
  // correction every other substep; the rate is never older than one
  // substep, as a kept matrix ages). Elastic systems never stop at the first.
  const double rate = it.k > 0 ? a.rho : it.withFreshMatrix < 0 && !elastic ? memory.lastRate : 1.0;
  a.remaining = rate < 1.0 ? rate / (1.0 - rate) * it.size : HUGE_VAL;
  a.resolved = elastic ? std::max(target_, tolerance_) : target_;
  // A fresh matrix's corrections that stop contracting below a looser floor
  // (the coordinates' ulps, 16 times the constraint noise) are noise too:
  // the noise estimate is only an estimate (Bricard's corrections hover at
  // 2-4e-16 against an estimated 2e-16).
  const bool noise = it.k > 0 && it.withFreshMatrix >= 1 && a.rho > 0.5 &&
                     it.size <= std::max(coordinateUlps_, 16.0 * memory.correctionNoise);
  const bool small = a.remaining <= a.resolved || it.size <= 0.01 * target_ || belowFloor || noise;
  a.converged = small && it.violation <= std::max(tolerance_, it.violationFloor);
  return a;
}

// At a communication point (where inputs may have jumped) a fresh iteration
// matrix where the kept one's error counts, and else when it pays. A kept
// matrix leaves an error of the same sign substep after substep (its
// contraction rate times the last correction), which adds up as a drift;
// where that error, summed over the communication step, exceeds a
// hundredth of the substeps' local discretisation error (the fraction
// Newton's tolerance keeps under error control), a fresh matrix, which
// contracts fastest, replaces it whatever the cost: four_bar at h = 1e-5,
// whose local errors of 1e-15 m lie below the corrections' round-off
// floor, kept its matrix over thousands of substeps and drifted in energy
// seven times its discretisation error. Otherwise the matrix is refreshed
// when it pays: the last substep took k corrections where a fresh
// matrix takes two; the k - 2 extra ones (a residual and a solve each)
// recur over the next substeps until the matrix is refreshed anyway, counted
// as kRefreshHorizon of them, against a tangent of tangentCost residuals. A
// double pendulum (cost 3) then refreshes whenever k > 2, a beam mesh (16)
// when k > 6, an 81-joint tree with 40 loops (82) hardly ever. Where the
// kept matrix itself has gone stale (its contraction at the first check
// above kStaleRate: a beam whose spin speeds up, with its centrifugal
// stiffening), a fresh one will serve about as long as this one did, so the
// horizon is half the substeps it served; corrections that come from the
// predictor's nonlinearity (a ringing cantilever: contraction 1e-4) do not
// go away with a fresh matrix and keep the short horizon. The rule depends
// on the run alone, so a run replays bit for bit.
void MatrixRefreshPolicy::beginAdvance(double tangentCost) {
  if (kind_ == Kind::Full) return;
  const bool biased = memory.newtonErrorLeft > kNewtonErrorFraction * memory.discretisationError;
  memory.newtonErrorLeft = memory.discretisationError = 0.0;
  if (biased) {
    memory.factoredStep = 0.0;
    return;
  }
  const double horizon = memory.firstRate > kStaleRate
                             ? std::max(kRefreshHorizon, 0.5 * memory.substepsSinceFactorization)
                             : kRefreshHorizon;
  if (horizon * (memory.lastIterations - 2) > tangentCost) memory.factoredStep = 0.0;
}

// Substeps still to start with a fresh matrix after an earlier substep's
// matrix failed to contract: a system whose Newton matrix changes too fast
// for modified Newton (the flexible four-bar with its defect: 0.3 % entry
// changes per substep, a 50 times larger first correction) then pays a
// tangent per substep but no wasted corrections; every kFreshStarts + 1
// substeps the kept matrix is tried again.
void MatrixRefreshPolicy::beginSolve() {
  if (kind_ == Kind::Full || memory.freshStarts <= 0) return;
  --memory.freshStarts;
  memory.factoredStep = 0.0;
}

// The last substep of a communication step equals h only up to round-off:
// it keeps the matrix of h rather than refactorising.
bool MatrixRefreshPolicy::needsFactorization(double h) const {
  return kind_ == Kind::Full || !(std::abs(memory.factoredStep - h) <= 1e-9 * h);
}

void MatrixRefreshPolicy::factorized(double h) {
  memory.factoredStep = h;
  memory.substepsSinceFactorization = 0.0;
}

// A second correction at the round-off floor is noise: its ratio to the
// first says nothing about the matrix (a good predictor leaves a first
// correction near the floor itself, R3's 1.3e-12 m against 5.9e-13 m, and
// the noise over it read as a stale matrix refreshed R3 at every
// communication point). An error under the floor is judged by its effect
// on accuracy instead (beginAdvance).
void MatrixRefreshPolicy::observe(const NewtonIterate& it, const Assessment& a) {
  if (it.k == 1 && it.withFreshMatrix < 0) memory.firstRate = it.size > a.floor ? a.rho : 0.0;
}

void MatrixRefreshPolicy::accepted(const NewtonIterate& it, const Assessment& a) {
  memory.lastRate = it.k > 0 ? a.rho : 1.0;
  memory.lastIterations = it.k + 1;
  // Where the rate is noise (no contraction) the error left is of the last
  // correction's size.
  memory.newtonErrorLeft += std::isfinite(a.remaining) ? a.remaining : it.size;
  memory.substepsSinceFactorization += 1.0;
}

// Modified Newton: a stale matrix is refreshed when the contraction slows,
// or when at its rate the error left would not be resolved in the few
// iterations left (a rate of 0.2 from 1e-3 to 1e-14 needs 16: a long
// communication step's matrix, kept over ten substeps of a double pendulum,
// failed whole substeps that way; a rate of 0.05 that leaves 1e-16 m per
// substep at h = 1e-5 is a steady acceleration error: four corrections at
// most, where the tolerance holds for vdot); a fresh one that does not
// contract has failed. Corrections near the round-off floor stay with the
// current matrix: there a refresh would save an iteration at most, and their
// rate is half noise. Where stiff forces read the coordinates the rate is
// judged only in the last few iterations: earlier, a refresh for a merely
// slow rate costs more than the iterations it saves wherever the tangent is
// expensive (flexible four-bar).
bool MatrixRefreshPolicy::diverging(const NewtonIterate& it, const Assessment& a, int maxIterations) {
  if (kind_ == Kind::Full) return false;
  const bool elastic = memory.elasticCoordinates;
  const int left = elastic ? maxIterations - 1 - it.k : 4;
  // The iteration ends at the target or at two corrections below the
  // round-off floor, whichever is larger: a rate that reaches that within
  // the corrections left is fast enough (a target below the floor, as the
  // vdot-level target of a rigid system at h = 1e-3, refreshed the matrix
  // about every 1.5 substeps of a double pendulum).
  const bool tooSlow =
      left <= 4 && a.rho < 1.0 && std::pow(a.rho, left) * a.remaining > std::max(a.resolved, a.floor);
  if (!(it.k > 0 && (it.size > 0.25 * it.previous || tooSlow) && it.size > (elastic ? 10.0 : 1.0) * a.floor))
    return false;
  memory.factoredStep = 0.0;  // refactorise at the next iteration
  // Two corrections of this solve's own matrix, growing (a correction right
  // after a refresh is not compared with the stale matrix's last one).
  if (it.withFreshMatrix >= 2 && it.size > it.previous) return true;
  // A matrix from an earlier substep that did not contract at all (rate
  // near 1 at the first check): the next few substeps start with a fresh
  // one rather than spend two corrections finding out again.
  if (it.withFreshMatrix < 0 && it.k == 1 && it.size > 0.5 * it.previous) memory.freshStarts = kFreshStarts;
  return false;
}

bool solveNewton(NewtonSystem& problem, const ConvergenceTest& test, MatrixRefreshPolicy& policy, double h,
                 int maxIterations, const char* goal, std::string& why) {
  policy.beginSolve();
  NewtonIterate it;
  for (it.k = 0; it.k < maxIterations; ++it.k) {
    if (!problem.evaluate(it, why)) return false;
    if (policy.needsFactorization(h)) {
      if (!problem.factorize(h, why)) return false;
      policy.factorized(h);
      it.withFreshMatrix = 0;
    }
    it.size = problem.correct();
    if (it.withFreshMatrix >= 0) ++it.withFreshMatrix;
    if (!std::isfinite(it.size)) {
      why = "Newton correction is not finite";
      return false;
    }
    const Assessment a = test.assess(it, policy.memory);
    policy.observe(it, a);
    if (a.converged) {
      policy.accepted(it, a);
      return true;
    }
    if (policy.diverging(it, a, maxIterations)) {
      std::ostringstream msg;
      msg << "Newton diverging (correction " << it.size << " after " << it.previous << ")";
      why = msg.str();
      return false;
    }
    it.previous = it.size;
  }
  std::ostringstream msg;
  msg << "Newton did not " << goal << " in " << maxIterations << " iterations";
  why = msg.str();
  policy.failed();
  return false;
}

}  // namespace mfbd
