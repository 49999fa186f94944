// Static equilibrium before a dynamic run (scene "solver": {"initial_equilibrium":
// true}): the system at rest under its gravity and loads at the start time,
// so that the dynamics starts there instead of from the stress-free design
// configuration.
#pragma once
#include <string>

#include "integrator/time_stepper.hpp"
#include "system.hpp"

namespace mfbd {

struct InitialEquilibriumReport {
  int loadSteps = 0;            // equilibria solved on the way (1: the full load at once)
  long newtonIterations = 0;    // over all load steps
  double nodeDisplacement = 0;  // largest node displacement from the start, m
  double nodeRotation = 0;      // largest node rotation from the start, rad
  int node = -1;                // the node that moved most (mesh numbering), -1: no nodes

  std::string describe(const System& system) const;  // one log line
};

// Newton on the tangent stiffness (StaticEquilibrium) at state.t from
// state.q, at rest; on failure load stepping: gravity and the flexible
// bodies' nodal loads (input loads included) ramped by a factor from 0 to 1
// in steps halved on failure (down to 1/1024) and grown after successes;
// other applied forces act in full throughout. On success state holds the
// equilibrium with v = vdot = 0; on failure state is unchanged.
bool solveInitialEquilibrium(System& system, IntegratorState& state, const SolverOptions& options,
                             InitialEquilibriumReport& report, std::string& message);

}  // namespace mfbd
