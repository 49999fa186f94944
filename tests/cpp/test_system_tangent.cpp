// The coupled rigid + flexible System against finite differences of its own
// residual: the iteration blocks dr/dq (along the retraction) and dr/dv, and
// the constraint Jacobian Phi_q, for scenes where joints and force elements
// touch flexible nodes through virtual bodies and flexible body joints; and
// the condition number of the scaled Newton matrix against the step size.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cstdio>
#include <random>

#include "integrator/generalized_alpha.hpp"
#include "scene/scene.hpp"
#include "system.hpp"

using namespace mfbd;

namespace {

// A beam clamped at its root; a rigid hub on a revolute joint to ground drives
// a second beam through a fixed joint (virtual body child of the hub); a
// pendulum hangs from the first beam's tip by a spherical joint (virtual body
// with a free joint); a spring joins the two beams (virtual bodies at both
// ends); a revolute joint joins the second beam's tip to a slider body.
const char* kScene = R"({
  "format": "mfbd-scene/1", "name": "coupled", "gravity": [0, -9.81, 0],
  "bodies": [
    {"name": "hub", "mass": 2.0, "inertia": [0.1, 0.1, 0.2], "position": [0, 2, 0]},
    {"name": "bob", "mass": 1.5, "inertia": [0.01, 0.02, 0.015], "position": [1.1, -0.4, 0.1],
     "center_of_mass": [0.05, -0.1, 0]},
    {"name": "slider", "mass": 0.7, "inertia": [0.01, 0.01, 0.01], "position": [1.2, 2.2, 0.3]}
  ],
  "joints": [
    {"name": "hinge", "type": "revolute", "parent": "ground", "child": "hub", "position": [0, 2, 0], "axis": [0, 0, 1]},
    {"name": "clamp", "type": "fixed", "parent": "hub", "child": {"flexible": "arm", "node": 0}, "position": [0.1, 2, 0]},
    {"name": "hang", "type": "spherical", "parent": {"flexible": "beam", "at": 1.0}, "child": "bob"},
    {"name": "pin", "type": "revolute", "parent": {"flexible": "arm", "node": 3}, "child": "slider",
     "axis": [0, 1, 1]}
  ],
  "flexible_bodies": [
    {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 3, "section_y": [0, 1, 0]},
     "section": {"EA": 1e4, "GAy": 5e3, "GAz": 5e3, "GJ": 20, "EIy": 30, "EIz": 40, "rhoA": 2, "rhoJ": [0.02, 0.01, 0.01]},
     "supports": [{"node": 0, "type": "clamp"}], "damping": 0.01},
    {"name": "arm", "beam": {"start": [0.1, 2, 0], "end": [1.3, 2.2, 0.3], "elements": 3, "section_y": [0, 0, 1]},
     "section": {"EA": 1e4, "GAy": 5e3, "GAz": 5e3, "GJ": 20, "EIy": 30, "EIz": 40, "rhoA": 2, "rhoJ": [0.02, 0.01, 0.01]}}
  ],
  "forces": [
    {"name": "spring", "type": "spring_damper", "body1": {"flexible": "beam", "node": 2}, "point1": [0.6667, 0, 0],
     "body2": {"flexible": "arm", "node": 2}, "point2": [0.9, 2.1333, 0.2], "stiffness": 50, "damping": 3}
  ]
})";

struct Evaluation {
  VectorXd r, phi;
};

Evaluation evaluate(System& s, double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                    const VectorXd& lambda) {
  Evaluation e;
  s.residual(t, q, v, vdot, lambda, e.r, e.phi);
  return e;
}

Eigen::MatrixXd dense(const Triplets& t, int rows, int cols) {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(rows, cols);
  for (const auto& e : t) m(e.row(), e.col()) += e.value();
  return m;
}

// A deformed, moving state away from the design configuration (the
// constraints need not hold for a Jacobian check): coordinates moved by up
// to 0.2, rates and accelerations up to 1, multipliers up to 10.
IntegratorState randomState(const System& system, double t, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random = [&](int size, double scale) {
    VectorXd x(size);
    for (int i = 0; i < size; ++i) x[i] = scale * u(rng);
    return x;
  };
  const int n = system.velocityCount();
  IntegratorState s;
  s.t = t;
  s.q = system.model().initialConfiguration;
  system.retract(s.q, random(n, 0.2));
  s.v = random(n, 1.0);
  s.vdot = random(n, 1.0);
  s.lambda = random(system.constraintCount(), 10.0);
  return s;
}

