// The substep loop keeps time as the duration of the step: the same motion
// at any start time, what is asked integrated to the last bit, and the work
// of one step bounded by solver.max_substeps.
#include <gtest/gtest.h>

#include <cmath>

#include "integrator/generalized_alpha.hpp"
#include "oscillator.hpp"
#include "scene/scene.hpp"
#include "simulation.hpp"

using namespace mfbd;

namespace {

IntegratorState released(GeneralizedAlpha& ga, Oscillator& osc, double t0) {
  IntegratorState s;
  s.t = t0;
  s.q.scalars = VectorXd::Ones(1);
  s.v = VectorXd::Zero(1);
  std::string message;
  EXPECT_TRUE(ga.initialize(osc, s, message)) << message;
  return s;
}

}  // namespace

TEST(TimeKeeping, TheMotionDoesNotDependOnTheStartTime) {
  // 100 steps of 0.01 s: at t0 = 1e10 an absolute time has a resolution of
  // 2e-6 s, but the substeps are sized from the durations alone.
  SolverOptions o;
  o.hMax = 1e-3;
  Oscillator osc(2.0 * M_PI);
  GeneralizedAlpha early(o), late(o);
  IntegratorState a = released(early, osc, 0.0), b = released(late, osc, 1e10);
  for (int k = 0; k < 100; ++k) {
    ASSERT_TRUE(early.advance(osc, a, 0.01).ok);
    ASSERT_TRUE(late.advance(osc, b, 0.01).ok);
  }
  EXPECT_EQ(a.q.scalars[0], b.q.scalars[0]);
  EXPECT_EQ(a.v[0], b.v[0]);
  EXPECT_EQ(a.substeps, 1000);
  EXPECT_NEAR(a.q.scalars[0], 1.0, 1e-4);  // one period: back to the start (phase error O(h^2))
}

TEST(TimeKeeping, TheStepEndsOnTheMastersTime) {
  // Simulation::doStep(t, H) ends at t + H as the master computes it.
  Scene scene = parseScene(R"({"format": "mfbd-scene/1", "name": "p", "gravity": [0, -9.81, 0],
    "bodies": [{"name": "bob", "mass": 1, "inertia": [0, 0, 0], "position": [1, 0, 0]}],
    "joints": [{"name": "hinge", "type": "revolute", "parent": "ground", "child": "bob", "position": [0, 0, 0]}]})");
  Simulation sim(scene);
  std::string message;
  const double t0 = 1e10, H = 0.01;
  ASSERT_TRUE(sim.initialize(t0, message)) << message;
  double t = t0;
  for (int k = 0; k < 10; ++k) {
    ASSERT_TRUE(sim.doStep(t, H).ok);
    t += H;
    EXPECT_EQ(sim.time(), t);
  }
  EXPECT_EQ(sim.state().substeps, 100);  // 0.01 s each, 10 substeps of h_max = 1e-3
}

TEST(TimeKeeping, AStepBeyondMaxSubstepsFailsBeforeAnySubstep) {
  SolverOptions o;
  o.hMax = 1e-3;
  o.maxSubsteps = 100;
  Oscillator osc(1.0);
  GeneralizedAlpha ga(o);
  IntegratorState s = released(ga, osc, 0.0);
  for (double duration : {0.2, 1e300}) {
    const AdvanceResult r = ga.advance(osc, s, duration);
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.message.find("more than solver.max_substeps = 100"), std::string::npos) << r.message;
    EXPECT_EQ(s.substeps, 0);
    EXPECT_EQ(s.t, 0.0);
  }
  EXPECT_TRUE(ga.advance(osc, s, 0.1).ok);  // exactly 100 substeps
  EXPECT_EQ(s.substeps, 100);
  EXPECT_EQ(s.t, 0.1);
}
