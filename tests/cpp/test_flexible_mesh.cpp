// The flexible mesh as the integrator sees it (System over a scene with a
// flexible body): the iteration-matrix blocks M, C, K that flexibleTangent
// assembles against central finite differences of flexibleResidual, with
// consistent and with lumped element mass; the consistent mass itself; and
// the bending frequencies each mass gives.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "flex/consistent_mass.hpp"
#include "model/model.hpp"
#include "scene/scene.hpp"
#include "system.hpp"

using namespace mfbd;

namespace {

// A bent, spinning three-element beam: pinned at node 0, node 3 sliding
// along y, a follower and a dead load, a point mass, damping, gravity.
std::string meshScene(const std::string& mass) {
  return R"json({
  "format": "mfbd-scene/1", "name": "mesh", "gravity": [0.3, -9.81, 1.2],
  "flexible_bodies": [{
    "name": "beam", "mass": ")json" + mass + R"json(",
    "beam": {"start": [0, 0, 0], "end": [1.5, 0.2, -0.1], "elements": 3, "section_y": [0, 0.3, 1]},
    "section": {"EA": 100, "GAy": 60, "GAz": 40, "GJ": 0.8, "EIy": 1.5, "EIz": 2.5, "rhoA": 2.0,
                "rhoJ": [0.03, 0.01, 0.02]},
    "damping": 0.05,
    "supports": [{"node": 0, "type": "pin"}, {"node": 3, "type": "slide", "direction": [0, 1, 0]}],
    "point_masses": [{"node": 2, "mass": 0.7, "inertia": [0.01, 0.02, 0.03]}],
    "loads": [{"node": 2, "force": [0.1, 0.4, -0.2], "moment": [0.05, 0, 0.1], "follower": true},
              {"node": 1, "force": [0, 0, 0.3], "moment": [0.02, -0.04, 0]}]
  }]})json";
}

Eigen::MatrixXd dense(const Triplets& t, int n) {
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
  for (const auto& e : t) S(e.row(), e.col()) += e.value();
  return S;
}

struct State {
  Configuration q;
  VectorXd v, vdot;
};

State randomState(const System& system, std::mt19937& gen) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = system.velocityCount();
  State s{system.model().initialConfiguration, VectorXd(n), VectorXd(n)};
  VectorXd dq(n);
  for (int i = 0; i < n; ++i) {
    dq[i] = 0.15 * u(gen);
    s.v[i] = 2.0 * u(gen);
    s.vdot[i] = 3.0 * u(gen);
  }
  system.retract(s.q, dq);
  return s;
}

VectorXd residualOf(System& system, const State& s) {
  VectorXd r, phi;
  system.residual(0.0, s.q, s.v, s.vdot, VectorXd(), r, phi);
  return r;
}

// max |block - finite differences| / max |finite differences| over the
// three blocks M = dr/dvdot, C = dr/dv, K = dr/dq (along the retraction).
void checkTangent(const std::string& mass) {
  System system(assemble(parseScene(meshScene(mass))));
  const int n = system.velocityCount();
  ASSERT_EQ(n, 3 + 6 + 6 + 1 + 3);  // pin: 3 rotations; free nodes 1, 2; slide: 1 + 3
  std::mt19937 gen(7u);
  double worst[3] = {0.0, 0.0, 0.0};
  for (int trial = 0; trial < 5; ++trial) {
    const State s = randomState(system, gen);
    for (int block = 0; block < 3; ++block) {
      Triplets S, G;
      system.tangent(0.0, s.q, s.v, s.vdot, VectorXd(), block == 0, block == 1, block == 2, S, G);
      const Eigen::MatrixXd analytic = dense(S, n);
      Eigen::MatrixXd fd(n, n);
      const double h = 1e-6;
      for (int c = 0; c < n; ++c) {
        State p = s, m = s;
        const VectorXd e = VectorXd::Unit(n, c) * h;
        if (block == 0) p.vdot += e, m.vdot -= e;
        if (block == 1) p.v += e, m.v -= e;
        if (block == 2) system.retract(p.q, e), system.retract(m.q, -e);
        fd.col(c) = (residualOf(system, p) - residualOf(system, m)) / (2.0 * h);
      }
      worst[block] = std::max(worst[block], (analytic - fd).cwiseAbs().maxCoeff() / fd.cwiseAbs().maxCoeff());
    }
  }
  std::printf("[ mesh %-10s ] max rel error M: %.2e, C: %.2e, K: %.2e\n", mass.c_str(), worst[0], worst[1],
              worst[2]);
  EXPECT_LT(worst[0], 1e-8);
  EXPECT_LT(worst[1], 1e-7);
  EXPECT_LT(worst[2], 1e-6);
}

}  // namespace

