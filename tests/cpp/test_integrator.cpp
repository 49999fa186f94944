// Generalized-alpha on the smallest systems with exact solutions: second-order
// convergence, the spectral radius at infinity, and step halving; the rank
// of a constraint Jacobian and the redundant rows left out of the solve.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "integrator/constraint_rank.hpp"
#include "integrator/generalized_alpha.hpp"
#include "oscillator.hpp"
#include "scene/scene.hpp"
#include "model/model.hpp"
#include "simulation.hpp"
#include "system.hpp"

using namespace mfbd;

namespace {

double finalError(double h, double rho) {
  SolverOptions o;
  o.hMax = h;
  o.rhoInf = rho;
  o.tolerance = 1e-14;
  Oscillator osc(2.0 * M_PI);
  GeneralizedAlpha ga(o);
  IntegratorState s;
  s.q.scalars = VectorXd::Ones(1);
  s.v = VectorXd::Zero(1);
  std::string msg;
  EXPECT_TRUE(ga.initialize(osc, s, msg)) << msg;
  // At 1.25 periods x(t) = cos(2 pi t) crosses zero, where the phase error
  // (second order) shows at first order; at a peak it would show squared.
  EXPECT_TRUE(ga.advance(osc, s, 1.25).ok);
  return std::abs(s.q.scalars[0]);
}

}  // namespace

TEST(GeneralizedAlpha, ConvergesAtSecondOrder) {
  for (double rho : {1.0, 0.8, 0.5}) {
    const double e1 = finalError(1e-2, rho), e2 = finalError(5e-3, rho);
    const double order = std::log2(e1 / e2);
    EXPECT_NEAR(order, 2.0, 0.1) << "rho_inf = " << rho;
  }
}

namespace {

// Free vibration at omega h = 1e4 over n steps of h = 1.
double amplitudeAfter(double rho, int steps) {
  SolverOptions o;
  o.hMax = 1.0;
  o.rhoInf = rho;
  o.tolerance = 1e-14;  // the problem is linear: the first correction is exact
  Oscillator osc(1e4);
  GeneralizedAlpha ga(o);
  IntegratorState s;
  s.q.scalars = VectorXd::Ones(1);
  s.v = VectorXd::Zero(1);
  std::string msg;
  EXPECT_TRUE(ga.initialize(osc, s, msg)) << msg;
  EXPECT_TRUE(ga.advance(osc, s, double(steps)).ok);
  return std::abs(s.q.scalars[0]);
}

}  // namespace

TEST(GeneralizedAlpha, DampsTheHighestFrequencyByRhoInf) {
  // The amplification matrix has the double root -rho_inf at omega h -> inf,
  // so x_n ~ (a + b n) rho_inf^n: the rate over steps 200..400 is rho_inf
  // within the polynomial factor 2^(1/200) = 1.0035 and
  // the finite omega h (measured: 1.0054 rho and 1.0067 rho).
  for (double rho : {0.5, 0.8}) {
    const double rate = std::pow(amplitudeAfter(rho, 400) / amplitudeAfter(rho, 200), 1.0 / 200.0);
    EXPECT_NEAR(rate, rho, 0.01 * rho) << "rho_inf = " << rho;
  }
  // rho_inf = 0 annihilates the high frequency within a few steps.
  EXPECT_LT(amplitudeAfter(0.0, 4), 1e-6);
}

