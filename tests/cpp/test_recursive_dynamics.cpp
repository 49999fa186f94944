// The recursive kinematics against finite differences: B (Y = B qdot) and
// Bdot qdot (Ydot at qddot = 0) for a chain through every joint kind, the
// mass matrix against the residual's dependence on qddot (the chain and a
// branched tree).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "rigid/recursive_dynamics.hpp"
#include "system.hpp"

using namespace mfbd;

namespace {

// A chain: ground -revolute- a -prismatic- b -cylindrical- c -universal- d
// -spherical- e -planar- f -fixed- g -free- h, with offset centres of mass.
const char* kChain = R"({
  "format": "mfbd-scene/1", "name": "chain", "gravity": [0, -9.81, 0],
  "bodies": [
    {"name": "a", "mass": 1.0, "inertia": [0.1, 0.2, 0.25], "position": [0.5, 0, 0]},
    {"name": "b", "mass": 2.0, "inertia": [0.2, 0.2, 0.3], "position": [1.0, 0.2, 0], "center_of_mass": [0.1, 0, 0]},
    {"name": "c", "mass": 1.5, "inertia": [0.1, 0.15, 0.2], "position": [1.5, 0.3, 0.1],
     "orientation": {"rotation_vector": [0.2, 0.3, -0.1]}},
    {"name": "d", "mass": 1.0, "inertia": [0.1, 0.1, 0.1], "position": [2.0, 0.3, 0.2]},
    {"name": "e", "mass": 1.2, "inertia": [0.05, 0.1, 0.12], "position": [2.5, 0.1, 0.2]},
    {"name": "f", "mass": 0.8, "inertia": [0.05, 0.05, 0.08], "position": [3.0, 0.0, 0.4]},
    {"name": "g", "mass": 0.5, "inertia": [0.02, 0.03, 0.04], "position": [3.3, 0.0, 0.5]},
    {"name": "h", "mass": 0.7, "inertia": [0.03, 0.04, 0.05], "position": [3.6, 0.2, 0.5]}
  ],
  "joints": [
    {"name": "j1", "type": "revolute", "parent": "ground", "child": "a", "position": [0, 0, 0], "axis": [0, 0, 1]},
    {"name": "j2", "type": "prismatic", "parent": "a", "child": "b", "position": [0.8, 0, 0], "axis": [1, 1, 0]},
    {"name": "j3", "type": "cylindrical", "parent": "b", "child": "c", "position": [1.3, 0.3, 0], "axis": [0, 1, 1]},
    {"name": "j4", "type": "universal", "parent": "c", "child": "d", "position": [1.8, 0.3, 0.1], "axis": [1, 0, 0.3]},
    {"name": "j5", "type": "spherical", "parent": "d", "child": "e", "position": [2.2, 0.2, 0.2]},
    {"name": "j6", "type": "planar", "parent": "e", "child": "f", "position": [2.8, 0.0, 0.3], "axis": [0.2, 1, 0]},
    {"name": "j7", "type": "fixed", "parent": "f", "child": "g", "position": [3.2, 0.0, 0.4]},
    {"name": "j8", "type": "free", "parent": "g", "child": "h", "position": [3.5, 0.1, 0.5]}
  ]
})";

struct Poses {
  std::vector<Vec3> r;
  std::vector<Mat3> A;
};

Poses poses(const Model& model, Data& data, const Configuration& q) {
  const VectorXd zero = VectorXd::Zero(model.velocityCount);
  forwardKinematics(model, data, q, zero, zero);
  Poses p;
  for (const auto& b : data.body) {
    p.r.push_back(b.position);
    p.A.push_back(b.orientation);
  }
  return p;
}

class RecursiveDynamics : public ::testing::Test {
 protected:
  void SetUp() override {
    model = assemble(parseScene(kChain));
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    q = model.initialConfiguration;
    VectorXd dq(model.velocityCount);
    for (int i = 0; i < dq.size(); ++i) dq[i] = 1.2 * u(rng);
    retract(model.blocks, q, dq);
    v.resize(model.velocityCount);
    for (int i = 0; i < v.size(); ++i) v[i] = 2.0 * u(rng);
  }
  Model model;
  Configuration q;
  VectorXd v;
};

}  // namespace

TEST_F(RecursiveDynamics, VelocityTransformationMatchesFiniteDifferences) {
  Data data(model);
  const double eps = 1e-6;
  Configuration qp = q, qm = q;
  retract(model.blocks, qp, eps * v);
  retract(model.blocks, qm, -eps * v);
  const Poses P = poses(model, data, qp), Mi = poses(model, data, qm);
  forwardKinematics(model, data, q, v, VectorXd::Zero(v.size()));
  computeVelocityTransformation(model, data);
  const VectorXd Y = data.velocityTransformation * v;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const Vec3 velocity = (P.r[i] - Mi.r[i]) / (2 * eps);
    const Vec3 omega = unskew(P.A[i] * Mi.A[i].transpose() - Mat3::Identity()) / (2 * eps);
    const double scale = 1.0 + v.norm();
    EXPECT_LT((velocity - data.body[i].velocity).norm(), 1e-7 * scale) << model.bodies[i].name;
    EXPECT_LT((omega - data.body[i].angularVelocity).norm(), 1e-7 * scale) << model.bodies[i].name;
    EXPECT_LT((Y.segment<3>(6 * i) - data.body[i].velocity).norm(), 1e-12 * scale);
    EXPECT_LT((Y.segment<3>(6 * i + 3) - data.body[i].angularVelocity).norm(), 1e-12 * scale);
  }
}

