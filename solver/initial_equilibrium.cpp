#include "initial_equilibrium.hpp"

#include <cstdio>
#include <sstream>

#include "integrator/static_equilibrium.hpp"

namespace mfbd {

namespace {

// Gravity and nodal loads scaled by a load factor; the originals come back
// when this goes out of scope (exactly: they are copied, not divided).
class LoadFactor {
 public:
  explicit LoadFactor(System& system)
      : system_(system),
        gravity_(system.model().gravity),
        loads_(system.model().flexible.loads),
        inputs_(system.flexibleInputs()) {}
  ~LoadFactor() { set(1.0); }

  void set(double factor) {
    Model& model = system_.tunableModel();
    model.gravity = factor * gravity_;
    for (std::size_t i = 0; i < loads_.size(); ++i) {
      FlexLoad& l = model.flexible.loads[i];
      l.force = factor * loads_[i].force;
      l.moment = factor * loads_[i].moment;
      if (l.inputOffset >= 0)
        system_.flexibleInputs().segment<6>(l.inputOffset) = factor * inputs_.segment<6>(l.inputOffset);
    }
  }

 private:
  System& system_;
  const Vec3 gravity_;
  const std::vector<FlexLoad> loads_;
  const VectorXd inputs_;
};

std::vector<NodeState> nodeStates(System& system, const IntegratorState& s) {
  system.evaluate(s.t, s.q, s.v, VectorXd::Zero(s.v.size()), s.lambda);
  return system.nodes();
}

}  // namespace

bool solveInitialEquilibrium(System& system, IntegratorState& state, const SolverOptions& options,
                             InitialEquilibriumReport& report, std::string& message) {
  report = InitialEquilibriumReport();
  IntegratorState start = state;
  start.v.setZero(system.velocityCount());
  const std::vector<NodeState> before = nodeStates(system, start);
  StaticEquilibrium newton(options);
  LoadFactor loads(system);
  IntegratorState done = start, trial;
  double reached = 0.0, step = 1.0;
  const long iterationsBefore = state.newtonIterations;
  while (reached < 1.0) {
    const double factor = std::min(1.0, reached + step);
    loads.set(factor);
    trial = done;
    std::string why;
    if (newton.initialize(system, trial, why)) {
      done = trial;
      reached = factor;
      ++report.loadSteps;
      step *= 2.0;
    } else {
      done.newtonIterations = trial.newtonIterations;
      done.factorizations = trial.factorizations;
      step *= 0.5;
      if (step < 1.0 / 1024.0) {
        char text[64];
        std::snprintf(text, sizeof text, " (at load factor %.4g after %d load steps)", factor, report.loadSteps);
        message = "initial equilibrium: " + why + text;
        return false;
      }
    }
  }
  report.newtonIterations = done.newtonIterations - iterationsBefore;
  state = done;
  const std::vector<NodeState> after = nodeStates(system, state);
  for (std::size_t i = 0; i < after.size(); ++i) {
    const double moved = (after[i].pose.r - before[i].pose.r).norm();
    if (moved > report.nodeDisplacement || report.node < 0) {
      report.nodeDisplacement = moved;
      report.node = int(i);
    }
    report.nodeRotation = std::max(report.nodeRotation, logSO3(before[i].pose.A.transpose() * after[i].pose.A).norm());
  }
  return true;
}

std::string InitialEquilibriumReport::describe(const System& system) const {
  std::ostringstream line;
  line.precision(3);
  line << "initial equilibrium: " << newtonIterations << " Newton iterations in " << loadSteps << " load step"
       << (loadSteps == 1 ? "" : "s");
  for (const FlexibleBody& b : system.model().flexible.bodies)
    if (node >= b.firstNode && node < b.firstNode + b.nodeCount)
      line << "; nodes moved by up to " << nodeDisplacement << " m (node " << node - b.firstNode << " of '" << b.name
           << "') and turned by up to " << nodeRotation << " rad";
  return line.str();
}

}  // namespace mfbd
