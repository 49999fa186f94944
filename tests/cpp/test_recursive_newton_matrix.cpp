// The recursive form of the Newton matrix (System::recursiveTangent): body
// velocity and wrench variations as auxiliary unknowns, eliminated leaf to
// root. Its Schur complement onto the joint rates must be the joint-space
// matrix where the form claims to be exact (the mass block, always; damping
// and stiffness where the variation of B has nothing to act on), the pivot
// order must not change a solve, and a run must reach the joint-space
// answer with about as many Newton iterations.
#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include "integrator/time_stepper.hpp"
#include "scene/scene.hpp"
#include "simulation.hpp"
#include "system.hpp"

using namespace mfbd;

namespace {

// The integrator's matrix assembly, for the tests.
struct Stepper : TimeStepper {
  using TimeStepper::TimeStepper;
  using TimeStepper::iterationMatrix;
  // The Newton matrix without the multipliers' regularisation.
  static SparseMatrix exact(Dynamics& system, const IntegratorState& at, double cM, double cC, double cK) {
    return unregularized(system, iterationMatrix(system, at, cM, cC, cK));
  }
  using TimeStepper::newtonSize;
  using TimeStepper::pivotOrder;
  bool initialize(Dynamics&, IntegratorState&, std::string&) override { return true; }
  bool substep(Dynamics&, IntegratorState&, double, std::string&) override { return true; }
};

std::string withNewtonMatrix(std::string scene, const std::string& form) {
  const std::string key = "\"name\": ";
  scene.insert(scene.find(key), "\"solver\": {\"newton_matrix\": \"" + form + "\"}, ");
  return scene;
}

// A branched tree of every joint kind with a closed loop (cut joint), joint
// springs and dampers, a spring-damper and a bushing between bodies; no
// gravity and every force element at rest in the design configuration.
const char* kTree = R"({
  "format": "mfbd-scene/1", "name": "tree",
  "bodies": [
    {"name": "a", "mass": 2.0, "inertia": [0.1, 0.2, 0.3], "position": [0, 0, 0]},
    {"name": "b", "mass": 1.0, "inertia": [0.05, 0.04, 0.03], "position": [1, 0, 0], "center_of_mass": [0.1, 0.05, 0]},
    {"name": "c", "mass": 0.5, "inertia": [0.01, 0.02, 0.02], "position": [1.5, 0.5, 0.2]},
    {"name": "d", "mass": 1.5, "inertia": [0.03, 0.03, 0.05], "position": [0, -1, 0]},
    {"name": "e", "mass": 0.8, "inertia": [0.02, 0.01, 0.02], "position": [0.5, -1.5, 0.3]},
    {"name": "f", "mass": 0.6, "inertia": [0.02, 0.02, 0.01], "position": [1, -1, 0.5]}
  ],
  "joints": [
    {"name": "root", "type": "revolute", "parent": "ground", "child": "a", "position": [0, 0, 0], "axis": [0, 0.3, 1],
     "damping": 0.4},
    {"name": "ab", "type": "universal", "parent": "a", "child": "b", "position": [0.5, 0, 0], "axis": [1, 0, 0]},
    {"name": "bc", "type": "spherical", "parent": "b", "child": "c", "position": [1.2, 0.3, 0.1]},
    {"name": "ad", "type": "prismatic", "parent": "a", "child": "d", "position": [0, -0.5, 0], "axis": [0, 1, 0.2],
     "damping": 1.5},
    {"name": "de", "type": "cylindrical", "parent": "d", "child": "e", "position": [0.2, -1.2, 0.1], "axis": [1, 0, 0]},
    {"name": "ef", "type": "free", "parent": "e", "child": "f", "position": [1, -1, 0.5]}
  ],
  "forces": [
    {"name": "spring", "type": "spring_damper", "body1": "b", "point1": [1, 0, 0], "body2": "d", "point2": [1, -1, 0],
     "stiffness": 300, "damping": 4, "free_length": 1},
    {"name": "mount", "type": "bushing", "body1": "c", "body2": "f", "position": [1.2, -0.3, 0.4],
     "stiffness": [500, 400, 300, 20, 30, 40], "damping": [5, 4, 3, 0.2, 0.3, 0.4]},
    {"name": "hold", "type": "bushing", "body1": "ground", "body2": "f", "position": [1, -1, 0.5],
     "stiffness": [100, 100, 100, 10, 10, 10]},
    {"name": "twist", "type": "rotational_spring_damper", "joint": "root", "stiffness": 50, "damping": 0.7}
  ]
})";

