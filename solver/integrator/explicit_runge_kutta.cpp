#include "integrator/explicit_runge_kutta.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/QR>

#include "math/number_text.hpp"

namespace mfbd {

const DormandPrinceTableau kDormandPrince = {
    {0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0},
    {{},
     {1.0 / 5.0},
     {3.0 / 40.0, 9.0 / 40.0},
     {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
     {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
     {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0},
     {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0}},
    {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0},
    {71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0},
    {-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0, -10690763975.0 / 1880347072.0,
     701980252875.0 / 199316789632.0, -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0},
};

bool DormandPrince::initialize(Dynamics& system, IntegratorState& state, std::string& message) {
  if (!consistentAccelerations(system, state, message)) return false;
  state.a = state.vdot;
  state.hBefore = 0.0;
  if (state.h <= 0.0) state.h = options_.hMax;
  return true;
}

bool DormandPrince::restartAfterInputJump(Dynamics& system, IntegratorState& state, std::string& message) {
  if (!consistentAccelerations(system, state, message)) return false;
  state.a = state.vdot;
  return true;
}

// The index-1 equations through the kept pattern and this stepper's solver:
// one numeric factorization per stage. The constraint block carries the
// regularisation of TimeStepper::iterationTriplets (-eps on its diagonal);
// two sweeps of refinement against the exact matrix remove its O(eps)
// error from vdot and lambda.
bool DormandPrince::accelerations(Dynamics& system, std::string& why) {
  const int n = system.velocityCount(), m = system.constraintCount();
  IntegratorState& at = stage_;
  if (system.unconstrainedAccelerations(at.t, at.q, at.v, x_)) {
    ++factorizations_;
    if (x_.allFinite()) return true;
    why = "accelerations are not finite";
    return false;
  }
  at.vdot.setZero(n);
  at.lambda.setZero(m);
  system.residual(at.t, at.q, at.v, at.vdot, at.lambda, r_, phi_);
  if (!r_.allFinite() || !phi_.allFinite()) {
    why = "residual is not finite";
    return false;
  }
  if (assembleIterationMatrix(system, at, 1.0, 0.0, 0.0))
    solver_.analyzePattern(assembledIterationMatrix(), pivotOrder(system, 1.0));
  const SparseMatrix& A = assembledIterationMatrix();
  ++factorizations_;
  if (solver_.factorize(A) != LinearSolver::Status::Ok) {
    why = "singular mass matrix";
    return false;
  }
  rhs_.setZero(A.rows());
  rhs_.head(n) = -r_;
  if (m > 0) {
    rhs_.segment(n, m) = -system.constraintAccelerationTerm(at.t, at.q, at.v);
  }
  solver_.solve(rhs_, x_);
  if (m > 0) {
    regularization_.resize(m);
    for (int i = 0; i < m; ++i) regularization_[i] = A.coeff(n + i, n + i);
    for (int sweep = 0; sweep < 2; ++sweep) {
      product_.noalias() = A * x_;
      correction_ = rhs_ - product_;
      correction_.segment(n, m) += regularization_.cwiseProduct(x_.segment(n, m));
      solver_.solve(correction_, dx_);
      x_ += dx_;
    }
  }
  if (!x_.allFinite()) {
    why = "accelerations are not finite";
    return false;
  }
  return true;
}

// Stage i at delta_i = h sum_j a_ij kDelta_j, v_i = v + h sum_j a_ij kV_j:
// kDelta_i = dexp^-1_{delta_i}(v_i), kV_i = vdot(t + c_i h, q o exp(delta_i),
// v_i). The first stage is the state's own (vdot at the step start: first
// same as last); the seventh is the new state.
bool DormandPrince::stages(Dynamics& system, const IntegratorState& s, double h, std::string& why) {
  const DormandPrinceTableau& T = kDormandPrince;
  const int n = system.velocityCount();
  kDelta_[0] = s.v;
  kV_[0] = s.vdot;
  for (int i = 1; i < kStages; ++i) {
    delta_ = T.a[i][0] * kDelta_[0];
    stage_.v = T.a[i][0] * kV_[0];
    for (int j = 1; j < i; ++j) {
      if (T.a[i][j] == 0.0) continue;
      delta_ += T.a[i][j] * kDelta_[j];
      stage_.v += T.a[i][j] * kV_[j];
    }
    delta_ *= h;
    stage_.v = s.v + h * stage_.v;
    stage_.t = s.t + T.c[i] * h;
    stage_.q = s.q;
    system.retract(stage_.q, delta_);
    system.chartRate(delta_, stage_.v, kDelta_[i]);
    if (!accelerations(system, why)) return false;
    kV_[i] = x_.head(n);
  }
  return true;
}

// The largest of |e_q| over the chart coordinates (m, rad) and |e_v| (1 s)
// over the velocities, e = h sum_i (b_i - bhat_i) k_i the difference of the
// order-5 and order-4 solutions, against tol L (1 s / horizon): error per
// step. The method goes on with the order-5 solution (local extrapolation),
// whose local error is O(h^6) where the estimate is O(h^5): a global error
// of T / h such errors is then proportional to the per-step target (Hairer,
// Norsett & Wanner I, II.4), as error per unit step, which would give
// tol^(5/4), is not. Dividing the target by the horizon in seconds keeps
// the sum over the experiment near tol L for motions of a 1 s time scale.
// The velocities as generalized-alpha's estimate holds the positions: a
// velocity error becomes a position error over time (1 s: the time unit the
// Newton tolerance also uses). Absolute in the velocities: a relative part
// (Hairer, Norsett & Wanner I, II.4) would let a fast light body's energy
// drift (the chain of 1e6 / 1e-6 kg masses lost 0.2 % of it in 0.01 s at
// tolerance 1e-6).
double DormandPrince::errorRatio(double h) const {
  const DormandPrinceTableau& T = kDormandPrince;
  double largest = 0.0;
  for (int i = 0; i < kDelta_[0].size(); ++i) {
    double eq = 0.0, ev = 0.0;
    for (int j = 0; j < kStages; ++j) {
      eq += T.e[j] * kDelta_[j][i];
      ev += T.e[j] * kV_[j][i];
    }
    const double e = std::max(std::abs(eq), std::abs(ev));
    if (!std::isfinite(e)) return std::numeric_limits<double>::infinity();
    largest = std::max(largest, e);
  }
  return h * largest / allowedLocalError(1.0);
}

// Least change in the mass metric: [M Phi_q^T; Phi_q 0] [dq; mu] = [0; -Phi]
// (Newton on the positions, q <- q o exp(dq)), then [dv; mu] = [0;
// -(Phi_q v + Phi_t)], through the factorization at the new state, down to
// the round-off of the rows. Not merely below the tolerance: near a
// singular configuration of a loop (R3's cranks horizontal) the index-1
// equations amplify a velocity violation into the motion, and R3 with four
// loops left its parallelogram branch at tolerance 1e-6 (46 J of energy
// gained) with the violation held to a hundredth of the tolerance; at
// round-off it kept the energy to 5e-9 J. The substep's local error
// already exceeds such a target, so a projection is made at every
// substep either way, and going on to round-off costs a residual more.
bool DormandPrince::project(Dynamics& system, IntegratorState& z, bool& moved, std::string& why) {
  const int n = system.velocityCount(), m = system.constraintCount();
  moved = false;
  if (m == 0) return true;
  const double floor = 64.0 * std::numeric_limits<double>::epsilon() * system.constraintLengthScale();
  for (int k = 0; k < 4 && phi_.cwiseAbs().maxCoeff() > floor; ++k) {
    rhs_.setZero(assembledIterationMatrix().rows());
    rhs_.segment(n, m) = -phi_;
    solver_.solve(rhs_, x_);
    delta_ = x_.head(n);
    system.retract(z.q, delta_);
    moved = true;
    system.residual(z.t, z.q, z.v, z.vdot, z.lambda, r_, phi_);
  }
  const double violation = phi_.cwiseAbs().maxCoeff();
  if (!(violation <= std::max(1e-2 * options_.errorTolerance * options_.errorScale, floor))) {
    why = "the constraints are violated by " + numberText(violation) + " after 4 projections";
    return false;
  }
  if (!redundantRowsHold(system, why)) return false;
  for (int sweep = 0; sweep < 2; ++sweep) {
    const VectorXd rates = system.velocityConstraints(z.t, z.q, z.v);
    if (rates.size() != m || !(rates.cwiseAbs().maxCoeff() > floor)) break;
    rhs_.setZero(assembledIterationMatrix().rows());
    rhs_.segment(n, m) = -rates;
    solver_.solve(rhs_, x_);
    z.v += x_.head(n);
    moved = true;
  }
  return z.v.allFinite();
}

bool DormandPrince::settle(Dynamics& system, std::string& why) {
  bool moved = false;
  if (!project(system, stage_, moved, why)) return false;
  return !moved || accelerations(system, why);
}

bool DormandPrince::substep(Dynamics& system, IntegratorState& s, double h, std::string& why) {
  const int n = system.velocityCount(), m = system.constraintCount();
  factorizations_ = 0;
  const auto done = [&](bool ok) {
    s.factorizations += factorizations_;
    return ok;
  };
  if (!stages(system, s, h, why)) return done(false);
  if (errorControlled()) {
    errorRatio_ = errorRatio(h);
    if (!(errorRatio_ <= 1.0)) {
      errorRejected_ = true;
      why = "local error estimate " + numberText(errorRatio_) + " times the tolerance";
      return done(false);
    }
  }
  // After a projection the first stage of the next substep is solved anew
  // at the projected state; else it is the seventh stage of this one.
  if (!settle(system, why)) return done(false);
  s.t = stage_.t;
  std::swap(s.q, stage_.q);
  std::swap(s.v, stage_.v);
  s.vdot = x_.head(n);
  s.lambda = x_.segment(n, m);
  s.a = s.vdot;
  ++s.substeps;
  return done(true);
}

// The stages of the substep just accepted (from `start`, size h) as the
// four vectors of the extension per chart coordinate and velocity: y1 - y0
// (the order-5 solution before its projection, which the extension meets
// at theta = 1), h k1 - (y1 - y0), (y1 - y0) - h k7 - (h k1 - (y1 - y0)),
// h sum_i d_i k_i.
void DormandPrince::keepExtension(const IntegratorState& start, double h) {
  const DormandPrinceTableau& T = kDormandPrince;
  Extension& x = extension_;
  x.h = h;
  x.q0 = start.q;
  x.v0 = start.v;
  const auto parts = [&](const std::array<VectorXd, kStages>& k, std::array<VectorXd, 4>& y) {
    y[0] = T.b[0] * k[0];
    y[3] = T.d[0] * k[0];
    for (int i = 1; i < kStages; ++i) {
      if (T.b[i] != 0.0) y[0] += T.b[i] * k[i];
      if (T.d[i] != 0.0) y[3] += T.d[i] * k[i];
    }
    y[0] *= h;
    y[3] *= h;
    y[1] = h * k[0] - y[0];
    y[2] = y[0] - h * k[kStages - 1] - y[1];
  };
  parts(kDelta_, x.delta);
  parts(kV_, x.v);
}

bool DormandPrince::interpolate(Dynamics& system, IntegratorState& s, double beforeEnd, std::string& why) {
  const Extension& x = extension_;
  const int n = system.velocityCount(), m = system.constraintCount();
  const double theta = 1.0 - beforeEnd / x.h, rest = 1.0 - theta;
  const auto at = [&](const std::array<VectorXd, 4>& y, VectorXd& out) {
    out = theta * (y[0] + rest * (y[1] + theta * (y[2] + rest * y[3])));
  };
  at(x.delta, delta_);
  at(x.v, stage_.v);
  stage_.v += x.v0;
  stage_.t = s.t;
  stage_.q = x.q0;
  system.retract(stage_.q, delta_);
  factorizations_ = 0;
  const bool ok = accelerations(system, why) && settle(system, why);
  s.factorizations += factorizations_;
  if (!ok) return false;
  std::swap(s.q, stage_.q);
  std::swap(s.v, stage_.v);
  s.vdot = x_.head(n);
  s.lambda = x_.segment(n, m);
  s.a = s.vdot;
  return true;
}

bool DormandPrince::fits(const IntegratorState& like) const {
  if (!TimeStepper::fits(like)) return false;
  if (!keepsSubstepAhead()) return true;  // the extension is read only with a kept substep
  const Extension& x = extension_;
  const Eigen::Index n = like.v.size();
  const auto sized = [n](const std::array<VectorXd, 4>& y) {
    for (const VectorXd& part : y)
      if (part.size() != n) return false;
    return true;
  };
  return x.h > 0.0 && std::isfinite(x.h) && x.q0.scalars.size() == like.q.scalars.size() &&
         x.q0.rotations.size() == like.q.rotations.size() && x.v0.size() == n && sized(x.delta) && sized(x.v);
}

// Power iteration on J = d(delta', v')/d(delta, v) at delta = 0, each
// product a directional difference of the chart's right-hand side. The
// growth per iteration of a pair of complex eigenvalues alternates (their
// q and v parts differ in size), so the rate is the geometric mean of the
// growth over the last ten (an even number of) iterations.
double DormandPrince::fastestRate(Dynamics& system, const IntegratorState& at) {
  const int n = system.velocityCount();
  if (n == 0) return 0.0;
  std::string why;
  stage_.t = at.t;
  stage_.q = at.q;
  stage_.v = at.v;
  if (!accelerations(system, why)) return std::numeric_limits<double>::infinity();
  const VectorXd a0 = x_.head(n);
  VectorXd xq(n), xv(n), rate;
  unsigned pattern = 12345u;
  for (int i = 0; i < n; ++i) {
    pattern = pattern * 1103515245u + 12345u;
    xq[i] = (pattern >> 16) & 1u ? 1.0 : -1.0;
    pattern = pattern * 1103515245u + 12345u;
    xv[i] = (pattern >> 16) & 1u ? 1.0 : -1.0;
  }
  const double eps = 1e-7 * std::max({1.0, options_.errorScale, at.v.cwiseAbs().maxCoeff()});
  constexpr int kIterations = 40, kAveraged = 10;
  double logGrowth = 0.0;
  for (int k = 0; k < kIterations; ++k) {
    const double norm = std::sqrt(xq.squaredNorm() + xv.squaredNorm());
    xq /= norm;
    xv /= norm;
    delta_ = eps * xq;
    stage_.q = at.q;
    system.retract(stage_.q, delta_);
    stage_.v = at.v + eps * xv;
    system.chartRate(delta_, stage_.v, rate);
    if (!accelerations(system, why)) return std::numeric_limits<double>::infinity();
    xq = (rate - at.v) / eps;
    xv = (x_.head(n) - a0) / eps;
    const double growth = std::sqrt(xq.squaredNorm() + xv.squaredNorm());
    if (!std::isfinite(growth)) return std::numeric_limits<double>::infinity();
    if (growth == 0.0) return 0.0;
    if (k >= kIterations - kAveraged) logGrowth += std::log(growth);
  }
  return std::exp(logGrowth / kAveraged);
}

}  // namespace mfbd