TEST(ConstraintRank, FindsVanishingAndDependentRows) {
  // Row 1 vanishes; row 3 = 5 (row 0 + row 2): rank 2 of four rows.
  Eigen::MatrixXd J(4, 3);
  J << 1, 0, 0,  //
      0, 0, 0,   //
      0, 1, 0,   //
      5, 5, 0;
  ConstraintRank r = constraintRank(J);
  EXPECT_EQ(r.rank, 2);
  ASSERT_EQ(r.vanishingRows, std::vector<int>{1});
  ASSERT_EQ(r.dependentRows.size(), 1u);
  std::vector<int> set = r.dependentRows[0];
  std::sort(set.begin(), set.end());
  EXPECT_EQ(set, (std::vector<int>{0, 2, 3}));
  // A dependency broken at 1e-6 (relative) is a full rank; at 1e-12 it is not.
  J(3, 2) = 5e-6;
  EXPECT_EQ(constraintRank(J).rank, 3);
  EXPECT_TRUE(constraintRank(J).dependentRows.empty());
  J(3, 2) = 5e-12;
  EXPECT_EQ(constraintRank(J).rank, 2);
}

namespace {

// R2: two 1 m, 1 kg bars from horizontal on revolute joints, rho_inf = 1.
Scene doublePendulum(double hMax) {
  Scene scene = parseScene(R"({"format": "mfbd-scene/1", "name": "r2", "gravity": [0, -9.81, 0],
    "solver": {"rho_inf": 1.0},
    "bodies": [{"name": "bar1", "mass": 1, "inertia": [0, 0.0833333333333333, 0.0833333333333333], "position": [0.5, 0, 0]},
               {"name": "bar2", "mass": 1, "inertia": [0, 0.0833333333333333, 0.0833333333333333], "position": [1.5, 0, 0]}],
    "joints": [{"name": "shoulder", "type": "revolute", "parent": "ground", "child": "bar1", "position": [0, 0, 0]},
               {"name": "elbow", "type": "revolute", "parent": "bar1", "child": "bar2", "position": [1, 0, 0]}]})");
  scene.solver.hMax = hMax;
  return scene;
}

}  // namespace

TEST(GeneralizedAlpha, LongCommunicationStepsNeitherRejectNorChangeTheAnswer) {
  // R2 double pendulum (two 1 m, 1 kg bars from horizontal), h = 1e-2,
  // rho_inf = 1: with doStep 0.1 s the matrix of a communication point is
  // kept over ten substeps. Modified Newton must refresh it in time to meet
  // the tolerance rather than fail whole substeps (it rejected 75 of 1075
  // in 10 s before), and land on the motion of doStep 0.01 s (fresh matrix
  // every substep) to the Newton tolerance's accumulation over 3 s.
  const Scene scene = doublePendulum(0.01);
  Simulation longSteps(scene), shortSteps(scene);
  std::string message;
  ASSERT_TRUE(longSteps.initialize(0.0, message));
  ASSERT_TRUE(shortSteps.initialize(0.0, message));
  for (int k = 0; k < 30; ++k) {
    ASSERT_TRUE(longSteps.doStep(0.1).ok);
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(shortSteps.doStep(0.01).ok);
  }
  EXPECT_EQ(longSteps.state().rejectedSubsteps, 0);
  EXPECT_EQ(longSteps.state().substeps, 300);
  EXPECT_LT((longSteps.state().q.scalars - shortSteps.state().q.scalars).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(GeneralizedAlpha, IterationMatrixIsKeptAcrossCommunicationPointsWhenItPays) {
  // A cantilever ringing after a tip pulse (F3 with 8 elements), h = 1e-3:
  // its substeps converge in two corrections with one matrix, so doStep
  // 0.01 s keeps that matrix across its 20 communication points (one
  // factorization in all) and lands on the motion of a single doStep of
  // 0.2 s to the Newton tolerance. The double pendulum of the test above at
  // h = 1e-3 takes more than two corrections per substep (its matrix ages
  // fast): a fresh matrix at (almost) every communication point.
  const char* beam = R"json({"format": "mfbd-scene/1", "name": "f3", "solver": {"h_max": 1e-3, "rho_inf": 0.9},
    "flexible_bodies": [{"name": "beam",
      "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 8, "section_y": [0, 1, 0]},
      "section": {"EA": 1e6, "GJ": 1, "EIy": 1, "EIz": 1, "rhoA": 1, "rhoJ": [2e-6, 1e-6, 1e-6]},
      "supports": [{"node": 0, "type": "clamp"}],
      "loads": [{"node": 8, "force": [0, 0.01, 0], "scale": "if(0.02 - t, sin(pi*t/0.02)^2, 0)"}]}]})json";
  Simulation stepped(parseScene(beam)), once(parseScene(beam));
  std::string message;
  ASSERT_TRUE(stepped.initialize(0.0, message));
  ASSERT_TRUE(once.initialize(0.0, message));
  for (int k = 0; k < 20; ++k) ASSERT_TRUE(stepped.doStep(0.01).ok);
  ASSERT_TRUE(once.doStep(0.2).ok);
  EXPECT_EQ(stepped.state().substeps, 200);
  EXPECT_EQ(stepped.state().newtonIterations, 400);
  EXPECT_EQ(stepped.state().factorizations, 1);
  EXPECT_LT((stepped.state().q.scalars - once.state().q.scalars).cwiseAbs().maxCoeff(), 1e-12);

  const Scene pendulum = doublePendulum(1e-3);
  Simulation swinging(pendulum);
  ASSERT_TRUE(swinging.initialize(0.0, message));
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(swinging.doStep(0.01).ok);
  // Measured 94 of 100: kept only where a communication step's last
  // substep happened to converge in two corrections.
  EXPECT_GT(swinging.state().factorizations, 90);

  // The beam at h = 1e-2 takes three or four corrections per substep, but
  // its tangent costs 16 residuals (the pendulum's 3): it keeps its matrix
  // over communication points, refreshed only inside substeps that slow.
  EXPECT_DOUBLE_EQ(System(assemble(pendulum)).tangentCost(), 3.0);
  EXPECT_DOUBLE_EQ(System(assemble(parseScene(beam))).tangentCost(), 16.0);
  Scene coarse = parseScene(beam);
  coarse.solver.hMax = 1e-2;
  Simulation ringing(coarse);
  ASSERT_TRUE(ringing.initialize(0.0, message));
  for (int k = 0; k < 300; ++k) ASSERT_TRUE(ringing.doStep(0.01).ok);
  EXPECT_GT(ringing.state().newtonIterations, 2.5 * 300);
  EXPECT_LT(ringing.state().factorizations, 0.2 * 300);
}

