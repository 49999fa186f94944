// Which time integrator a scene runs with (SolverOptions::method), and why:
// one line for the FMU's log.
#pragma once
#include <memory>
#include <string>

#include "integrator/time_stepper.hpp"
#include "system.hpp"

namespace mfbd {

struct IntegratorChoice {
  std::unique_ptr<TimeStepper> stepper;
  std::string note;  // "integrator: ...: why" (empty for statics)
};

// Statics: load stepping. Dynamics: generalized-alpha or Dormand-Prince as
// solver.method says; automatic takes Dormand-Prince under an error
// tolerance for a scene without flexible bodies whose substeps may grow to
// the output interval (h_max at least experiment.output_interval) and whose
// fastest mode at the start, |lambda|, is slow for them: |lambda| times the
// output interval <= 1, the half-disc of the explicit method's stability
// region (DormandPrince::kStabilityRadius).
// `system` is evaluated at the scene's initial state (the estimate).
IntegratorChoice chooseIntegrator(const Scene& scene, System& system, SolverOptions options);

}  // namespace mfbd
