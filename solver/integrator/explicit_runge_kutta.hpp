// Explicit embedded Runge-Kutta of Dormand and Prince (1980), order 5 with an
// embedded order-4 solution for the error estimate (DOPRI5; Hairer, Norsett
// and Wanner, Solving ODEs I, II.5, Table 5.2), for scenes that are not
// stiff (the choice: solver/integrator_choice.cpp).
//
// On the configuration manifold (scalars x SO(3)^k, body-frame angular
// velocities) it integrates in the local chart at the substep's start
// (Munthe-Kaas 1998): q(t) = q0 o exp(delta(t)) with
//   delta' = dexp^-1_delta(v)   (Dynamics::chartRate),
//   v'     = vdot(t, q0 o exp(delta), v),
// an ODE on a vector space, so the classical method keeps its order 5.
// The accelerations of each stage solve the index-1 equations
//   [M Phi_q^T; Phi_q 0] [vdot; lambda] = [-r(vdot = 0, lambda = 0); -gamma]
// through the Newton-matrix pattern (cM = 1, cC = cK = 0) analysed once.
// Closed loops and drives: after each accepted substep the positions are
// projected onto Phi = 0 and the velocities onto Phi_q v + Phi_t = 0, least
// change in the mass metric, so the drift stays far below the tolerance.
// While the inputs are held it steps past a communication point and answers
// there from the continuous extension of order 4 (Hairer, Norsett & Wanner
// I, II.6: Dormand and Prince's dense output), in the same chart, projected
// like a substep's end: the substeps follow the motion, not the sampling.
#pragma once
#include <array>

#include "integrator/time_stepper.hpp"

namespace mfbd {

// The tableau (Hairer, Norsett & Wanner I, II.5, Table 5.2): nodes c,
// coefficients a[i][j] (j < i), order-5 weights b (= a[6]: the seventh
// stage is taken at the new state, first same as last) and e = b - bhat,
// bhat the embedded order-4 weights.
struct DormandPrinceTableau {
  double c[7];
  double a[7][6];
  double b[7];
  double e[7];
  // The continuous extension's fourth-degree part (Hairer, Norsett &
  // Wanner I, II.6, dense output of DOPRI5): y(t0 + theta h) = y0 +
  // theta (y1 - y0 + (1 - theta) (h k1 - (y1 - y0) + theta (2 (y1 - y0) -
  // h (k1 + k7) + (1 - theta) h sum_i d_i k_i))).
  double d[7];
};
extern const DormandPrinceTableau kDormandPrince;

class DormandPrince : public TimeStepper {
 public:
  // Always error-controlled: options.errorTolerance must be positive.
  explicit DormandPrince(const SolverOptions& options) : TimeStepper(options) {}

  // Consistent accelerations and multipliers at the state (its own
  // factorization: a probe of the outputs leaves the stepper untouched).
  bool initialize(Dynamics& system, IntegratorState& state, std::string& message) override;

  // What carries over: the kept pattern and the linear solver's record
  // (KLU's refactorizations keep the pivot order of its last full one).
  // The step size and the first stage (vdot, lambda) are in IntegratorState.
  // The extension of a substep taken past the state's time, if one is kept.
  void saveState(StateWriter& ar) override {
    TimeStepper::saveState(ar);
    solver_.saveOrLoad(ar);
    ar(extension_);
  }
  void loadState(StateReader& ar) override {
    TimeStepper::loadState(ar);
    solver_.saveOrLoad(ar);
    ar(extension_);
  }
  bool fits(const IntegratorState& like) const override;

  // The spectral radius of the Jacobian of (delta, v)' at the state (1/s):
  // the fastest mode, oscillating or damped, that an explicit substep must
  // resolve. Power iteration by directional differences; infinity if the
  // accelerations cannot be solved there.
  double fastestRate(Dynamics& system, const IntegratorState& at);

  // The radius of the half-disc |h lambda| <= r of the left half-plane
  // inside the method's stability region |R(z)| <= 1, R(z) = sum_k<=5 z^k/k!
  // + z^6/600: 0.997, set by the imaginary axis (|R(i)| = 1 + 1.4e-6); the
  // region reaches 3.3 on the negative real axis but only ~1 for undamped
  // oscillations.
  static constexpr double kStabilityRadius = 1.0;

 protected:
  // The accelerations of the new inputs: the first stage of the next substep.
  bool restartAfterInputJump(Dynamics& system, IntegratorState& state, std::string& message) override;
  bool substep(Dynamics& system, IntegratorState& s, double h, std::string& why) override;
  bool errorControlled() const override { return options_.errorTolerance > 0.0; }
  bool continuousExtension() const override { return true; }
  void keepExtension(const IntegratorState& start, double h) override;
  bool interpolate(Dynamics& system, IntegratorState& s, double beforeEnd, std::string& why) override;
  // The estimate (order-5 minus order-4 solution) goes as h^5 and is held
  // per step (see errorRatio); no Newton matrix to keep, so no band of kept
  // sizes.
  StepControl stepControl() const override { return {5.0, 1.0}; }

 private:
  static constexpr int kStages = 7;
  // vdot and lambda at stage_'s (t, q, v) through the kept pattern into x_
  // (vdot, then lambda); the residual's phi stays in phi_. Sets stage_'s
  // vdot and lambda to zero (the residual's arguments).
  bool accelerations(Dynamics& system, std::string& why);
  // The stages from s into stage_ (the new state) and the error estimate.
  bool stages(Dynamics& system, const IntegratorState& s, double h, std::string& why);
  double errorRatio(double h) const;
  // Positions onto Phi = 0, velocities onto Phi_q v + Phi_t = 0, through the
  // last factorization (at z = stage_, whose Phi is in phi_, vdot and
  // lambda zero); `moved` if either changed.
  bool project(Dynamics& system, IntegratorState& z, bool& moved, std::string& why);
  // stage_ (its accelerations just solved) projected, and its accelerations
  // solved again if that moved it: a substep's end, or an answer from the
  // extension.
  bool settle(Dynamics& system, std::string& why);

  // The continuous extension of the kept substep (read while the base
  // class keeps that substep's end), in the chart at its start q0: the
  // tableau's polynomial for delta (y0 = 0) and for v (y0 = v0), each as its
  // four vectors y1 - y0, h k1 - (y1 - y0), 2 (y1 - y0) - h (k1 + k7),
  // h sum_i d_i k_i.
  struct Extension {
    double h = 0.0;
    Configuration q0;
    VectorXd v0;
    std::array<VectorXd, 4> delta, v;
    template <class Archive>
    void visitState(Archive& ar) {
      ar(h, q0, v0, delta[0], delta[1], delta[2], delta[3], v[0], v[1], v[2], v[3]);
    }
  } extension_;

  LinearSolver solver_;
  IntegratorState stage_;  // the stage under way (t, q, v)
  std::array<VectorXd, kStages> kDelta_, kV_;
  VectorXd delta_, r_, phi_, rhs_, x_, dx_, correction_, product_, regularization_;
  long factorizations_ = 0;  // of the substep under way
};

}  // namespace mfbd