TEST(GeneralizedAlpha, NewtonToleranceDoesNotMoveTheConvergedMotion) {
  // The pendulum R1, 10 s at h = 2e-3: the Newton tolerance bounds the
  // position error a substep leaves, but a position error d is a velocity
  // error gamma' d ~ d / h and an acceleration error ~ d / h^2, which the
  // motion accumulates. Stopping at a looser tolerance must still land on
  // the converged motion (measured: 1e-10 and 1e-16 agree to round-off).
  // A stop at the first correction with the estimated error below 1e-10
  // or 1e-12 (tried, session 7) moved the angle at 10 s by 5e-6 and 3e-6
  // rad, 3 % of the time discretization's error.
  const char* pendulum = R"json({"format": "mfbd-scene/1", "name": "r1", "gravity": [0, -9.81, 0],
    "solver": {"h_max": 2e-3, "rho_inf": 0.8},
    "bodies": [{"name": "bob", "mass": 1, "inertia": [0, 0, 0], "position": [1, 0, 0]}],
    "joints": [{"name": "hinge", "type": "revolute", "parent": "ground", "child": "bob", "position": [0, 0, 0],
                "axis": [0, 0, 1]}]})json";
  double angle[2];
  for (int k = 0; k < 2; ++k) {
    Scene scene = parseScene(pendulum);
    scene.solver.tolerance = k == 0 ? 1e-10 : 1e-16;
    Simulation sim(scene);
    std::string message;
    ASSERT_TRUE(sim.initialize(0.0, message)) << message;
    for (int i = 0; i < 100; ++i) ASSERT_TRUE(sim.doStep(0.1).ok);
    angle[k] = sim.state().q.scalars[0];
  }
  EXPECT_LT(std::abs(angle[0] - angle[1]), 1e-9) << angle[0] << " " << angle[1];
}

