#include "integrator/time_stepper.hpp"

#include <cmath>
#include <sstream>

namespace mfbd {

SparseMatrix TimeStepper::iterationMatrix(Dynamics& system, const IntegratorState& at, double cM, double cC,
                                          double cK) {
  const int n = system.velocityCount(), m = system.constraintCount();
  Triplets all, jacobian;
  system.tangent(at.t, at.q, at.v, at.vdot, at.lambda, cM, cC, cK, all, jacobian);
  all.reserve(all.size() + 2 * jacobian.size() + n + m);
  for (const auto& t : jacobian) {
    all.emplace_back(n + t.row(), t.col(), t.value());
    all.emplace_back(t.col(), n + t.row(), t.value());
  }
  // Every diagonal entry structurally present: the pattern stays the same.
  for (int i = 0; i < n + m; ++i) all.emplace_back(i, i, 0.0);
  SparseMatrix S(n + m, n + m);
  S.setFromTriplets(all.begin(), all.end());
  S.makeCompressed();
  return S;
}

AdvanceResult TimeStepper::advance(Dynamics& system, IntegratorState& s, double tEnd) {
  AdvanceResult result;
  beginAdvance();
  double h = std::min(s.h > 0.0 ? s.h : options_.hMax, options_.hMax);
  int successes = 0;
  while (tEnd - s.t > 1e-12 * std::max(1.0, std::abs(tEnd))) {
    const double remaining = tEnd - s.t;
    // Take the rest in one substep when it fits (within round-off), else h.
    const double step = remaining <= h * (1.0 + 1e-9) ? remaining : h;
    std::string why;
    if (substep(system, s, step, why)) {
      if (++successes >= 2 && h < options_.hMax) {
        h = std::min(2.0 * h, options_.hMax);
        successes = 0;
      }
      continue;
    }
    ++s.rejectedSubsteps;
    successes = 0;
    h = 0.5 * step;
    if (h < options_.hMin) {
      std::ostringstream msg;
      msg << "substep failed at t = " << s.t << " with h = " << step << " (h_min = " << options_.hMin
          << "): " << why;
      result.ok = false;
      result.reachedTime = s.t;
      result.message = msg.str();
      return result;
    }
  }
  s.t = tEnd;
  s.h = h;
  result.reachedTime = tEnd;
  return result;
}

}  // namespace mfbd