// Central differences of the residual (r) and constraints (phi) along each
// rate: of the configuration along the retraction (cK != 0: the columns of
// K and Phi_q) or of the rates (cK == 0: the columns of C).
struct Differences {
  Eigen::MatrixXd r, phi;
};

Differences centralDifferences(System& system, const IntegratorState& s, double cK, double eps) {
  const int n = system.velocityCount();
  Differences d{Eigen::MatrixXd(n, n), Eigen::MatrixXd(system.constraintCount(), n)};
  for (int i = 0; i < n; ++i) {
    Configuration qp = s.q, qm = s.q;
    VectorXd vp = s.v, vm = s.v, step = VectorXd::Zero(n);
    step[i] = eps;
    if (cK != 0.0) {
      system.retract(qp, step);
      system.retract(qm, -step);
    } else {
      vp[i] += eps;
      vm[i] -= eps;
    }
    const Evaluation p = evaluate(system, s.t, qp, vp, s.vdot, s.lambda), m = evaluate(system, s.t, qm, vm, s.vdot, s.lambda);
    d.r.col(i) = (p.r - m.r) / (2 * eps);
    d.phi.col(i) = (p.phi - m.phi) / (2 * eps);
  }
  return d;
}

class CoupledSystem : public ::testing::Test {
 protected:
  void SetUp() override {
    Scene scene = parseScene(kScene);
    system = std::make_unique<System>(assemble(scene));
    n = system->velocityCount();
    m = system->constraintCount();
    const IntegratorState s = randomState(*system, t, 7);
    q = s.q, v = s.v, vdot = s.vdot, lambda = s.lambda;
  }

  std::unique_ptr<System> system;
  int n = 0, m = 0;
  Configuration q;
  VectorXd v, vdot, lambda;
  const double t = 0.3;
};

}  // namespace

TEST_F(CoupledSystem, MakesVirtualBodiesAndFlexibleBodyJoints) {
  // clamp: child on a node; hang: parent on a node; pin: parent on a node;
  // spring: both ends. Five welds, 30 rows, plus none from cut joints.
  EXPECT_EQ(system->model().flexibleBodyJoints.size(), 5u);
  EXPECT_EQ(m, 30);
  int virtualBodies = 0;
  for (const Body& b : system->model().bodies) virtualBodies += b.isVirtual ? 1 : 0;
  EXPECT_EQ(virtualBodies, 5);
}