TEST(GeneralizedAlpha, StaleMatrixOfASpinningUpBeamIsRefreshed) {
  // F4 at two elements (h = 8e-3, doStep 0.04 s, the first 8 s of the
  // spin-up): turned with the beam, the kept matrix still ages as the spin
  // speeds up (centrifugal stiffening), its first contraction rising past
  // 1e-3; then a fresh one is worth its tangent over half the substeps the
  // old one served, and the corrections stay near three per substep
  // (measured 2.97, 34 factorizations; with the short horizon alone 4.49
  // and 4).
  // The ringing cantilever above stays with its matrix: its contraction
  // is 1e-4 whatever its corrections.
  const char* spinUp = R"json({"format": "mfbd-scene/1", "name": "f4", "solver": {"h_max": 8e-3, "rho_inf": 0.8},
    "parameters": {"T": {"value": 15.0}, "omega": {"value": 6.0}},
    "flexible_bodies": [{"name": "beam",
      "beam": {"start": [0, 0, 0], "end": [10, 0, 0], "elements": 2, "section_y": [0, 1, 0]},
      "section": {"EA": 2.8e7, "GAy": 1e7, "GAz": 1e7, "GJ": 1.4e4, "EIy": 1.4e4, "EIz": 1.4e4, "rhoA": 1.2,
                  "rhoJ": [1.2e-3, 6e-4, 6e-4]},
      "supports": [{"node": 0, "type": "driven", "axis": [0, 0, 1],
                    "angle": "if(T - t, omega/T*(t^2/2 + (T/(2*pi))^2*(cos(2*pi*t/T) - 1)), omega*T/2 + omega*(t - T))"}]}]})json";
  Simulation sim(parseScene(spinUp));
  std::string message;
  ASSERT_TRUE(sim.initialize(0.0, message)) << message;
  for (int k = 0; k < 200; ++k) ASSERT_TRUE(sim.doStep(0.04).ok);
  const IntegratorState& s = sim.state();
  std::printf("spin-up: %ld substeps, %.2f corrections and %.3f factorizations per substep\n", s.substeps,
              double(s.newtonIterations) / s.substeps, double(s.factorizations) / s.substeps);
  EXPECT_EQ(s.substeps, 1000);
  EXPECT_LT(s.newtonIterations, 3.3 * s.substeps);
  EXPECT_GT(s.factorizations, 5);
  EXPECT_LT(s.factorizations, 0.1 * s.substeps);
}

TEST(GeneralizedAlpha, RestoredStateAndNewtonMemoryReplayBitForBit) {
  // What FMU state saves of the integrator: the IntegratorState (with the
  // predictor's history and the substep size) and the NewtonMemory (the
  // refresh policy and the origin of the kept matrix). A second integrator
  // given both continues exactly as the first, kept matrix included.
  const Scene scene = doublePendulum(1e-3);
  SolverOptions options;
  options.hMax = scene.solver.hMax;
  options.rhoInf = 0.8;
  System first(assemble(scene)), second(assemble(scene));
  GeneralizedAlpha a(options), b(options);
  IntegratorState s;
  s.q = first.model().initialConfiguration;
  s.v = first.model().initialVelocity;
  std::string message;
  ASSERT_TRUE(a.initialize(first, s, message)) << message;
  for (int k = 0; k < 30; ++k) ASSERT_TRUE(a.advance(first, s, 0.01).ok);
  ASSERT_GT(a.newtonMemory().factoredStep, 0.0);  // a kept matrix to restore
  IntegratorState saved = s;
  ASSERT_TRUE(b.restoreNewtonMemory(second, a.newtonMemory()));
  for (int k = 0; k < 30; ++k) {
    ASSERT_TRUE(a.advance(first, s, 0.01).ok);
    ASSERT_TRUE(b.advance(second, saved, 0.01).ok);
  }
  EXPECT_EQ(s.q.scalars, saved.q.scalars);
  EXPECT_EQ(s.v, saved.v);
  EXPECT_EQ(s.newtonIterations, saved.newtonIterations);
  EXPECT_EQ(s.factorizations, saved.factorizations);
}

