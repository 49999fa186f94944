// Rotations over a long run (issue 4): a short beam (two elements) spun about z by its
// driven root node makes 1e6 implicit substeps through the solver
// (mfbd::Simulation, no FMU) and thousands of turns. The stored nodal
// orientations stay orthogonal to 1e-12 at every communication point, and
// the turn the tip node accumulates is the hub's analytic spin angle.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "scene/scene.hpp"
#include "simulation.hpp"

using namespace mfbd;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kOmega = 20.0;  // spin rate, rad/s: 0.02 rad per substep

// A stiff 1 m beam of two elements (first bending frequency 18 Hz) whose
// root starts spinning at once: the start transient (a lag of order
// omega / omega_1 = 0.2 rad)
// decays through a little stiffness-proportional damping (1 / (zeta
// omega_1) = 0.2 s for the first mode), long before the end of the run.
std::string spinningBeamScene() {
  return R"json({
  "format": "mfbd-scene/1", "name": "spinning_beam",
  "parameters": {"omega": 20.0},
  "solver": {"h_max": 1e-3, "rho_inf": 0.8},
  "flexible_bodies": [{
    "name": "beam", "damping": 1e-3,
    "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 2, "section_y": [0, 1, 0]},
    "section": {"EA": 1e6, "GJ": 1e3, "EIy": 1e3, "EIz": 1e3, "rhoA": 1.0, "rhoJ": [2e-4, 1e-4, 1e-4]},
    "supports": [{"node": 0, "type": "driven", "axis": [0, 0, 1], "angle": "omega*t"}]
  }]})json";
}

double orthogonalityError(const Mat3& A) { return (A.transpose() * A - Mat3::Identity()).norm(); }

}  // namespace

TEST(SpinningBeam, MillionStepsKeepOrientationsOrthogonalAndTheTurnCount) {
  Simulation sim(parseScene(spinningBeamScene()));
  std::string message;
  ASSERT_TRUE(sim.initialize(0.0, message)) << message;
  const double H = 0.01;  // communication step: 10 substeps, 0.2 rad of spin
  const long steps = 100000;
  const int tip = int(sim.state().q.rotations.size()) - 1;  // free nodes 1, 2 in order
  double worstOrthogonality = 0.0;
  // The tip's x axis angle in the xy plane, in (-pi, pi], and how often it
  // wrapped: the accumulated turn is 2 pi wraps + angle (no sum of
  // 1e5 increments, whose round-off would reach 1e-8 rad).
  double angle = 0.0;
  long wraps = 0;
  for (long k = 0; k < steps; ++k) {
    const AdvanceResult r = sim.doStep(H);
    ASSERT_TRUE(r.ok) << r.message;
    for (const Mat3& A : sim.state().q.rotations) worstOrthogonality = std::max(worstOrthogonality, orthogonalityError(A));
    const Mat3& A = sim.state().q.rotations[tip];
    const double previous = angle;
    angle = std::atan2(A(1, 0), A(0, 0));
    if (angle - previous < -kPi) ++wraps;  // increments are 0.2 rad: a jump is a wrap
    if (angle - previous > kPi) --wraps;
  }
  const double turned = 2 * kPi * double(wraps) + angle;
  const double t = sim.time();
  EXPECT_GE(sim.state().substeps, 1000000);  // a few more where round-off in t splits a step
  const double exact = kOmega * t;
  const Mat3& A = sim.state().q.rotations[tip];
  const Mat3 hub = Eigen::AngleAxisd(exact, Vec3::UnitZ()).toRotationMatrix();
  std::printf("[ spinning  ] %.0f turns in %ld substeps: max |A^T A - I| %.2e, tip turn - hub angle %.2e rad, "
              "|A_tip - Rz(hub)| %.2e; Newton %.2f, factorizations %.3f per substep\n",
              exact / (2 * kPi), sim.state().substeps, worstOrthogonality, turned - exact, (A - hub).norm(),
              double(sim.state().newtonIterations) / sim.state().substeps,
              double(sim.state().factorizations) / sim.state().substeps);
  EXPECT_LT(worstOrthogonality, 1e-12);
  EXPECT_GT(exact / (2 * kPi), 3000.0);
  // The tip lags the hub by 2.3e-9 rad after 1e6 substeps (the numerical
  // damping of rho_inf = 0.8 at omega h = 0.02 drags a little).
  EXPECT_LT(std::abs(turned - exact), 1e-8);
  EXPECT_LT((A - hub).norm(), 1e-8);
}

// Quaternion outputs: the exposed node's quaternion stays sign-continuous as
// the beam turns (no jump between communication points, while w changes
// sign with the turn); a node the scene does not list is not tracked at
// each step, and reading it gives its orientation with w >= 0.
TEST(SpinningBeam, ExposedQuaternionsAreContinuousOthersStillReadable) {
  std::string text = spinningBeamScene();
  const std::string anchor = R"("supports")";
  text.insert(text.find(anchor), R"("outputs": {"nodes": [2]}, )");
  Simulation sim(parseScene(text));
  std::string message;
  ASSERT_TRUE(sim.initialize(0.0, message)) << message;
  auto component = [&](int node, int c) { return sim.read({QuantityKind::NodeOrientation, node, c}); };
  auto quaternion = [&](int node) {
    return Eigen::Vector4d(component(node, 0), component(node, 1), component(node, 2), component(node, 3));
  };
  Eigen::Vector4d previous = quaternion(2);
  double largestJump = 0.0, smallestW = 1.0;
  for (int k = 0; k < 100; ++k) {  // 2 s: 6.4 turns of 0.2 rad per communication step
    ASSERT_TRUE(sim.doStep(0.01).ok);
    const Eigen::Vector4d now = quaternion(2);
    largestJump = std::max(largestJump, (now - previous).norm());
    smallestW = std::min(smallestW, now[0]);
    previous = now;
    const Eigen::Quaterniond middle(sim.system().nodes()[1].pose.A);
    const double sign = middle.w() < 0.0 ? -1.0 : 1.0;
    EXPECT_NEAR(component(1, 0), sign * middle.w(), 1e-15);
    EXPECT_NEAR(component(1, 3), sign * middle.z(), 1e-15);
    EXPECT_GE(component(1, 0), 0.0);
  }
  EXPECT_LT(smallestW, -0.99);      // the exposed quaternion went through w = -1: no re-signing
  // Half the turn of a step (0.2 rad, more in the start transient) apart at
  // most; a re-signed quaternion would jump by about 2.
  EXPECT_LT(largestJump, 0.5);
}