TEST_F(CoupledSystem, DesignConfigurationMeetsTheWelds) {
  VectorXd r, phi;
  system->residual(0.0, system->model().initialConfiguration, VectorXd::Zero(n), VectorXd::Zero(n),
                   VectorXd::Zero(m), r, phi);
  EXPECT_LT(phi.cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(CoupledSystem, StiffnessBlockMatchesFiniteDifferences) {
  Triplets iteration, jacobian;
  system->tangent(t, q, v, vdot, lambda, 0.0, 0.0, 1.0, iteration, jacobian);
  const Eigen::MatrixXd K = dense(iteration, n, n), G = dense(jacobian, m, n);
  const double eps = 1e-6;
  Eigen::MatrixXd Kfd(n, n), Gfd(m, n);
  for (int i = 0; i < n; ++i) {
    Configuration qp = q, qm = q;
    VectorXd d = VectorXd::Zero(n);
    d[i] = eps;
    system->retract(qp, d);
    system->retract(qm, -d);
    const Evaluation p = evaluate(*system, t, qp, v, vdot, lambda), mm = evaluate(*system, t, qm, v, vdot, lambda);
    Kfd.col(i) = (p.r - mm.r) / (2 * eps);
    Gfd.col(i) = (p.phi - mm.phi) / (2 * eps);
  }
  // The rigid block is itself a one-sided difference (eps 1e-7) in the solver.
  EXPECT_LT((K - Kfd).cwiseAbs().maxCoeff(), 1e-5 * Kfd.cwiseAbs().maxCoeff()) << (K - Kfd).cwiseAbs().maxCoeff();
  EXPECT_LT((G - Gfd).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, Gfd.cwiseAbs().maxCoeff()));
}

TEST_F(CoupledSystem, DampingAndMassBlocksMatchFiniteDifferences) {
  Triplets C, M, unused;
  system->tangent(t, q, v, vdot, lambda, 0.0, 1.0, 0.0, C, unused);
  system->tangent(t, q, v, vdot, lambda, 1.0, 0.0, 0.0, M, unused);
  const double eps = 1e-6;
  Eigen::MatrixXd Cfd(n, n), Mfd(n, n);
  for (int i = 0; i < n; ++i) {
    VectorXd vp = v, vm = v, ap = vdot, am = vdot;
    vp[i] += eps;
    vm[i] -= eps;
    ap[i] += eps;
    am[i] -= eps;
    Cfd.col(i) = (evaluate(*system, t, q, vp, vdot, lambda).r - evaluate(*system, t, q, vm, vdot, lambda).r) / (2 * eps);
    Mfd.col(i) = (evaluate(*system, t, q, v, ap, lambda).r - evaluate(*system, t, q, v, am, lambda).r) / (2 * eps);
  }
  EXPECT_LT((dense(C, n, n) - Cfd).cwiseAbs().maxCoeff(), 1e-5 * Cfd.cwiseAbs().maxCoeff());
  EXPECT_LT((dense(M, n, n) - Mfd).cwiseAbs().maxCoeff(), 1e-6 * Mfd.cwiseAbs().maxCoeff());
}

// gamma: d2/dt2 Phi(q(t)) = Phi_q vdot + gamma along a path with velocity v
// and acceleration vdot (q(t) = q o exp(v t + vdot t^2 / 2) to second order).
TEST_F(CoupledSystem, ConstraintAccelerationTermMatchesSecondDifferences) {
  Triplets unused, jacobian;
  system->tangent(t, q, v, vdot, lambda, 0.0, 0.0, 0.0, unused, jacobian);
  const VectorXd predicted = dense(jacobian, m, n) * vdot + system->constraintAccelerationTerm(t, q, v);
  const double h = 1e-4;
  auto phiAt = [&](double s) {
    Configuration qs = q;
    system->retract(qs, v * s + 0.5 * vdot * s * s);
    return evaluate(*system, t, qs, v, vdot, lambda).phi;
  };
  const VectorXd second = (phiAt(h) - 2 * phiAt(0.0) + phiAt(-h)) / (h * h);
  EXPECT_LT((predicted - second).cwiseAbs().maxCoeff(), 1e-4 * std::max(1.0, second.cwiseAbs().maxCoeff()))
      << (predicted - second).cwiseAbs().maxCoeff();
}

// The scaled Newton matrix (docs/design.md 3) stays well conditioned as h -> 0:
// it tends to [M Phi_q^T; Phi_q 0], regular although the virtual bodies are
// massless (their motion is fixed by the welds). Without the scaling the
// stiffness blocks would grow as 1/h^2 against the constraint rows.
TEST(ScaledNewtonMatrix, ConditionNumberStaysBoundedAsTheStepShrinks) {
  Scene scene = parseScene(kScene);
  System system(assemble(scene));
  SolverOptions options;
  GeneralizedAlpha integrator(options);
  IntegratorState state;
  state.q = system.model().initialConfiguration;
  state.v = system.model().initialVelocity;
  std::string message;
  ASSERT_TRUE(integrator.initialize(system, state, message)) << message;
  std::vector<double> condition;
  for (double h : {1e-2, 1e-3, 1e-4, 1e-5, 1e-6}) {
    const Eigen::MatrixXd S(integrator.newtonMatrix(system, state, h));
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(S);
    condition.push_back(svd.singularValues()(0) / svd.singularValues().tail<1>()(0));
    std::printf("h = %.0e: condition number %.3e (size %d)\n", h, condition.back(), int(S.rows()));
  }
  for (double c : condition) EXPECT_LT(c, 10.0 * condition.back());
  EXPECT_LT(condition.back(), 1e9);  // finite: massless virtual bodies do not make it singular
}

// A tree without cut joints or two-body force elements: the rigid tangent is
// emitted only for rates of which one is outboard of the other, and rows only
// over the rates that move their bodies. The dropped entries must really be
// zero: the whole tangent against finite differences, row by row.
TEST(SparseRigidTangent, TreeWithWeldedBeamMatchesFiniteDifferences) {
  const char* scene = R"({
    "format": "mfbd-scene/1", "name": "arm", "gravity": [0, -9.81, 0],
    "bodies": [
      {"name": "upper", "mass": 2.0, "inertia": [0.01, 0.05, 0.05], "position": [0.25, 0, 0]},
      {"name": "hub", "mass": 0.5, "inertia": [0.02, 0.02, 0.03], "position": [0.5, 0, 0]},
      {"name": "payload", "mass": 0.5, "inertia": [2e-4, 3e-4, 4e-4], "position": [1.1, 0, 0.05]},
      {"name": "side", "mass": 1.0, "inertia": [0.01, 0.02, 0.03], "position": [0, -0.3, 0]}
    ],
    "joints": [
      {"name": "shoulder", "type": "revolute", "parent": "ground", "child": "upper", "position": [0, 0, 0]},
      {"name": "elbow", "type": "universal", "parent": "upper", "child": "hub", "position": [0.5, 0, 0],
       "axis": [0.2, 0, 1]},
      {"name": "clamp", "type": "fixed", "parent": "hub", "child": {"flexible": "arm", "node": 0}},
      {"name": "grip", "type": "spherical", "parent": {"flexible": "arm", "node": 3}, "child": "payload"},
      {"name": "swing", "type": "revolute", "parent": "ground", "child": "side", "position": [0, -0.1, 0],
       "axis": [1, 0, 0]}
    ],
    "flexible_bodies": [
      {"name": "arm", "beam": {"start": [0.5, 0, 0], "end": [1.1, 0, 0], "elements": 3, "section_y": [0, 1, 0]},
       "section": {"EA": 1e4, "GAy": 5e3, "GAz": 5e3, "GJ": 20, "EIy": 30, "EIz": 40, "rhoA": 2,
                   "rhoJ": [0.02, 0.01, 0.01]}, "damping": 0.01}
    ]
  })";
  System system(assemble(parseScene(scene)));
  const int n = system.velocityCount(), m = system.constraintCount();
  const double t = 0.2, eps = 1e-6;
  const IntegratorState s = randomState(system, t, 11);
  const Configuration& q = s.q;
  const VectorXd &v = s.v, &vdot = s.vdot, &lambda = s.lambda;
  for (const auto& [cC, cK] : {std::pair{0.0, 1.0}, std::pair{1.0, 0.0}}) {
    Triplets iteration, jacobian;
    system.tangent(t, q, v, vdot, lambda, 0.0, cC, cK, iteration, jacobian);
    const Eigen::MatrixXd S = dense(iteration, n, n), G = dense(jacobian, m, n);
    const Differences fd = centralDifferences(system, s, cK, eps);
    const Eigen::MatrixXd &Sfd = fd.r, &Gfd = fd.phi;
    for (int i = 0; i < n; ++i)
      EXPECT_LT((S - Sfd).row(i).cwiseAbs().maxCoeff(), 1e-5 * std::max(1.0, Sfd.row(i).cwiseAbs().maxCoeff()))
          << "row " << i << (cK != 0.0 ? " of K" : " of C");
    if (cK != 0.0) {
      EXPECT_LT((G - Gfd).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, Gfd.cwiseAbs().maxCoeff()));
    }
  }
  // The side pendulum's rate couples with nothing in the arm's tree.
  Triplets iteration, jacobian;
  system.tangent(t, q, v, vdot, lambda, 1.0, 1.0, 1.0, iteration, jacobian);
  const int side = system.model().joints[findJoint(system.model(), "swing")].velocityOffset;
  const int shoulder = system.model().joints[findJoint(system.model(), "shoulder")].velocityOffset;
  bool coupled = false;
  for (const auto& e : iteration) coupled = coupled || (e.row() == side && e.col() == shoulder);
  EXPECT_FALSE(coupled);
}

