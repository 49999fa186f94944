#include "integrator/static_equilibrium.hpp"

#include <sstream>

namespace mfbd {

bool StaticEquilibrium::initialize(Dynamics& system, IntegratorState& state, std::string& message) {
  const int n = system.velocityCount();
  state.v = VectorXd::Zero(n);
  state.vdot = VectorXd::Zero(n);
  state.a = VectorXd::Zero(n);
  state.lambda = VectorXd::Zero(system.constraintCount());
  state.pathRate.resize(0);
  if (state.h <= 0.0) state.h = options_.hMax;
  VectorXd increment = VectorXd::Zero(n);
  if (!solve(system, state, increment, message)) {
    message = "no static equilibrium at the start: " + message;
    return false;
  }
  return true;
}

bool StaticEquilibrium::substep(Dynamics& system, IntegratorState& s, double h, std::string& why) {
  IntegratorState trial = s;
  trial.t = s.t + h;
  VectorXd increment = VectorXd::Zero(system.velocityCount());
  if (s.pathRate.size() == increment.size()) {
    increment = h * s.pathRate;
    system.retract(trial.q, increment);
  }
  if (!solve(system, trial, increment, why)) {
    s.newtonIterations = trial.newtonIterations;
    s.factorizations = trial.factorizations;
    s.pathRate.resize(0);  // the retry (halved) starts from the equilibrium itself
    return false;
  }
  ++trial.substeps;
  trial.pathRate = increment / h;
  s = std::move(trial);
  return true;
}

// Full Newton: the tangent stiffness is refactorised at every iteration.
bool StaticEquilibrium::solve(Dynamics& system, IntegratorState& s, VectorXd& increment, std::string& why) {
  const int n = system.velocityCount(), m = system.constraintCount();
  VectorXd r, phi, rhs;
  for (int k = 0; k < options_.maxIterations; ++k) {
    system.residual(s.t, s.q, s.v, s.vdot, s.lambda, r, phi);
    if (!r.allFinite() || !phi.allFinite()) {
      why = "residual is not finite";
      return false;
    }
    if (assembleIterationMatrix(system, s, 0.0, 0.0, 1.0)) solver_.analyzePattern(assembledIterationMatrix());
    ++s.factorizations;
    if (solver_.factorize(assembledIterationMatrix()) != LinearSolver::Status::Ok) {
      why = "singular tangent stiffness (an unsupported rigid-body mode, or a limit point)";
      return false;
    }
    rhs.setZero(assembledIterationMatrix().rows());
    rhs.head(n) = -r;
    rhs.segment(n, m) = -phi;
    const VectorXd delta = solver_.solve(rhs);
    ++s.newtonIterations;
    const double size = delta.head(n).cwiseAbs().maxCoeff();
    if (!std::isfinite(size)) {
      why = "Newton correction is not finite";
      return false;
    }
    system.retract(s.q, delta.head(n));
    increment += delta.head(n);
    s.lambda += delta.segment(n, m);
    if (size <= options_.tolerance && (m == 0 || phi.cwiseAbs().maxCoeff() <= options_.tolerance)) return true;
  }
  std::ostringstream msg;
  msg << "Newton did not reach equilibrium in " << options_.maxIterations << " iterations";
  why = msg.str();
  return false;
}

}  // namespace mfbd