TEST(FlexibleMesh, ConsistentMassTangentsMatchFiniteDifferences) { checkTangent("consistent"); }

TEST(FlexibleMesh, LumpedMassTangentsMatchFiniteDifferences) { checkTangent("lumped"); }

// The consistent centre-line mass is exact for motions whose field is
// linear along the element (rigid ones, and stretching: the axial
// interpolation is the bar's): a uniform acceleration carries the
// whole mass, with the classic consistent nodal moments q L^2 / 12 and no
// net moment about the centre; a rigid spin about node 1 gives the exact
// centripetal force and kinetic energy of a uniform rod.
TEST(ConsistentMass, IsExactForRigidMotionsOfTheElement) {
  const NodePose n1{Vec3(0.2, -0.1, 0.4), expSO3(Vec3(0.3, -0.5, 0.2))};
  const Vec3 axis = Vec3(1.0, 0.4, -0.3).normalized(), y = axis.cross(Vec3::UnitZ()).normalized();
  const double L = 1.7, m = 2.4;  // m = rhoA L0
  const NodePose n2{n1.r + L * axis, n1.A};
  // Node frames turned against the element (C1, C2 not the identity).
  const CorotationalBeam beam = CorotationalBeam::fromReference(n1, n2, y, BeamSection{});
  const Vec3 c = 0.5 * (n1.r + n2.r);
  auto netMoment = [&](const Vec12& f) -> Vec3 {  // world, about the centre
    return (n1.r - c).cross(f.segment<3>(0)) + n1.A * f.segment<3>(3) + (n2.r - c).cross(f.segment<3>(6)) +
           n2.A * f.segment<3>(9);
  };
  const Vec3 a(0.3, -1.0, 2.0);
  const NodeAcceleration acc{a, Vec3::Zero()};
  const Vec12 uniform = consistentInertiaForce(beam, m, n1, {}, acc, n2, {}, acc, Vec3::Zero());
  EXPECT_LT((uniform.segment<3>(0) + uniform.segment<3>(6) - m * a).norm(), 1e-13);
  EXPECT_LT(netMoment(uniform).norm(), 1e-13);
  const Vec3 aNormal = a - a.dot(axis) * axis;  // q L^2 / 12 with q = m a / L
  EXPECT_NEAR((n1.A * uniform.segment<3>(3)).norm(), m * L * aNormal.norm() / 12.0, 1e-13);
  // Weight: the same as an acceleration -g.
  const Vec12 weight = consistentInertiaForce(beam, m, n1, {}, {}, n2, {}, {}, -a);
  EXPECT_LT((weight - uniform).norm(), 1e-13);

  // Stretching: node 2 accelerating along the element loads the nodes like
  // the linear bar's consistent mass, m/6 [2 1; 1 2], with no moments.
  const NodeAcceleration stretch{2.5 * axis, Vec3::Zero()};
  const Vec12 bar = consistentInertiaForce(beam, m, n1, {}, {}, n2, {}, stretch, Vec3::Zero());
  EXPECT_LT((bar.segment<3>(0) - m / 6.0 * stretch.a).norm(), 1e-13);
  EXPECT_LT((bar.segment<3>(6) - m / 3.0 * stretch.a).norm(), 1e-13);
  EXPECT_LT(bar.segment<3>(3).norm() + bar.segment<3>(9).norm(), 1e-13);

  // Spin at rate w about an axis through node 1, w perpendicular to the element.
  const Vec3 w = 3.0 * y;
  const NodeVelocity v1{Vec3::Zero(), n1.A.transpose() * w}, v2{w.cross(L * axis), n2.A.transpose() * w};
  const NodeAcceleration a1{Vec3::Zero(), Vec3::Zero()}, a2{w.cross(w.cross(L * axis)), Vec3::Zero()};
  const Vec12 spin = consistentInertiaForce(beam, m, n1, v1, a1, n2, v2, a2, Vec3::Zero());
  EXPECT_LT((spin.segment<3>(0) + spin.segment<3>(6) - m * w.cross(w.cross(0.5 * L * axis))).norm(), 1e-13);
  const ConsistentEnergy e = consistentEnergy(beam, m, n1, v1, n2, v2, Vec3::Zero());
  EXPECT_NEAR(e.kinetic, 0.5 * (m * L * L / 3.0) * w.squaredNorm(), 1e-13);
}