// Closed loops on a shallow tree: a chain of three four-bars (R3 with
// N = 3; every crank on its ground pivot, every coupler on its crank's top,
// the couplers' ends on the next cranks cut) with a spring-damper from
// coupler 0 to crank 2 and a bushing from crank 1 to coupler 2. A cut joint
// or force element couples only the rates that move its two bodies, so the
// tangent is banded, and rates that share no row are perturbed together in
// its finite differences; the whole matrix, rows and columns outside the
// band included, against central differences of the residual.
TEST(SparseRigidTangent, LoopsAndForceElementsCoupleOnlyTheRatesOfTheirBodies) {
  std::string bodies, joints;
  for (int i = 0; i <= 3; ++i) {
    const std::string x = std::to_string(i);
    bodies += std::string(i ? ", " : "") + R"({"name": "crank)" + x + R"(", "mass": 1, "inertia": [0.01, 0.09, 0.085],
      "position": [)" + x + R"(, 0.5, 0], "orientation": {"x_axis": [0, 1, 0], "z_axis": [0, 0, 1]}})";
    joints += std::string(i ? ", " : "") + R"({"name": "pivot)" + x + R"(", "type": "revolute", "parent": "ground",
      "child": "crank)" + x + R"(", "position": [)" + x + ", 0, 0]}";
    if (i == 3) continue;
    const std::string next = std::to_string(i + 1);
    bodies += R"(, {"name": "coupler)" + x + R"(", "mass": 1.2, "inertia": [0.02, 0.1, 0.11], "position": [)" + x +
              R"(.5, 1, 0]})";
    joints += R"(, {"name": "top)" + x + R"(", "type": "revolute", "parent": "crank)" + x + R"(", "child": "coupler)" + x +
              R"(", "position": [)" + x + R"(, 1, 0]}, {"name": "end)" + x + R"(", "type": "revolute", "parent": "coupler)" +
              x + R"(", "child": "crank)" + next + R"(", "position": [)" + next + R"(, 1, 0], "cut": true})";
  }
  const std::string loops = R"({"format": "mfbd-scene/1", "name": "loops", "gravity": [0, -9.81, 0], "bodies": [)" +
                            bodies + R"(], "joints": [)" + joints + "]";
  // Loops alone: crank 0's rate and crank 3's share no row, so a tangent
  // costs fewer residuals (one per colour, and the unperturbed one) than
  // one per rate.
  EXPECT_LT(System(assemble(parseScene(loops + "}"))).tangentCost(), 7.0 + 1.0);
  const std::string scene = loops + R"(, "forces": [
      {"name": "spring", "type": "spring_damper", "body1": "coupler0", "point1": [0.3, 1, 0], "body2": "crank2",
       "point2": [2, 0.7, 0], "stiffness": 40, "damping": 2},
      {"name": "bushing", "type": "bushing", "body1": "crank1", "body2": "coupler2", "position": [1.5, 0.8, 0],
       "stiffness": [10, 20, 30, 1, 2, 3], "damping": [0.1, 0.2, 0.3, 0.01, 0.02, 0.03]}]})";
  System system(assemble(parseScene(scene)));
  const int n = system.velocityCount();
  ASSERT_EQ(n, 7);
  ASSERT_EQ(system.constraintCount(), 15);
  const double t = 0.1, eps = 1e-6;
  const IntegratorState s = randomState(system, t, 5);
  for (const auto& [cC, cK] : {std::pair{0.0, 1.0}, std::pair{1.0, 0.0}}) {
    Triplets iteration, jacobian;
    system.tangent(t, s.q, s.v, s.vdot, s.lambda, 0.0, cC, cK, iteration, jacobian);
    const Eigen::MatrixXd S = dense(iteration, n, n);
    const Eigen::MatrixXd Sfd = centralDifferences(system, s, cK, eps).r;
    EXPECT_LT((S - Sfd).cwiseAbs().maxCoeff(), 1e-5 * Sfd.cwiseAbs().maxCoeff())
        << (cK != 0.0 ? "K" : "C") << ":\n" << S << "\n\n" << Sfd;
  }
  // Crank 0 and crank 3 share no loop and no force element.
  Triplets iteration, jacobian;
  system.tangent(t, s.q, s.v, s.vdot, s.lambda, 1.0, 1.0, 1.0, iteration, jacobian);
  const int first = system.model().joints[findJoint(system.model(), "pivot0")].velocityOffset;
  const int last = system.model().joints[findJoint(system.model(), "pivot3")].velocityOffset;
  for (const auto& e : iteration) EXPECT_FALSE(e.row() == first && e.col() == last);
}

