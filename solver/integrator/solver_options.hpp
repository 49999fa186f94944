// What the time steppers are told: substep sizes, the generalized-alpha
// parameter, Newton's tolerance and error control. Plain numbers with no
// scene behind them: the Simulation fills them from the scene's solver
// section and the FMI tolerance (simulation.cpp: solverOptions), tests and
// drivers set them directly.
#pragma once

namespace mfbd {

struct SolverOptions {
  double hMax = 1e-3;       // largest implicit substep, s
  double hMin = 1e-9;       // smallest substep before a step is discarded, s
  double rhoInf = 0.8;      // generalized-alpha spectral radius at infinity
  // Substeps (tried, rejected ones included) one communication step may
  // take: the bound on the work of one fmi2DoStep.
  double maxSubsteps = 1e5;
  // Newton: the position error left after the last correction (m, rad).
  // Truncation errors of Newton accumulate over many steps as a drift (energy
  // of a conservative system), so the default is near round-off.
  double tolerance = 1e-14;
  int maxIterations = 12;
  // Error control (the FMI tolerance, fmi2SetupExperiment), meant for the
  // error at the end of an experiment of duration errorHorizon (s), in
  // units of errorScale, the scene's length scale (rad against errorScale /
  // 1 m). How each stepper holds it per substep (per unit step, tol L h /
  // T; per step) is said where it does (TimeStepper::allowedLocalError,
  // GeneralizedAlpha::errorRatio, DormandPrince::errorRatio). 0: no
  // control, substeps of h_max.
  double errorTolerance = 0.0;
  double errorScale = 1.0;
  double errorHorizon = 1.0;
  // Newton's tolerance follows the error tolerance (a fraction of the local
  // error allowed) instead of `tolerance`, which the scene did not set.
  bool newtonFollowsError = false;
};

}  // namespace mfbd