TEST(GeneralizedAlpha, ErrorControlRejectsAndShrinksTheSubstepOfAStiffOscillator) {
  // omega = 1e3 rad/s at h_max = 1e-2 (omega h = 10): the fixed step damps
  // the motion away; with a tolerance the substeps shrink until the local
  // error estimate is met (error per unit step over the 0.1 s run), and the
  // motion x = cos(omega t) comes out to a small multiple of the tolerance.
  auto run = [](double tolerance, IntegratorState& s) {
    SolverOptions o;
    o.hMax = 1e-2;
    o.errorTolerance = tolerance;
    o.errorHorizon = 0.1;
    Oscillator osc(1e3);
    GeneralizedAlpha ga(o);
    s.q.scalars = VectorXd::Ones(1);
    s.v = VectorXd::Zero(1);
    std::string msg;
    EXPECT_TRUE(ga.initialize(osc, s, msg)) << msg;
    for (int k = 0; k < 10; ++k) EXPECT_TRUE(ga.advance(osc, s, 0.01).ok);
    return std::abs(s.q.scalars[0] - std::cos(1e3 * 0.1));
  };
  IntegratorState fixed, controlled;
  EXPECT_GT(run(0.0, fixed), 0.5);
  EXPECT_LT(run(1e-4, controlled), 1e-3);
  EXPECT_GT(controlled.rejectedSubsteps, 0);
  EXPECT_GT(controlled.substeps, 100 * fixed.substeps);
}

namespace {

// Twenty substeps of three corrections each with a kept matrix, as measured
// on R3 (81 bodies, 40 loops) at h = 5e-4: a good predictor leaves a first
// correction of 1.3e-12 m, about twice the round-off floor of 5.9e-13 m;
// the next two are noise. Each substep's local discretisation error is
// `local`. Returns whether the communication point refreshes the matrix.
bool refreshesAfterNoiseLevelSubsteps(double local) {
  MatrixRefreshPolicy policy;
  policy.factorized(5e-4);
  const double sizes[] = {1.3e-12, 1.5e-14, 1.0e-14};
  for (int substep = 0; substep < 20; ++substep) {
    policy.beginSolve();
    NewtonIterate it;
    for (it.k = 0; it.k < 3; ++it.k) {
      it.size = sizes[it.k];
      Assessment a;
      a.floor = 5.9e-13;
      a.rho = it.k > 0 ? it.size / it.previous : 1.0;
      a.remaining = a.rho < 1.0 ? a.rho / (1.0 - a.rho) * it.size : HUGE_VAL;
      policy.observe(it, a);
      if (it.k == 2) policy.accepted(it, a);
      it.previous = it.size;
    }
    policy.addDiscretisationError(local);
  }
  policy.beginAdvance(6.0);  // R3's tangent cost in residuals
  return policy.needsFactorization(5e-4);
}

}  // namespace

TEST(MatrixRefreshPolicy, NoiseLevelRatesKeepTheMatrixUnlessItsErrorCounts) {
  // R3's local errors (1.2e-10 m): the noise over the first correction is
  // no sign of a stale matrix (before: read as a rate of 0.012, it
  // refreshed the matrix at every communication point).
  EXPECT_FALSE(refreshesAfterNoiseLevelSubsteps(1.2e-10));
  // The same corrections against local errors of 5e-15 m (four_bar at
  // h = 1e-5): Newton's error left, 2e-14 m a substep, is no longer a
  // hundredth of them, and a kept matrix's error adds up as a drift.
  EXPECT_TRUE(refreshesAfterNoiseLevelSubsteps(5e-15));
}