// Modified Newton across large rotations (GeneralizedAlpha with
// Dynamics::turnWithRotations): the Newton matrix of a state turned rigidly
// by Q is D S D^T, D the turns of the blocks whose translation rates live in
// a fixed frame (free nodes, free joints), exactly, and the residual turns
// the same way. A floating beam without gravity (the only term that does
// not turn with the system), a bob on a spherical joint at its tip (virtual
// body on a free joint), a spring from a node to the bob (a second one).
TEST(TurnedNewtonMatrix, IsTheMatrixOfTheRigidlyTurnedState) {
  const char* scene = R"({
    "format": "mfbd-scene/1", "name": "floating", "gravity": [0, 0, 0],
    "bodies": [{"name": "bob", "mass": 1.5, "inertia": [0.01, 0.02, 0.015], "position": [1.2, -0.3, 0.1],
                "center_of_mass": [0.05, -0.1, 0]}],
    "joints": [{"name": "hang", "type": "spherical", "parent": {"flexible": "beam", "node": 3}, "child": "bob"}],
    "flexible_bodies": [
      {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0.2, 0], "elements": 3, "section_y": [0, 1, 0]},
       "section": {"EA": 1e4, "GAy": 5e3, "GAz": 5e3, "GJ": 20, "EIy": 30, "EIz": 40, "rhoA": 2,
                   "rhoJ": [0.02, 0.01, 0.01]}, "damping": 0.01}
    ],
    "forces": [{"name": "spring", "type": "spring_damper", "body1": {"flexible": "beam", "node": 1},
                "point1": [0.3333, 0.0667, 0], "body2": "bob", "point2": [1.2, -0.3, 0.1], "stiffness": 50, "damping": 3}]
  })";
  System system(assemble(parseScene(scene)));
  const Model& model = system.model();
  const int n = system.velocityCount(), m = system.constraintCount();
  const IntegratorState a = randomState(system, 0.1, 5);

  // The same state turned by Q about the world origin.
  const Mat3 Q = expSO3(Vec3(0.7, -1.1, 0.4));
  IntegratorState b = a;
  int turned = 0;
  for (const FlexNode& node : model.flexible.nodes) {
    ASSERT_TRUE(node.free);
    auto x = b.q.scalars.segment<3>(node.scalarOffset);
    x = Q * (node.reference.r + x) - node.reference.r;
    b.q.rotations[node.rotation] = Q * b.q.rotations[node.rotation];
    for (VectorXd* rate : {&b.v, &b.vdot}) rate->segment<3>(node.dof[0]) = Q * rate->segment<3>(node.dof[0]);
    ++turned;
  }
  for (const Joint& j : model.joints) {
    if (j.type != JointType::Free) continue;  // relative coordinates of other joints do not change
    ASSERT_EQ(j.parentMarker.body, kGroundIndex);
    const Vec3 p0 = j.parentMarker.position;
    const Mat3 P0 = j.parentMarker.orientation, turnInP0 = P0.transpose() * Q * P0;
    auto d = b.q.scalars.segment<3>(j.scalarOffset);
    d = P0.transpose() * (Q * (p0 + P0 * d) - p0);
    b.q.rotations[j.rotation] = turnInP0 * b.q.rotations[j.rotation];
    for (VectorXd* rate : {&b.v, &b.vdot}) rate->segment<3>(j.velocityOffset) = turnInP0 * rate->segment<3>(j.velocityOffset);
    ++turned;
  }
  EXPECT_EQ(turned, 4 + 2);  // four nodes, two virtual bodies on free joints

  Eigen::MatrixXd D = Eigen::MatrixXd::Identity(n + m, n + m);
  for (int i = 0; i < n; ++i) {
    VectorXd column = VectorXd::Unit(n, i);
    system.turnWithRotations(a.q, b.q, column, false);
    D.block(0, i, n, 1) = column;
  }
  const Evaluation ea = evaluate(system, a.t, a.q, a.v, a.vdot, a.lambda);
  const Evaluation eb = evaluate(system, b.t, b.q, b.v, b.vdot, b.lambda);
  const double rScale = ea.r.cwiseAbs().maxCoeff();
  EXPECT_LT((eb.r - D.topLeftCorner(n, n) * ea.r).cwiseAbs().maxCoeff(), 1e-12 * rScale);
  EXPECT_LT((eb.phi - ea.phi).cwiseAbs().maxCoeff(), 1e-12);

  SolverOptions options;
  GeneralizedAlpha integrator(options);
  const Eigen::MatrixXd Sa(integrator.newtonMatrix(system, a, 1e-3)), Sb(integrator.newtonMatrix(system, b, 1e-3));
  const double scale = Sa.cwiseAbs().maxCoeff();
  // (To the finite differences of the rigid joint-space tangent: 2e-10 of
  // the scale; the flexible blocks are analytic and turn to round-off.)
  EXPECT_LT((Sb - D * Sa * D.transpose()).cwiseAbs().maxCoeff(), 1e-8 * scale);
  const int rigid = model.rigidVelocityCount;
  EXPECT_LT((Sb - D * Sa * D.transpose()).block(rigid, rigid, n - rigid, n - rigid).cwiseAbs().maxCoeff(),
            1e-12 * scale);
  // Not trivially: the matrix itself changes with the turn by O(1).
  EXPECT_GT((Sb - Sa).cwiseAbs().maxCoeff(), 0.1 * scale);
}