TEST_F(RecursiveDynamics, BdotQdotMatchesFiniteDifferences) {
  // Along q(t) = q o exp(t v) with constant v (qddot = 0): Ydot = Bdot qdot.
  Data data(model), probe(model);
  const VectorXd zero = VectorXd::Zero(v.size());
  const double eps = 1e-5;
  Configuration qp = q, qm = q;
  retract(model.blocks, qp, eps * v);
  retract(model.blocks, qm, -eps * v);
  forwardKinematics(model, data, q, v, zero);
  Data dp(model), dm(model);
  forwardKinematics(model, dp, qp, v, zero);
  forwardKinematics(model, dm, qm, v, zero);
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const Vec3 a = (dp.body[i].velocity - dm.body[i].velocity) / (2 * eps);
    const Vec3 alpha = (dp.body[i].angularVelocity - dm.body[i].angularVelocity) / (2 * eps);
    const double scale = 1.0 + v.squaredNorm();
    EXPECT_LT((a - data.body[i].acceleration).norm(), 1e-7 * scale) << model.bodies[i].name;
    EXPECT_LT((alpha - data.body[i].angularAcceleration).norm(), 1e-7 * scale) << model.bodies[i].name;
  }
}

namespace {

// M (composite rigid bodies) against the residual, which is linear in qddot.
void expectMassMatrixIsTheResidualsSlope(const Model& model, const Configuration& q, const VectorXd& v) {
  System system(model);
  const int n = model.velocityCount;
  VectorXd vdot = VectorXd::Random(n), r0, r1, phi;
  system.residual(0.0, q, v, vdot, VectorXd(), r0, phi);
  Triplets S, G;
  system.tangent(0.0, q, v, vdot, VectorXd(), 1.0, 0.0, 0.0, S, G);
  Eigen::SparseMatrix<double> M(n, n);
  M.setFromTriplets(S.begin(), S.end());
  const Eigen::MatrixXd Md(M);
  for (int i = 0; i < n; ++i) {
    system.residual(0.0, q, v, vdot + VectorXd::Unit(n, i), VectorXd(), r1, phi);
    EXPECT_LT((r1 - r0 - Md.col(i)).norm(), 1e-10 * (1.0 + Md.norm())) << "column " << i;
  }
  EXPECT_LT((Md - Md.transpose()).norm(), 1e-12 * Md.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Md).eigenvalues().minCoeff(), 0.0);
}

// A branched tree: two subtrees on body a, bodies away from the origin.
const char* kTree = R"({
  "format": "mfbd-scene/1", "name": "tree", "gravity": [0, 0, -9.81],
  "bodies": [
    {"name": "a", "mass": 2.0, "inertia": [0.1, 0.2, 0.25], "position": [3.0, 2.0, 1.0]},
    {"name": "b", "mass": 1.0, "inertia": [0.1, 0.1, 0.05], "position": [3.5, 2.5, 1.0], "center_of_mass": [0.1, 0, 0]},
    {"name": "c", "mass": 1.5, "inertia": [0.1, 0.15, 0.2], "position": [2.5, 2.0, 1.5]},
    {"name": "d", "mass": 0.5, "inertia": [0.02, 0.03, 0.04], "position": [2.5, 1.5, 2.0]}
  ],
  "joints": [
    {"name": "ja", "type": "revolute", "parent": "ground", "child": "a", "position": [3, 2, 0], "axis": [0, 0.3, 1]},
    {"name": "jb", "type": "spherical", "parent": "a", "child": "b", "position": [3.3, 2.3, 1.0]},
    {"name": "jc", "type": "prismatic", "parent": "a", "child": "c", "position": [2.8, 2.0, 1.2], "axis": [1, 0, 1]},
    {"name": "jd", "type": "universal", "parent": "c", "child": "d", "position": [2.5, 1.8, 1.8], "axis": [0, 1, 0]}
  ]
})";

}  // namespace

TEST_F(RecursiveDynamics, MassMatrixIsTheResidualsSlopeInAcceleration) {
  expectMassMatrixIsTheResidualsSlope(model, q, v);
}

TEST(RecursiveDynamicsTree, MassMatrixIsTheResidualsSlopeInAcceleration) {
  const Model tree = assemble(parseScene(kTree));
  Configuration q = tree.initialConfiguration;
  retract(tree.blocks, q, VectorXd::LinSpaced(tree.velocityCount, -0.7, 0.9));
  expectMassMatrixIsTheResidualsSlope(tree, q, VectorXd::LinSpaced(tree.velocityCount, 1.5, -0.5));
}