namespace {

Scene exampleScene(const std::string& name) {
  std::ifstream file(std::string(MFBD_EXAMPLES_DIR) + "/" + name + "/" + name + ".json");
  std::stringstream text;
  text << file.rdbuf();
  return parseScene(text.str());
}

}  // namespace

TEST(RedundantConstraints, BricardLeavesItsRedundantRowOutAndKeepsItsMultipliersBounded) {
  // R4 at the benchmark's settings (h = 1e-3, rho_inf = 1, Newton
  // tolerance 1e-14), 3 s: one row of the cut joint J6 depends on the
  // others along the whole motion. Kept in the solve, the regularised
  // constraint block turned its round-off into a multiplier along the null
  // space of Phi_q^T at every iteration, and the iterations added it up
  // (3.5e4 N at 3 s, 2e6 N at 10 s); through a kept matrix it leaked into
  // corrections that did not contract, and the matrix was refactorised at
  // 2,116 of the 3,000 substeps. Left out, the multipliers stay of the
  // reactions' size (20 N; the five rods weigh 49 N) and the matrix is
  // kept (296 factorizations).
  Scene scene = exampleScene("bricard");
  scene.solver.tolerance = 1e-14;
  Simulation simulation(scene);
  std::string message;
  ASSERT_TRUE(simulation.initialize(0.0, message)) << message;
  ASSERT_EQ(simulation.system().redundantRows().size(), 1u);
  for (int k = 0; k < 300; ++k) ASSERT_TRUE(simulation.doStep(0.01).ok);
  EXPECT_EQ(simulation.state().substeps, 3000);
  EXPECT_LT(simulation.state().lambda.cwiseAbs().maxCoeff(), 100.0);
  EXPECT_LT(simulation.state().factorizations, 600);
  EXPECT_EQ(simulation.system().redundantRows().size(), 1u);  // redundant all along
}

TEST(RedundantConstraints, ARowThatIsNotRedundantGoesBackIntoTheSolve) {
  // The four-bar with one of its two in-plane closure rows left out as if
  // the start had been singular: where Newton meets the other rows that row
  // is violated, so it goes back into the solve and the substep is tried
  // again. The motion is then that of all rows: the loop stays closed (the
  // row left out for good opened it by 0.72 m in 0.5 s).
  const Scene scene = exampleScene("four_bar");
  SolverOptions options;
  options.hMax = 1e-3;
  options.rhoInf = 0.8;
  options.tolerance = 1e-10;
  System left(assemble(scene)), all(assemble(scene));
  IntegratorState s;
  s.q = all.model().initialConfiguration;
  s.v = all.model().initialVelocity;
  Triplets jacobian;
  all.constraintJacobian(0.0, s.q, s.v, jacobian);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(all.constraintCount(), all.velocityCount());
  for (const auto& e : jacobian) J(e.row(), e.col()) += e.value();
  std::vector<int> rows = constraintRank(J).redundantRows();
  ASSERT_EQ(rows.size(), 3u);  // planar: the out-of-plane rows
  const int kept = rows[0] == 0 ? (rows[1] == 1 ? 2 : 1) : 0;  // the first row that constrains
  rows.push_back(kept);
  std::sort(rows.begin(), rows.end());
  left.setRedundantRows(rows);
  GeneralizedAlpha stepper(options), reference(options);
  IntegratorState r = s;
  std::string message;
  ASSERT_TRUE(stepper.initialize(left, s, message)) << message;
  ASSERT_TRUE(reference.initialize(all, r, message)) << message;
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(stepper.advance(left, s, 0.01).ok);
    ASSERT_TRUE(reference.advance(all, r, 0.01).ok);
  }
  EXPECT_TRUE(left.redundantRows().empty());
  VectorXd residual, phi;
  left.residual(s.t, s.q, s.v, s.vdot, s.lambda, residual, phi);
  EXPECT_LT(phi.cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((s.q.scalars - r.q.scalars).cwiseAbs().maxCoeff(), 1e-8);
}