// The predictor's turn (Dynamics::turnOverStep): a floating beam spinning
// rigidly at a constant rate omega about an axis through the origin has the
// centripetal accelerations omega x (omega x r) at its nodes; after h they
// are those of the nodes turned by exp(h omega), which the turn gives exactly.
TEST(TurnedPredictor, TurnsCentripetalAccelerationsWithASpinningBody) {
  const char* scene = R"({
    "format": "mfbd-scene/1", "name": "spinning", "gravity": [0, 0, 0],
    "flexible_bodies": [
      {"name": "beam", "beam": {"start": [0.2, 0.1, 0], "end": [1, 0.3, 0.2], "elements": 3, "section_y": [0, 1, 0]},
       "section": {"EA": 1e4, "GJ": 20, "EIy": 30, "EIz": 40, "rhoA": 2, "rhoJ": [0.02, 0.01, 0.01]}}
    ]
  })";
  System system(assemble(parseScene(scene)));
  const Model& model = system.model();
  const Vec3 omega(0.3, -0.5, 2.0);
  const double h = 0.05;
  // The state turned by Q about the origin, spinning at omega (world).
  auto spinning = [&](const Mat3& Q, Configuration& q, VectorXd& v, VectorXd& vdot) {
    q = model.initialConfiguration;
    v = VectorXd::Zero(system.velocityCount());
    vdot = v;
    for (const FlexNode& node : model.flexible.nodes) {
      const Vec3 r = Q * node.reference.r;
      q.scalars.segment<3>(node.scalarOffset) = r - node.reference.r;
      q.rotations[node.rotation] = Q * q.rotations[node.rotation];
      v.segment<3>(node.dof[0]) = omega.cross(r);
      v.segment<3>(node.dof[3]) = q.rotations[node.rotation].transpose() * omega;
      vdot.segment<3>(node.dof[0]) = omega.cross(omega.cross(r));
    }
  };
  Configuration q0, q1;
  VectorXd v0, vdot0, v1, vdot1;
  spinning(Mat3::Identity(), q0, v0, vdot0);
  spinning(expSO3(h * omega), q1, v1, vdot1);
  VectorXd predicted = vdot0;
  system.turnOverStep(q0, v0, h, predicted);
  EXPECT_GT((vdot1 - vdot0).cwiseAbs().maxCoeff(), 0.05);  // the accelerations do turn
  EXPECT_LT((predicted - vdot1).cwiseAbs().maxCoeff(), 1e-13);
}