// The element's inertia alone: M, C, K against central differences of f
// in random states (bent element, node frames turned against it, moving).
TEST(ConsistentMass, TangentsMatchFiniteDifferences) {
  std::mt19937 gen(11u);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto vec = [&](double s) { return Vec3(s * u(gen), s * u(gen), s * u(gen)); };
  double worst[3] = {0.0, 0.0, 0.0};
  for (int trial = 0; trial < 10; ++trial) {
    const NodePose ref1{vec(1.0), expSO3(vec(1.5))};
    const NodePose ref2{ref1.r + Vec3(0.8, 0.3, -0.2) + vec(0.1), expSO3(vec(1.5))};
    const CorotationalBeam beam = CorotationalBeam::fromReference(ref1, ref2, Vec3(0.1, 1.0, 0.4), BeamSection{});
    NodePose n[2] = {{ref1.r + vec(0.05), ref1.A * expSO3(vec(0.3))}, {ref2.r + vec(0.05), ref2.A * expSO3(vec(0.3))}};
    NodeVelocity v[2] = {{vec(2.0), vec(3.0)}, {vec(2.0), vec(3.0)}};
    NodeAcceleration a[2] = {{vec(5.0), vec(5.0)}, {vec(5.0), vec(5.0)}};
    const Vec3 g(0.3, -9.81, 1.2);
    const double m = 1.7;
    auto tangent = [&](double cM, double cC, double cK) {
      return consistentInertia(beam, m, n[0], v[0], a[0], n[1], v[1], a[1], g, cM, cC, cK);
    };
    const ConsistentInertia in = tangent(1.0, 0.0, 0.0);
    auto force = [&] { return consistentInertiaForce(beam, m, n[0], v[0], a[0], n[1], v[1], a[1], g); };
    EXPECT_LT((in.f - force()).norm(), 1e-13 * in.f.norm());
    Mat12 fd[3];
    const double h = 1e-6;
    for (int col = 0; col < 12; ++col) {
      const int node = col / 6, k = col % 6;
      const Vec3 e = Vec3::Unit(k % 3) * h;
      for (int block = 0; block < 3; ++block) {
        Vec12 plus, minus;
        for (int sign : {1, -1}) {
          const NodePose pose = n[node];
          const NodeVelocity vel = v[node];
          const NodeAcceleration acc = a[node];
          if (block == 0) (k < 3 ? a[node].a : a[node].omegaDot) += sign * e;
          if (block == 1) (k < 3 ? v[node].v : v[node].omega) += sign * e;
          if (block == 2) {
            if (k < 3) n[node].r += sign * e;
            else n[node].A = n[node].A * expSO3(sign * e);
          }
          (sign > 0 ? plus : minus) = force();
          n[node] = pose;
          v[node] = vel;
          a[node] = acc;
        }
        fd[block].col(col) = (plus - minus) / (2 * h);
      }
    }
    const Mat12 analytic[3] = {in.S, tangent(0.0, 1.0, 0.0).S, tangent(0.0, 0.0, 1.0).S};
    for (int block = 0; block < 3; ++block)
      worst[block] = std::max(worst[block], (analytic[block] - fd[block]).cwiseAbs().maxCoeff() /
                                                fd[block].cwiseAbs().maxCoeff());
    // The factors combine linearly.
    EXPECT_LT((tangent(0.3, 2.0, 7.0).S - (0.3 * analytic[0] + 2.0 * analytic[1] + 7.0 * analytic[2]))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12 * analytic[2].cwiseAbs().maxCoeff() * 7.0);
  }
  std::printf("[ consistent mass ] max rel error M: %.2e, C: %.2e, K: %.2e\n", worst[0], worst[1], worst[2]);
  EXPECT_LT(worst[0], 1e-8);
  EXPECT_LT(worst[1], 1e-7);
  EXPECT_LT(worst[2], 1e-6);
}

