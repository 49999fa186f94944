#include "integrator_choice.hpp"

#include <algorithm>
#include <sstream>

#include "integrator/explicit_runge_kutta.hpp"
#include "integrator/generalized_alpha.hpp"
#include "integrator/static_equilibrium.hpp"
#include "math/number_text.hpp"

namespace mfbd {

namespace {
// Three significant digits: an estimate, for the log.
std::string estimate(double x) {
  std::ostringstream out;
  out.precision(3);
  out << x;
  return out.str();
}

IntegratorChoice generalizedAlpha(const SolverOptions& options, const std::string& why) {
  return {std::make_unique<GeneralizedAlpha>(options), "integrator: generalized-alpha: " + why};
}

IntegratorChoice dormandPrince(const SolverOptions& options, const std::string& why) {
  return {std::make_unique<DormandPrince>(options), "integrator: Dormand-Prince 5(4): " + why};
}
}  // namespace

IntegratorChoice chooseIntegrator(const Scene& scene, System& system, SolverOptions options) {
  using Method = SolverSection::Method;
  if (scene.analysis == Analysis::Static) return {std::make_unique<StaticEquilibrium>(options), ""};
  const bool flexible = system.model().flexible.nodes.size() > 0;
  if (scene.solver.method == Method::GeneralizedAlpha) return generalizedAlpha(options, "solver.method");
  if (scene.solver.method == Method::DormandPrince) {
    // Always error-controlled: an explicit method at a fixed step could go
    // unstable on a stiff scene and still return fmi2OK.
    const bool own = options.errorTolerance <= 0.0;
    if (own) options.errorTolerance = scene.experiment.tolerance;
    return dormandPrince(options, "solver.method, tolerance " + numberText(options.errorTolerance) +
                                      (own ? " (experiment.tolerance: none from fmi2SetupExperiment)" : "") +
                                      (flexible ? "; flexible bodies are stiff: expect many small substeps" : ""));
  }
  if (options.errorTolerance <= 0.0)
    return generalizedAlpha(options, "no error tolerance (fmi2SetupExperiment without one): substeps of h_max");
  if (flexible)
    return generalizedAlpha(options, "flexible bodies (stiff); the error of modes slower than h_max = " +
                                         numberText(options.hMax) + " s is held per unit step, of faster ones "
                                         "per step (README, Error control)");
  // Below the output interval h_max caps the substeps: there a substep of
  // generalized-alpha (Newton with a kept matrix) costs a fraction of the
  // explicit method's six stage solves, and the explicit method's order
  // buys accuracy the tolerance did not ask for.
  const double interval = scene.experiment.outputInterval;
  if (options.hMax < interval)
    return generalizedAlpha(options, "h_max = " + numberText(options.hMax) + " s caps the substeps below the output "
                                     "interval " + numberText(interval) + " s, where an implicit substep is cheaper");
  IntegratorState start;
  start.t = scene.experiment.startTime;
  start.q = system.model().initialConfiguration;
  start.v = system.model().initialVelocity;
  const double rate = DormandPrince(options).fastestRate(system, start);
  const std::string mode = "fastest mode at the start |lambda| = " + estimate(rate) +
                           " 1/s, times the output interval = " + estimate(rate * interval);
  if (rate * interval <= DormandPrince::kStabilityRadius)
    return dormandPrince(options, "rigid scene, not stiff: " + mode + " <= 1 (explicit stability)");
  return generalizedAlpha(options, "stiff: " + mode + " > 1 (explicit stability)");
}

}  // namespace mfbd
