#include "integrator/static_equilibrium.hpp"

#include <functional>
#include <limits>

#include "integrator/newton.hpp"

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

namespace {
// Equilibrium r(q) = 0, Phi(q) = 0 by Newton on the tangent stiffness, with
// the corrections accumulated in `increment`.
class EquilibriumNewton : public NewtonSystem {
 public:
  EquilibriumNewton(Dynamics& system, IntegratorState& s, VectorXd& increment, LinearSolver& solver,
                    const std::function<const SparseMatrix&(bool&)>& assemble)
      : system_(system), s_(s), increment_(increment), solver_(solver), assemble_(assemble),
        n_(system.velocityCount()), m_(system.constraintCount()) {}

  bool evaluate(NewtonIterate& it, std::string& why) override {
    system_.residual(s_.t, s_.q, s_.v, s_.vdot, s_.lambda, r_, phi_);
    if (!r_.allFinite() || !phi_.allFinite()) {
      why = "residual is not finite";
      return false;
    }
    it.violation = m_ > 0 ? phi_.cwiseAbs().maxCoeff() : 0.0;
    return true;
  }

  bool factorize(double, std::string& why) override {
    bool newPattern = false;
    const SparseMatrix& K = assemble_(newPattern);
    if (newPattern) solver_.analyzePattern(K);
    ++s_.factorizations;
    if (solver_.factorize(K) != LinearSolver::Status::Ok) {
      why = "singular tangent stiffness (an unsupported rigid-body mode, or a limit point)";
      return false;
    }
    rows_ = K.rows();
    return true;
  }

  double correct() override {
    VectorXd rhs = VectorXd::Zero(rows_);
    rhs.head(n_) = -r_;
    rhs.segment(n_, m_) = -phi_;
    const VectorXd delta = solver_.solve(rhs);
    ++s_.newtonIterations;
    if (!delta.allFinite()) return std::numeric_limits<double>::quiet_NaN();
    const double size = delta.head(n_).cwiseAbs().maxCoeff();
    system_.retract(s_.q, delta.head(n_));
    increment_ += delta.head(n_);
    s_.lambda += delta.segment(n_, m_);
    return size;
  }

 private:
  Dynamics& system_;
  IntegratorState& s_;
  VectorXd& increment_;
  LinearSolver& solver_;
  const std::function<const SparseMatrix&(bool&)>& assemble_;
  int n_, m_;
  Eigen::Index rows_ = 0;
  VectorXd r_, phi_;
};
}  // namespace

// Full Newton: the tangent stiffness is refactorised at every iteration.
bool StaticEquilibrium::solve(Dynamics& system, IntegratorState& s, VectorXd& increment, std::string& why) {
  const std::function<const SparseMatrix&(bool&)> assemble = [&](bool& newPattern) -> const SparseMatrix& {
    newPattern = assembleIterationMatrix(system, s, 0.0, 0.0, 1.0);
    return assembledIterationMatrix();
  };
  EquilibriumNewton problem(system, s, increment, solver_, assemble);
  MatrixRefreshPolicy fullNewton(MatrixRefreshPolicy::Kind::Full);
  return solveNewton(problem, CorrectionSizeTest(options_.tolerance), fullNewton, 0.0, options_.maxIterations,
                     "reach equilibrium", why) &&
         redundantRowsHold(system, why);
}

}  // namespace mfbd