// The choice of the default mass, from the linear eigenvalue problem
// K x = w^2 M x of the F3 cantilever (EI = rhoA = L = 1, shear-rigid) at its
// reference: with 16 elements the consistent mass (cubic across the element) puts
// the first two bending frequencies within 2e-5 of Euler-Bernoulli's,
// converging at fourth order; lumped mass -0.18 % and -0.62 %, second order.
namespace {

std::string cantilever(const std::string& mass, int elements) {
  return R"json({
  "format": "mfbd-scene/1", "name": "f3",
  "flexible_bodies": [{
    "name": "beam", "mass": ")json" + mass + R"json(",
    "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": )json" + std::to_string(elements) + R"json(,
             "section_y": [0, 1, 0]},
    "section": {"EA": 1e6, "GJ": 1, "EIy": 1, "EIz": 1, "rhoA": 1, "rhoJ": [2e-6, 1e-6, 1e-6]},
    "supports": [{"node": 0, "type": "clamp"}]
  }]})json";
}

// Relative errors of the two lowest distinct bending frequencies (each
// appears twice: bending in y and in z).
Eigen::Vector2d bendingFrequencyErrors(const std::string& mass, int elements = 16) {
  System system(assemble(parseScene(cantilever(mass, elements))));
  const int n = system.velocityCount();
  const Configuration& q = system.model().initialConfiguration;
  const VectorXd zero = VectorXd::Zero(n);
  Triplets M, K, G;
  system.tangent(0.0, q, zero, zero, VectorXd(), 1.0, 0.0, 0.0, M, G);
  system.tangent(0.0, q, zero, zero, VectorXd(), 0.0, 0.0, 1.0, K, G);
  const Eigen::MatrixXd Kd = dense(K, n), Md = dense(M, n);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (Kd + Kd.transpose()), Md);
  const VectorXd f = eig.eigenvalues().cwiseSqrt() / (2 * M_PI);
  const double exact1 = std::pow(1.8751040687, 2) / (2 * M_PI), exact2 = std::pow(4.6940911330, 2) / (2 * M_PI);
  EXPECT_NEAR(f[0] / f[1], 1.0, 1e-7);  // the pairs
  EXPECT_NEAR(f[2] / f[3], 1.0, 1e-7);
  return Eigen::Vector2d(f[0] / exact1 - 1, f[2] / exact2 - 1);
}

}  // namespace

TEST(FlexibleMesh, ConsistentMassGetsTheBendingFrequenciesAtFourthOrder) {
  const Eigen::Vector2d consistent = bendingFrequencyErrors("consistent"), lumped = bendingFrequencyErrors("lumped");
  std::printf("[ F3 linear ] 16 elements, f1 and f2 errors: consistent %+.4f %% %+.4f %%, lumped %+.3f %% %+.3f %%\n",
              100 * consistent[0], 100 * consistent[1], 100 * lumped[0], 100 * lumped[1]);
  // The section's rotary inertia (rhoJ / rhoA = 1e-6 m^2) puts the
  // Rayleigh beam's own frequencies about 2e-6 and 1e-5 below
  // Euler-Bernoulli's: the floor that 16 consistent elements reach.
  EXPECT_LT(std::abs(consistent[0]), 5e-6);
  EXPECT_LT(std::abs(consistent[1]), 2e-5);
  // Above the floor the error falls 16-fold per halving (f1: 4.8e-4 ->
  // 3.0e-5 from 2 to 4 elements, f2: 1.1e-3 -> 6.4e-5 from 4 to 8).
  const double order1 = std::log2(bendingFrequencyErrors("consistent", 2)[0] / bendingFrequencyErrors("consistent", 4)[0]);
  const double order2 = std::log2(bendingFrequencyErrors("consistent", 4)[1] / bendingFrequencyErrors("consistent", 8)[1]);
  std::printf("[ F3 linear ] consistent mass: order %.2f (f1, 2 -> 4 elements), %.2f (f2, 4 -> 8)\n", order1, order2);
  EXPECT_NEAR(order1, 4.0, 0.3);
  EXPECT_NEAR(order2, 4.0, 0.3);
  EXPECT_NEAR(lumped[0], -0.00179, 0.00003);
  EXPECT_NEAR(lumped[1], -0.00620, 0.00003);
}