// The same tree closed by a revolute cut joint between c and e.
std::string closedTree() {
  std::string s = kTree;
  const std::string last = R"({"name": "ef", "type": "free", "parent": "e", "child": "f", "position": [1, -1, 0.5]})";
  s.replace(s.find(last), last.size(),
            last + R"(, {"name": "loop", "type": "spherical", "parent": "c", "child": "e", "position": [1, -0.5, 0.3],
                         "cut": true})");
  return s;
}

// Rigid and flexible: a clamped beam carries a two-body pendulum from its
// tip (the revolute joint's parent is a virtual body on a free joint) and a
// spring from its middle node to the lower body (a second virtual body).
const char* kCoupled = R"({
  "format": "mfbd-scene/1", "name": "coupled", "gravity": [0, -9.81, 0],
  "bodies": [
    {"name": "upper", "mass": 1.0, "inertia": [0.01, 0.08, 0.08], "position": [1.0, -0.5, 0]},
    {"name": "lower", "mass": 0.7, "inertia": [0.01, 0.05, 0.05], "position": [1.0, -1.4, 0.1]}
  ],
  "joints": [
    {"name": "tip", "type": "revolute", "parent": {"flexible": "beam", "node": 4}, "child": "upper",
     "axis": [1, 0, 0]},
    {"name": "knee", "type": "universal", "parent": "upper", "child": "lower", "position": [1.0, -1.0, 0],
     "axis": [0, 0, 1]}
  ],
  "flexible_bodies": [
    {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 4, "section_y": [0, 1, 0]},
     "section": {"EA": 1e4, "GAy": 5e3, "GAz": 5e3, "GJ": 20, "EIy": 30, "EIz": 40, "rhoA": 2, "rhoJ": [0.02, 0.01, 0.01]},
     "supports": [{"node": 0, "type": "clamp"}]}
  ],
  "forces": [
    {"name": "spring", "type": "spring_damper", "body1": {"flexible": "beam", "node": 2}, "point1": [0.5, 0, 0],
     "body2": "lower", "point2": [1.0, -1.4, 0.1], "stiffness": 80, "damping": 2}
  ]
})";

Eigen::MatrixXd denseMatrix(const SparseMatrix& A) { return Eigen::MatrixXd(A); }

// Schur complement of the Newton matrix onto its first k unknowns.
Eigen::MatrixXd schurComplement(const Eigen::MatrixXd& A, int k) {
  const int a = int(A.rows()) - k;
  if (a == 0) return A;
  return A.topLeftCorner(k, k) -
         A.topRightCorner(k, a) * A.bottomRightCorner(a, a).partialPivLu().solve(A.bottomLeftCorner(a, k));
}

IntegratorState stateOf(const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda) {
  IntegratorState st;
  st.t = 0.1;
  st.q = q;
  st.v = v;
  st.vdot = vdot;
  st.lambda = lambda;
  return st;
}

// cC C + cK K over the joint rates as the Newton matrix holds it: the Schur
// complement onto velocities and multipliers, less its mass block.
Eigen::MatrixXd jointRateBlock(System& s, const IntegratorState& st, double cC, double cK) {
  const int k = s.velocityCount() + s.constraintCount();
  const Eigen::MatrixXd all = schurComplement(denseMatrix(Stepper::exact(s, st, 1, cC, cK)), k);
  const Eigen::MatrixXd mass = schurComplement(denseMatrix(Stepper::exact(s, st, 1, 0, 0)), k);
  return (all - mass).topLeftCorner(s.velocityCount(), s.velocityCount());
}

}  // namespace