// A stage of an explicit method on a small tree takes M^-1 Q from the dense
// joint-space mass matrix: the residual vanishes at those accelerations (to
// round-off of M's size), on a 3D tree of revolute, spherical, prismatic,
// universal and free joints with damping and a spring, at a moved state; a system with constraints or flexible bodies
// leaves it to the iteration matrix.
TEST(UnconstrainedAccelerations, MakeTheTreesResidualVanish) {
  const std::string tree = R"({
    "format": "mfbd-scene/1", "name": "tree", "gravity": [0, 0, -9.81],
    "bodies": [
      {"name": "a", "mass": 2.0, "inertia": [0.1, 0.2, 0.25], "position": [3.0, 2.0, 1.0]},
      {"name": "b", "mass": 1.0, "inertia": [0.1, 0.1, 0.05], "position": [3.5, 2.5, 1.0], "center_of_mass": [0.1, 0, 0]},
      {"name": "c", "mass": 1.5, "inertia": [0.1, 0.15, 0.2], "position": [2.5, 2.0, 1.5]},
      {"name": "d", "mass": 0.5, "inertia": [0.02, 0.03, 0.04], "position": [2.5, 1.5, 2.0]},
      {"name": "e", "mass": 0.8, "inertia": [0.03, 0.02, 0.04], "position": [4.0, 1.0, 0.5]}
    ],
    "joints": [
      {"name": "ja", "type": "revolute", "parent": "ground", "child": "a", "position": [3, 2, 0], "axis": [0, 0.3, 1],
       "damping": 0.4},
      {"name": "jb", "type": "spherical", "parent": "a", "child": "b", "position": [3.3, 2.3, 1.0]},
      {"name": "jc", "type": "prismatic", "parent": "a", "child": "c", "position": [2.8, 2.0, 1.2], "axis": [1, 0, 1]},
      {"name": "jd", "type": "universal", "parent": "c", "child": "d", "position": [2.5, 1.8, 1.8], "axis": [0, 1, 0]},
      {"name": "je", "type": "free", "parent": "ground", "child": "e", "position": [4.0, 1.0, 0.5]}
    ],
    "forces": [{"name": "spring", "type": "spring_damper", "body1": "b", "point1": [3.5, 2.5, 1.0], "body2": "e",
                "point2": [4.0, 1.0, 0.5], "stiffness": 30, "damping": 1.5}]
  })";
  System system(assemble(parseScene(tree)));
  const int n = system.velocityCount();
  ASSERT_EQ(system.constraintCount(), 0);
  Configuration q = system.model().initialConfiguration;
  system.retract(q, VectorXd::LinSpaced(n, -0.7, 0.9));
  const VectorXd v = VectorXd::LinSpaced(n, 1.5, -0.5);
  VectorXd vdot, r, phi;
  ASSERT_TRUE(system.unconstrainedAccelerations(0.3, q, v, vdot));
  ASSERT_EQ(vdot.size(), n);
  system.residual(0.3, q, v, VectorXd::Zero(n), VectorXd(), r, phi);
  const double forces = r.cwiseAbs().maxCoeff();
  EXPECT_GT(vdot.cwiseAbs().maxCoeff(), 1.0);  // the state is far from rest
  system.residual(0.3, q, v, vdot, VectorXd(), r, phi);
  EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-12 * forces) << r.transpose();

  System loop(assemble(parseScene(R"({
    "format": "mfbd-scene/1", "name": "loop", "gravity": [0, -9.81, 0],
    "bodies": [{"name": "a", "mass": 1, "inertia": [0.1, 0.1, 0.1], "position": [0, 1, 0]}],
    "joints": [{"name": "p", "type": "revolute", "parent": "ground", "child": "a", "position": [0, 0, 0]},
               {"name": "c", "type": "spherical", "parent": "ground", "child": "a", "position": [0, 2, 0],
                "cut": true}]})")));
  EXPECT_FALSE(loop.unconstrainedAccelerations(0.0, loop.model().initialConfiguration,
                                               VectorXd::Zero(loop.velocityCount()), vdot));
  System coupled(assemble(parseScene(kScene)));
  EXPECT_FALSE(coupled.unconstrainedAccelerations(0.0, coupled.model().initialConfiguration,
                                                  VectorXd::Zero(coupled.velocityCount()), vdot));
}