TEST(RecursiveNewtonMatrix, PivotOrderLeavesTheSolutionUnchanged) {
  // A random sparse matrix with a strong diagonal; the order reverses the
  // first half and pairs rows with shifted columns.
  const int n = 80;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Triplets t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 8.0 + u(rng));
    for (int k = 0; k < 3; ++k) t.emplace_back(i, std::uniform_int_distribution<int>(0, n - 1)(rng), u(rng));
  }
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = u(rng);
  std::vector<std::pair<int, int>> order;
  for (int i = n / 2 - 1; i >= 0; --i) order.emplace_back(i, i);
  LinearSolver plain, ordered;
  plain.analyzePattern(A);
  ordered.analyzePattern(A, order);
  ASSERT_EQ(plain.factorize(A), LinearSolver::Status::Ok);
  ASSERT_EQ(ordered.factorize(A), LinearSolver::Status::Ok);
  const Eigen::VectorXd x = ordered.solve(b);
  EXPECT_LT((x - plain.solve(b)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((Eigen::MatrixXd(A) * x - b).cwiseAbs().maxCoeff(), 1e-12);
  // A copy (state saving) re-analyses with the same order.
  LinearSolver copy = ordered;
  ASSERT_EQ(copy.factorize(A), LinearSolver::Status::Ok);
  EXPECT_LT((copy.solve(b) - x).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(RecursiveNewtonMatrix, MassBlockIsTheJointSpaceMassMatrix) {
  // cM = 1, cC = cK = 0: the Schur complement onto velocities and
  // multipliers equals [B^T M B, Phi_q^T; Phi_q, -eps] of the joint space,
  // for the closed tree and for the coupled rigid + flexible scene with
  // massless virtual bodies, at a random state.
  for (const std::string& scene : {closedTree(), std::string(kCoupled)}) {
    System joint(assemble(parseScene(withNewtonMatrix(scene, "joint_space"))));
    System recursive(assemble(parseScene(withNewtonMatrix(scene, "recursive"))));
    ASSERT_FALSE(joint.recursiveNewtonMatrix());
    ASSERT_TRUE(recursive.recursiveNewtonMatrix());
    const int n = joint.velocityCount(), m = joint.constraintCount();
    const int bodies = int(joint.model().bodies.size());
    EXPECT_EQ(m, scene == kCoupled ? 12 : 3);  // two welds; one spherical cut joint
    EXPECT_EQ(recursive.auxiliaryCount(1.0), 18 * bodies);
    EXPECT_EQ(recursive.auxiliaryCount(0.0), 0);  // statics: joint space
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    VectorXd dq(n), v(n), vdot(n), lambda(m);
    for (int i = 0; i < n; ++i) dq[i] = 0.3 * u(rng), v[i] = u(rng), vdot[i] = u(rng);
    for (int i = 0; i < m; ++i) lambda[i] = 10.0 * u(rng);
    Configuration q = joint.model().initialConfiguration;
    joint.retract(q, dq);
    // Unregularised: the -eps I of the constraint block scales with each
    // form's own diagonal.
    const Eigen::MatrixXd J =
        denseMatrix(Stepper::exact(joint, stateOf(q, v, vdot, lambda), 1, 0, 0));
    const Eigen::MatrixXd R =
        denseMatrix(Stepper::exact(recursive, stateOf(q, v, vdot, lambda), 1, 0, 0));
    ASSERT_EQ(R.rows(), n + m + 18 * bodies);
    const Eigen::MatrixXd S = schurComplement(R, n + m);
    EXPECT_LT((S - J).cwiseAbs().maxCoeff(), 1e-10 * J.cwiseAbs().maxCoeff());
  }
}

TEST(RecursiveNewtonMatrix, DampingBlockIsTheJointSpaceOneAtAnyState) {
  // The velocity derivatives (Coriolis and centripetal terms through the
  // acceleration recursion, gyroscopic terms, dampers of joints and force
  // elements) are all there: the cC block of the Schur complement equals
  // the joint space's finite-difference dr/dv at a random moving state,
  // for the closed tree and the coupled scene.
  for (const std::string& scene : {std::string(kTree), closedTree(), std::string(kCoupled)}) {
    SCOPED_TRACE(scene.size());
    System joint(assemble(parseScene(withNewtonMatrix(scene, "joint_space"))));
    System recursive(assemble(parseScene(withNewtonMatrix(scene, "recursive"))));
    const int n = joint.velocityCount(), m = joint.constraintCount();
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    VectorXd dq(n), v(n), vdot(n), lambda(m);
    for (int i = 0; i < n; ++i) dq[i] = 0.3 * u(rng), v[i] = 2.0 * u(rng), vdot[i] = u(rng);
    for (int i = 0; i < m; ++i) lambda[i] = 10.0 * u(rng);
    Configuration q = joint.model().initialConfiguration;
    joint.retract(q, dq);
    const IntegratorState st = stateOf(q, v, vdot, lambda);
    const Eigen::MatrixXd C = jointRateBlock(joint, st, 1.0, 0.0), Cr = jointRateBlock(recursive, st, 1.0, 0.0);
    EXPECT_GT(C.cwiseAbs().maxCoeff(), 1.0);
    EXPECT_LT((Cr - C).cwiseAbs().maxCoeff(), 1e-6 * C.cwiseAbs().maxCoeff()) << (Cr - C).cwiseAbs().maxCoeff();
  }
}

TEST(RecursiveNewtonMatrix, StiffnessBlockIsTheJointSpaceOneWhereNothingAccelerates) {
  // At rest (v = 0, vdot = 0) but loaded (gravity, stretched springs and
  // bushings at a random configuration, random multipliers) the terms left
  // out (the turning of S and T acting on accelerations) vanish; what B's
  // variation does to the transmitted wrenches (a loaded chain's string
  // stiffness) is in: the cK block equals the joint space's FD dr/dq.
  for (const std::string& scene : {closedTree(), std::string(kCoupled)}) {
    SCOPED_TRACE(scene.size());
    std::string loaded = scene;
    if (loaded.find("\"gravity\"") == std::string::npos)
      loaded.insert(loaded.find("\"name\": "), "\"gravity\": [0, -9.81, 0], ");
    System joint(assemble(parseScene(withNewtonMatrix(loaded, "joint_space"))));
    System recursive(assemble(parseScene(withNewtonMatrix(loaded, "recursive"))));
    const int n = joint.velocityCount(), m = joint.constraintCount();
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    VectorXd dq(n), lambda(m);
    for (int i = 0; i < n; ++i) dq[i] = 0.3 * u(rng);
    for (int i = 0; i < m; ++i) lambda[i] = 10.0 * u(rng);
    Configuration q = joint.model().initialConfiguration;
    joint.retract(q, dq);
    const VectorXd zero = VectorXd::Zero(n);
    const IntegratorState st = stateOf(q, zero, zero, lambda);
    const Eigen::MatrixXd K = jointRateBlock(joint, st, 0.0, 1.0), Kr = jointRateBlock(recursive, st, 0.0, 1.0);
    EXPECT_GT(K.cwiseAbs().maxCoeff(), 1.0);
    EXPECT_LT((Kr - K).cwiseAbs().maxCoeff(), 1e-5 * K.cwiseAbs().maxCoeff()) << (Kr - K).cwiseAbs().maxCoeff();
  }
}

TEST(RecursiveNewtonMatrix, CutJointsLeaveTheJointForcesOfTreeJointsAlone) {
  // Found by the test above: a cut joint (no rates of its own, offset 0)
  // overwrote the joint forces of the first tree joints with zero, so joint
  // damping, rotational springs and torque inputs there were lost in every
  // closed-loop scene. With zero multipliers, closing the loop must not
  // change dr/dv (the root's damping 0.4 + 0.7 N m s).
  System open(assemble(parseScene(kTree))), closed(assemble(parseScene(closedTree())));
  const int n = open.velocityCount();
  ASSERT_EQ(closed.velocityCount(), n);
  const Configuration q = open.model().initialConfiguration;
  VectorXd v = VectorXd::Constant(n, 0.5), vdot = VectorXd::Zero(n), r0, r1, s0, s1, phi;
  const double eps = 1e-6;
  open.residual(0.0, q, v, vdot, VectorXd(), r0, phi);
  closed.residual(0.0, q, v, vdot, VectorXd::Zero(closed.constraintCount()), s0, phi);
  v[0] += eps;
  open.residual(0.0, q, v, vdot, VectorXd(), r1, phi);
  closed.residual(0.0, q, v, vdot, VectorXd::Zero(closed.constraintCount()), s1, phi);
  EXPECT_LT(((s1 - s0) - (r1 - r0)).cwiseAbs().maxCoeff() / eps, 1e-6);
  EXPECT_LT((s0 - r0).cwiseAbs().maxCoeff(), 1e-12);  // and the forces themselves
}

TEST(RecursiveNewtonMatrix, DampingAndStiffnessMatchTheJointSpaceWhereBIsNotLoaded) {
  // At rest in the design configuration with no gravity every body force is
  // zero, so the terms the recursive form leaves out (the variation of B
  // acting on transmitted wrenches, Coriolis terms) vanish: its Schur
  // complement must equal the joint space's finite-difference tangent.
  System joint(assemble(parseScene(withNewtonMatrix(kTree, "joint_space"))));
  System recursive(assemble(parseScene(withNewtonMatrix(kTree, "recursive"))));
  const int n = joint.velocityCount();
  const Configuration q = joint.model().initialConfiguration;
  const VectorXd zero = VectorXd::Zero(n);
  VectorXd r, phi;
  joint.residual(0.0, q, zero, zero, VectorXd(), r, phi);
  ASSERT_LT(r.cwiseAbs().maxCoeff(), 1e-12);  // at rest indeed
  for (const auto& [cC, cK] : {std::pair{1.0, 0.0}, std::pair{0.0, 1.0}, std::pair{0.3, 0.05}}) {
    const Eigen::MatrixXd J = denseMatrix(Stepper::iterationMatrix(joint, stateOf(q, zero, zero, VectorXd()),
                                                                   1.0, cC, cK));
    const Eigen::MatrixXd S = schurComplement(
        denseMatrix(Stepper::iterationMatrix(recursive, stateOf(q, zero, zero, VectorXd()), 1.0, cC, cK)),
        n);
    // Both hold finite differences (step 1e-7): agreement to ~1e-6.
    EXPECT_LT((S - J).cwiseAbs().maxCoeff(), 1e-6 * J.cwiseAbs().maxCoeff()) << "cC " << cC << " cK " << cK;
    // And the blocks are really there: without them the difference is O(1).
    const Eigen::MatrixXd M = denseMatrix(Stepper::iterationMatrix(joint, stateOf(q, zero, zero, VectorXd()),
                                                                   1.0, 0.0, 0.0));
    EXPECT_GT((J - M).cwiseAbs().maxCoeff(), 1e-2 * J.cwiseAbs().maxCoeff());
  }
}

TEST(RecursiveNewtonMatrix, ChainRunReachesTheJointSpaceAnswer) {
  // A 90-bar pendulum chain released from horizontal (automatic choice: the
  // recursive form) against the joint-space form over 0.5 s: the same
  // motion to the Newton tolerance's accumulation, with at most 30 % more
  // Newton iterations (the neglected terms are O(h omega)), and no
  // rejected substep.
  const int n = 90;
  std::ostringstream s;
  s.precision(17);
  s << R"({"format": "mfbd-scene/1", "name": "chain", "gravity": [0, -9.81, 0], "bodies": [)";
  for (int i = 0; i < n; ++i)
    s << (i ? ", " : "") << R"({"name": "bar)" << i << R"(", "mass": 1, "inertia": [0, 0.0833333333, 0.0833333333],)"
      << R"( "position": [)" << i + 0.5 << ", 0, 0]}";
  s << R"(], "joints": [)";
  for (int i = 0; i < n; ++i)
    s << (i ? ", " : "") << R"({"name": "hinge)" << i << R"(", "type": "revolute", "parent": ")"
      << (i ? "bar" + std::to_string(i - 1) : std::string("ground")) << R"(", "child": "bar)" << i
      << R"(", "position": [)" << i << ", 0, 0]}";
  s << "]}";
  Simulation automatic(parseScene(s.str()));
  Simulation joint(parseScene(withNewtonMatrix(s.str(), "joint_space")));
  ASSERT_TRUE(automatic.system().recursiveNewtonMatrix());
  ASSERT_FALSE(joint.system().recursiveNewtonMatrix());
  std::string message;
  ASSERT_TRUE(automatic.initialize(0.0, message)) << message;
  ASSERT_TRUE(joint.initialize(0.0, message)) << message;
  // Consistent accelerations come from the mass block alone: the same to
  // the round-off of two factorizations of a chain's ill-conditioned mass
  // matrix (measured 1.5e-10 relative).
  const double vdotScale = joint.state().vdot.cwiseAbs().maxCoeff();
  EXPECT_LT((automatic.state().vdot - joint.state().vdot).cwiseAbs().maxCoeff(), 1e-9 * vdotScale) << vdotScale;
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(automatic.doStep(0.01).ok);
    ASSERT_TRUE(joint.doStep(0.01).ok);
  }
  const IntegratorState &a = automatic.state(), &b = joint.state();
  EXPECT_LT((a.q.scalars - b.q.scalars).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((a.v - b.v).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_EQ(a.rejectedSubsteps, 0);
  EXPECT_LT(double(a.newtonIterations), 1.3 * double(b.newtonIterations))
      << a.newtonIterations << " vs " << b.newtonIterations;
  std::printf("Newton iterations over 500 substeps: recursive %ld, joint space %ld\n", a.newtonIterations,
              b.newtonIterations);
}

TEST(RecursiveNewtonMatrix, BodyInertiaBlockMatchesFiniteDifferences) {
  // The rotary part of a body's block H: cM J + cC d(w x J w)/dw +
  // cK d(J alpha + w x J w)/dphi (J = A J0 A^T turned by dphi), against
  // central differences of that torque, for a tumbling free body.
  const char* scene = R"({"format": "mfbd-scene/1", "name": "tumbler", "solver": {"newton_matrix": "recursive"},
    "bodies": [{"name": "box", "mass": 2.0, "inertia": [0.2, 0.25, 0.4], "position": [0, 0, 0]}],
    "joints": [{"name": "float", "type": "free", "parent": "ground", "child": "box", "position": [0, 0, 0]}]})";
  System system(assemble(parseScene(scene)));
  const int n = system.velocityCount();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VectorXd dq(n), v(n), vdot(n);
  for (int i = 0; i < n; ++i) dq[i] = u(rng), v[i] = 3.0 * u(rng), vdot[i] = 5.0 * u(rng);
  Configuration q = system.model().initialConfiguration;
  system.retract(q, dq);
  VectorXd r, phi;
  system.residual(0.0, q, v, vdot, VectorXd(), r, phi);  // the body's kinematics into data()
  const BodyKinematics k = system.data().body[0];
  const Mat3 J0 = system.model().bodies[0].inertia;
  auto torque = [&](const Mat3& A, const Vec3& w) {
    const Mat3 J = A * J0 * A.transpose();
    return Vec3(J * k.angularAcceleration + w.cross(J * w));
  };
  Mat3 C, K;
  const double eps = 1e-6;
  for (int d = 0; d < 3; ++d) {
    const Vec3 e = eps * Vec3::Unit(d);
    C.col(d) = (torque(k.orientation, k.angularVelocity + e) - torque(k.orientation, k.angularVelocity - e)) / (2 * eps);
    K.col(d) = (torque(expSO3(e) * k.orientation, k.angularVelocity) -
                torque(expSO3(-e) * k.orientation, k.angularVelocity)) / (2 * eps);
  }
  const Mat3 J = k.orientation * J0 * k.orientation.transpose();
  const double cM = 1.0, cC = 0.7, cK = 0.3;
  const Eigen::MatrixXd R =
      denseMatrix(Stepper::exact(system, stateOf(q, v, vdot, VectorXd()), cM, cC, cK));
  // Body 0's rotary rows: cM J on its acceleration (columns n + 12 + 3..),
  // the rest on its pose and velocity (columns n + 3..).
  const Mat3 block = R.block<3, 3>(n + 3, n + 3) + R.block<3, 3>(n + 3, n + 12 + 3);
  const Mat3 expected = cM * J + cC * C + cK * K;
  EXPECT_LT((block - expected).cwiseAbs().maxCoeff(), 1e-8 * expected.cwiseAbs().maxCoeff())
      << block << "\n\n" << expected;
  EXPECT_GT(C.cwiseAbs().maxCoeff(), 0.1);  // a real gyroscopic and turning part
  EXPECT_GT(K.cwiseAbs().maxCoeff(), 0.1);
}
