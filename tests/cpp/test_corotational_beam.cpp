// Corotational beam element, beam sections and nodal inertia: tangents by
// central finite differences on the manifold increments (r + dr,
// A expSO3(dtheta)), rigid-motion invariance, and physical references
// (linear Timoshenko cantilever; exact discrete roll-up under end moment).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <functional>
#include <algorithm>
#include <random>
#include <vector>

#include "scene/beam_section.hpp"
#include "flex/consistent_mass.hpp"
#include "flex/corotational_beam.hpp"
#include "flex/element_force_lanes.hpp"
#include "flex/nodal_inertia.hpp"
#include "math/rotation.hpp"

using namespace mfbd;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Rng {
  std::mt19937 gen{20240611u};
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
  Vec3 vector(double a, double b) { return Vec3(uniform(a, b), uniform(a, b), uniform(a, b)); }
  Vec3 direction() { return vector(-1, 1).normalized(); }
  Mat3 rotation(double maxAngle) { return expSO3(direction() * uniform(0, maxAngle)); }
};

// A deliberately "balanced" section (axial, bending and shear terms of similar
// size) so that geometric and material parts weigh alike in the checks.
BeamSection balancedSection() {
  BeamSection s;
  s.EA = 100.0;
  s.GAy = 60.0;
  s.GAz = 40.0;
  s.GJ = 0.8;
  s.EIy = 1.5;
  s.EIz = 2.5;
  s.rhoA = 2.0;
  s.rhoJ = Vec3(0.03, 0.01, 0.02);
  return s;
}

BeamSection steelRectangle(double b, double h) {
  return rectangleSection(BeamMaterial{210e9, 80.77e9, 7850.0}, b, h);
}

struct Element {
  CorotationalBeam beam;
  NodePose ref1, ref2;
};

// Random reference: node frames NOT aligned with the element.
Element randomElement(Rng& rng, const BeamSection& s) {
  Element e;
  e.ref1.r = rng.vector(-1, 1);
  e.ref2.r = e.ref1.r + rng.direction() * rng.uniform(0.8, 1.6);
  e.ref1.A = rng.rotation(kPi);
  e.ref2.A = rng.rotation(kPi);
  e.beam = CorotationalBeam::fromReference(e.ref1, e.ref2, rng.direction(), s);
  return e;
}

NodePose rigidlyMoved(const NodePose& n, const Mat3& Q, const Vec3& t) {
  return NodePose{Q * n.r + t, Q * n.A};
}

// Moderately deformed and then rigidly moved by a rotation of up to
// maxTurns full turns.
void deformedConfiguration(Rng& rng, const Element& e, double maxTurns, NodePose& n1,
                           NodePose& n2) {
  const double L0 = e.beam.L0;
  n1 = NodePose{e.ref1.r + rng.vector(-0.1, 0.1) * L0, expSO3(rng.vector(-0.3, 0.3)) * e.ref1.A};
  n2 = NodePose{e.ref2.r + rng.vector(-0.1, 0.1) * L0, expSO3(rng.vector(-0.3, 0.3)) * e.ref2.A};
  const Mat3 Q = expSO3(rng.direction() * rng.uniform(0, 2 * kPi * maxTurns));
  const Vec3 t = rng.vector(-5, 5);
  n1 = rigidlyMoved(n1, Q, t);
  n2 = rigidlyMoved(n2, Q, t);
}

void applyIncrement(NodePose& n1, NodePose& n2, const Vec12& dq) {
  n1.r += dq.segment<3>(0);
  n1.A = n1.A * expSO3(dq.segment<3>(3));
  n2.r += dq.segment<3>(6);
  n2.A = n2.A * expSO3(dq.segment<3>(9));
}

// Central differences of f over the manifold increments.
Mat12 finiteDifferenceTangent(const std::function<Vec12(const NodePose&, const NodePose&)>& f,
                              const NodePose& n1, const NodePose& n2, double h) {
  Mat12 K;
  for (int c = 0; c < 12; ++c) {
    NodePose p1 = n1, p2 = n2, m1 = n1, m2 = n2;
    applyIncrement(p1, p2, h * Vec12::Unit(c));
    applyIncrement(m1, m2, -h * Vec12::Unit(c));
    K.col(c) = (f(p1, p2) - f(m1, m2)) / (2 * h);
  }
  return K;
}

// The element's force and its tangent at one state (internalForceVector,
// internalForceTangent); valid where both are.
struct BeamForces {
  Vec12 f = Vec12::Zero();
  Mat12 K = Mat12::Zero(), C = Mat12::Zero();
  bool valid = false;
};

BeamForces internalForces(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                          const NodeVelocity& v1, const NodeVelocity& v2, double dampingBeta) {
  BeamForces out;
  const BeamTangent tangent = internalForceTangent(beam, n1, n2, v1, v2, dampingBeta);
  const bool force = internalForceVector(beam, n1, n2, v1, v2, dampingBeta, out.f);
  out.K = tangent.K;
  out.C = tangent.C;
  out.valid = force && tangent.valid;
  return out;
}

double relativeError(const Mat12& K, const Mat12& Kref) {
  return (K - Kref).cwiseAbs().maxCoeff() / Kref.cwiseAbs().maxCoeff();
}

}  // namespace

// ---------------------------------------------------------------------------
// 0. The internal force is the gradient of the strain energy: without
// damping, f = dU/dq with U = localStrainEnergy(e_l(q)), e_l from
// localDeformation (the log map of math/rotation.cpp); central differences
// over the manifold increments, at large rigid rotations. A second form of
// f, independent of the kernel's products with B.
// ---------------------------------------------------------------------------
TEST(CorotationalBeam, InternalForceIsTheGradientOfTheStrainEnergy) {
  Rng rng;
  const NodeVelocity still;
  auto energy = [](const CorotationalBeam& beam, const NodePose& a, const NodePose& b) {
    const LocalDeformation d = localDeformation(beam, a, b);
    Vec7 e;
    e << d.u, d.theta1, d.theta2;
    return localStrainEnergy(beam, e);
  };
  double worst = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    const Element e = randomElement(rng, balancedSection());
    NodePose n1, n2;
    deformedConfiguration(rng, e, 10.0, n1, n2);
    Vec12 f, gradient;
    ASSERT_TRUE(internalForceVector(e.beam, n1, n2, still, still, 0.0, f));
    const double h = 1e-6;
    for (int c = 0; c < 12; ++c) {
      NodePose p1 = n1, p2 = n2, m1 = n1, m2 = n2;
      applyIncrement(p1, p2, h * Vec12::Unit(c));
      applyIncrement(m1, m2, -h * Vec12::Unit(c));
      gradient[c] = (energy(e.beam, p1, p2) - energy(e.beam, m1, m2)) / (2 * h);
    }
    worst = std::max(worst, (f - gradient).cwiseAbs().maxCoeff() / f.cwiseAbs().maxCoeff());
  }
  std::printf("[ energy    ] max rel error of f against dU/dq: %.2e\n", worst);
  EXPECT_LT(worst, 1e-6);
}

// ---------------------------------------------------------------------------
// 1. Consistent tangent against finite differences, large rotations
// ---------------------------------------------------------------------------
TEST(CorotationalBeam, StiffnessTangentMatchesFiniteDifferencesAtLargeRotations) {
  Rng rng;
  const NodeVelocity still;
  double worst = 0.0, worstGeometric = 0.0;
  for (int trial = 0; trial < 30; ++trial) {
    const Element e = randomElement(rng, balancedSection());
    NodePose n1, n2;
    if (trial % 5 == 4) {  // pure rigid motion of many turns
      const Mat3 Q = expSO3(rng.direction() * rng.uniform(20.0, 60.0));
      n1 = rigidlyMoved(e.ref1, Q, rng.vector(-3, 3));
      n2 = rigidlyMoved(e.ref2, Q, n1.r - Q * e.ref1.r);
    } else {
      deformedConfiguration(rng, e, 10.0, n1, n2);
    }
    const BeamForces F = internalForces(e.beam, n1, n2, still, still, 0.0);
    ASSERT_TRUE(F.valid);
    auto force = [&](const NodePose& a, const NodePose& b) {
      return internalForces(e.beam, a, b, still, still, 0.0).f;
    };
    const Mat12 Kfd = finiteDifferenceTangent(force, n1, n2, 1e-5);
    const double err = relativeError(F.K, Kfd);
    worst = std::max(worst, err);
    // The geometric stiffness alone must be resolved too: compare the
    // non-symmetric part (material part B^T K_l B is symmetric).
    const Mat12 skewK = F.K - F.K.transpose(), skewFd = Kfd - Kfd.transpose();
    if (skewFd.cwiseAbs().maxCoeff() > 1e-3 * Kfd.cwiseAbs().maxCoeff()) {
      worstGeometric = std::max(worstGeometric, relativeError(skewK, skewFd));
    }
    EXPECT_LT(err, 1e-6) << "trial " << trial;
  }
  std::printf("[ stiffness ] max |K - K_fd| / |K|: %.2e, non-symmetric part: %.2e\n", worst,
              worstGeometric);
  EXPECT_LT(worstGeometric, 1e-6);
}

// The local element alone: its force is the gradient of its strain energy
// and K_l + localTangentExcess is the force's Jacobian (central differences,
// random local deformations up to 0.3 rad); a pure bending pair
// theta_1 = -theta_2 = a / 2 with u = -L0 a^2 / 24 is free of axial force.
TEST(CorotationalBeam, ShallowArchLocalElementIsConservativeAndItsTangentExact) {
  Rng rng;
  const CorotationalBeam beam =
      CorotationalBeam::fromReference(NodePose{}, NodePose{Vec3(0.7, 0, 0), Mat3::Identity()}, Vec3::UnitY(),
                                      balancedSection());
  double worstForce = 0.0, worstTangent = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    Vec7 e;
    e[0] = rng.uniform(-0.01, 0.01);
    for (int i = 1; i < 7; ++i) e[i] = rng.uniform(-0.3, 0.3);
    const Vec7 f = localElasticForce(beam, e);
    const Mat7 K = beam.localStiffness + localTangentExcess(beam, e);
    Vec7 gradient;
    Mat7 jacobian;
    const double h = 1e-6;
    for (int j = 0; j < 7; ++j) {
      Vec7 p = e, m = e;
      p[j] += h;
      m[j] -= h;
      gradient[j] = (localStrainEnergy(beam, p) - localStrainEnergy(beam, m)) / (2 * h);
      jacobian.col(j) = (localElasticForce(beam, p) - localElasticForce(beam, m)) / (2 * h);
    }
    worstForce = std::max(worstForce, (f - gradient).cwiseAbs().maxCoeff() / f.cwiseAbs().maxCoeff());
    worstTangent = std::max(worstTangent, (K - jacobian).cwiseAbs().maxCoeff() / K.cwiseAbs().maxCoeff());
  }
  std::printf("[ local     ] force vs energy gradient: %.2e, tangent vs finite differences: %.2e\n", worstForce,
              worstTangent);
  EXPECT_LT(worstForce, 1e-8);
  EXPECT_LT(worstTangent, 1e-8);
  const double a = 0.2;
  Vec7 bent = Vec7::Zero();
  bent << -beam.L0 * a * a / 24.0, 0, 0, a / 2, 0, 0, -a / 2;
  EXPECT_LT(std::abs(localElasticForce(beam, bent)[0]), 1e-12 * beam.section.EA);
}

// ---------------------------------------------------------------------------
// 2. Damping: velocity tangent C and the damping force's position tangent
// ---------------------------------------------------------------------------
TEST(CorotationalBeam, DampingTangentsMatchFiniteDifferences) {
  Rng rng;
  const double beta = 0.05;
  double worstC = 0.0, worstK = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    const Element e = randomElement(rng, balancedSection());
    NodePose n1, n2;
    deformedConfiguration(rng, e, 5.0, n1, n2);
    const NodeVelocity v1{rng.vector(-2, 2), rng.vector(-3, 3)};
    const NodeVelocity v2{rng.vector(-2, 2), rng.vector(-3, 3)};
    const BeamForces F = internalForces(e.beam, n1, n2, v1, v2, beta);
    ASSERT_TRUE(F.valid);

    Mat12 Cfd;
    const double h = 1e-2;  // f is linear in the velocities: no truncation error
    for (int c = 0; c < 12; ++c) {
      NodeVelocity p[2] = {v1, v2}, m[2] = {v1, v2};
      Vec3& dp = c % 6 < 3 ? p[c / 6].v : p[c / 6].omega;
      Vec3& dm = c % 6 < 3 ? m[c / 6].v : m[c / 6].omega;
      dp[c % 3] += h;
      dm[c % 3] -= h;
      Cfd.col(c) = (internalForces(e.beam, n1, n2, p[0], p[1], beta).f -
                    internalForces(e.beam, n1, n2, m[0], m[1], beta).f) / (2 * h);
    }
    worstC = std::max(worstC, relativeError(F.C, Cfd));

    auto force = [&](const NodePose& a, const NodePose& b) {
      return internalForces(e.beam, a, b, v1, v2, beta).f;
    };
    worstK = std::max(worstK, relativeError(F.K, finiteDifferenceTangent(force, n1, n2, 1e-5)));
  }
  std::printf("[ damping   ] max rel error C: %.2e, K (with damping): %.2e\n", worstC, worstK);
  EXPECT_LT(worstC, 1e-8);
  EXPECT_LT(worstK, 1e-6);
}

// The residual's element forces, four elements side by side in vector
// lanes (elementForceVectors: internal force plus consistent inertia less
// weight) against one element's (internalForceVector, consistentInertia):
// lanes that take different branches (node frames
// aligned with the element or not, damping or none, mass or none, local
// rotations small enough for the short series, for the long one, or
// beyond both), groups of four and a last group of three. The baseline
// and AVX2 variants agree to the bit.
TEST(CorotationalBeam, ResidualForcesInVectorLanesMatchTheTangentPaths) {
  Rng rng;
  struct Case {
    Element e;
    NodePose n1, n2;
    NodeVelocity v1, v2;
    NodeAcceleration a1, a2;
    double damping, mass;
  };
  const Vec3 gravity(0.3, -9.81, 1.2);
  std::vector<Case> cases;
  for (int k = 0; k < 11; ++k) {
    Case c;
    if (k % 3 == 0) {  // node frames the element's own: C = I exactly
      c.e.ref1 = NodePose{Vec3::Zero(), Mat3::Identity()};
      c.e.ref2 = NodePose{Vec3(1.2, 0, 0), Mat3::Identity()};
      c.e.beam = CorotationalBeam::fromReference(c.e.ref1, c.e.ref2, Vec3::UnitY(), balancedSection());
      ASSERT_TRUE(c.e.beam.identityC1 && c.e.beam.identityC2);
    } else {
      c.e = randomElement(rng, balancedSection());
    }
    // local rotations ~1e-4 (short series), ~0.05 (long series), ~0.4 (logSO3)
    const double size = k % 4 == 0 ? 1e-4 : k % 4 == 1 ? 0.05 : 0.4;
    const Mat3 Q = expSO3(rng.direction() * rng.uniform(0, 2 * kPi));
    c.n1 = rigidlyMoved(NodePose{c.e.ref1.r + rng.vector(-size, size), expSO3(rng.vector(-size, size)) * c.e.ref1.A},
                        Q, rng.vector(-5, 5));
    c.n2 = NodePose{c.n1.r + Q * (c.e.ref2.r - c.e.ref1.r + rng.vector(-size, size)),
                    Q * expSO3(rng.vector(-size, size)) * c.e.ref2.A};
    c.v1 = NodeVelocity{rng.vector(-2, 2), rng.vector(-3, 3)};
    c.v2 = NodeVelocity{rng.vector(-2, 2), rng.vector(-3, 3)};
    c.a1 = NodeAcceleration{rng.vector(-20, 20), rng.vector(-30, 30)};
    c.a2 = NodeAcceleration{rng.vector(-20, 20), rng.vector(-30, 30)};
    c.damping = k % 2 == 0 ? 0.0 : 0.05;
    c.mass = k % 5 == 0 ? 0.0 : 2.4;
    cases.push_back(c);
  }
  double worst = 0.0;
  for (std::size_t first = 0; first < cases.size(); first += kForceLanes) {
    const int count = int(std::min<std::size_t>(kForceLanes, cases.size() - first));
    ElementInputs inputs[kForceLanes];
    for (int i = 0; i < count; ++i) {
      const Case& c = cases[first + i];
      inputs[i] = {&c.e.beam, c.damping, c.mass, &c.n1, &c.n2, &c.v1, &c.v2, &c.a1, &c.a2};
    }
    Vec12 f[kForceLanes], baseline[kForceLanes];
    ASSERT_TRUE(elementForceVectors(count, inputs, gravity, f));
    ASSERT_TRUE(elementForceVectorsBaseline(count, inputs, gravity, baseline));
    for (int i = 0; i < count; ++i) {
      const Case& c = cases[first + i];
      const BeamForces internal = internalForces(c.e.beam, c.n1, c.n2, c.v1, c.v2, c.damping);
      ASSERT_TRUE(internal.valid);
      Vec12 reference = internal.f;
      if (c.mass > 0.0)
        reference += consistentInertia(c.e.beam, c.mass, c.n1, c.v1, c.a1, c.n2, c.v2, c.a2, gravity, 0, 0, 0).f;
      Vec12 one;
      ASSERT_TRUE(internalForceVector(c.e.beam, c.n1, c.n2, c.v1, c.v2, c.damping, one));
      worst = std::max({worst, (f[i] - reference).norm() / reference.norm(),
                        (one - internal.f).norm() / internal.f.norm()});
      EXPECT_EQ(f[i], baseline[i]) << "element " << first + i;  // same variant or AVX2: bit for bit
    }
  }
  std::printf("[ lanes     ] max rel error of f: %.2e (AVX2 variant %s)\n", worst, hasAvx2() ? "used" : "absent");
  EXPECT_LT(worst, 1e-12);
  // One element with a collapsed chord among four: the group reports it.
  ElementInputs inputs[kForceLanes];
  for (int i = 0; i < kForceLanes; ++i) {
    const Case& c = cases[i];
    inputs[i] = {&c.e.beam, c.damping, c.mass, &c.n1, i == 2 ? &c.n1 : &c.n2, &c.v1, &c.v2, &c.a1, &c.a2};
  }
  Vec12 f[kForceLanes];
  EXPECT_FALSE(elementForceVectors(kForceLanes, inputs, gravity, f));
}

// ---------------------------------------------------------------------------
// 3. Rigid motions produce no internal (elastic or damping) force
// ---------------------------------------------------------------------------
TEST(CorotationalBeam, RigidMotionGivesZeroForce) {
  Rng rng;
  const BeamSection s = steelRectangle(0.02, 0.01);
  double worst = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    Element e = randomElement(rng, s);
    const double forceScale = s.EIy / (e.beam.L0 * e.beam.L0);
    const Mat3 Q = expSO3(rng.direction() * rng.uniform(0.0, 100.0));
    const Vec3 t = rng.vector(-10, 10);
    const NodePose n1 = rigidlyMoved(e.ref1, Q, t), n2 = rigidlyMoved(e.ref2, Q, t);
    // Rigid velocity field: v = V + Omega x (r - r1), omega_i = A_i^T Omega.
    const Vec3 V = rng.vector(-5, 5), Omega = rng.vector(-20, 20);
    const NodeVelocity v1{V, n1.A.transpose() * Omega};
    const NodeVelocity v2{V + Omega.cross(n2.r - n1.r), n2.A.transpose() * Omega};
    const BeamForces F = internalForces(e.beam, n1, n2, v1, v2, 0.01);
    ASSERT_TRUE(F.valid);
    worst = std::max(worst, F.f.cwiseAbs().maxCoeff() / forceScale);
  }
  std::printf("[ rigid     ] max |f| / (EI/L^2): %.2e\n", worst);
  EXPECT_LT(worst, 1e-9);
}

TEST(CorotationalBeam, DegenerateConfigurationsAreReportedNotComputed) {
  const BeamSection s = balancedSection();
  const NodePose a, b{Vec3(1, 0, 0), Mat3::Identity()};
  EXPECT_THROW(CorotationalBeam::fromReference(a, a, Vec3::UnitY(), s), std::invalid_argument);
  EXPECT_THROW(CorotationalBeam::fromReference(a, b, Vec3(2, 0, 0), s), std::invalid_argument);
  const CorotationalBeam beam = CorotationalBeam::fromReference(a, b, Vec3::UnitY(), s);
  const NodeVelocity still;
  EXPECT_FALSE(internalForces(beam, a, a, still, still, 0).valid);  // collapsed chord
  // Both section y axes along the chord (local rotations of 90 deg) and a
  // relative twist of 180 deg leave the corotated frame undefined.
  const Mat3 quarterZ = expSO3(Vec3(0, 0, kPi / 2)), halfX = expSO3(Vec3(kPi, 0, 0));
  EXPECT_FALSE(internalForces(beam, {a.r, quarterZ}, {b.r, quarterZ}, still, still, 0).valid);
  EXPECT_FALSE(internalForces(beam, a, {b.r, halfX}, still, still, 0).valid);
  EXPECT_TRUE(internalForces(beam, a, b, still, still, 0).valid);
}

// ---------------------------------------------------------------------------
// 4. Small-deformation limit: one-element cantilever against linear theory
// ---------------------------------------------------------------------------
namespace {

// Clamp node 1, load node 2 with a world force and a world moment, solve
// f_int(node 2) = [P; A2^T M] by Newton on the element tangent (plus the
// load stiffness skew(A2^T M) of the fixed-direction moment).
NodePose solveCantilever(const CorotationalBeam& beam, const NodePose& n1, NodePose n2,
                         const Vec3& P, const Vec3& M, int* iterations = nullptr) {
  const NodeVelocity still;
  for (int it = 0; it < 30; ++it) {
    const BeamForces F = internalForces(beam, n1, n2, still, still, 0.0);
    Eigen::Matrix<double, 6, 1> r;
    r << F.f.segment<3>(6) - P, F.f.segment<3>(9) - n2.A.transpose() * M;
    Eigen::Matrix<double, 6, 6> K = F.K.bottomRightCorner<6, 6>();
    K.bottomRightCorner<3, 3>() -= skew(n2.A.transpose() * M);
    const Eigen::Matrix<double, 6, 1> dq = -K.partialPivLu().solve(r);
    n2.r += dq.head<3>();
    n2.A = n2.A * expSO3(dq.tail<3>());
    // Converged when the correction is at round-off of the pose (the
    // residual itself bottoms out at ~eps EA, far above eps P).
    if (dq.head<3>().norm() <= 1e-14 * beam.L0 && dq.tail<3>().norm() <= 1e-14) {
      if (iterations) *iterations = it + 1;
      return n2;
    }
  }
  ADD_FAILURE() << "cantilever Newton did not converge";
  return n2;
}

struct Cantilever {
  CorotationalBeam beam;
  NodePose n1, n2;
  Mat3 E0;  // element frame in world
};

// A stubby steel beam (shear gives 5-12% of the deflection) in a general
// orientation, with node frames not aligned with the element.
Cantilever makeCantilever(const BeamSection& s) {
  Rng rng;
  Cantilever c;
  c.E0 = rng.rotation(kPi);
  const double L = 0.12;
  c.n1 = NodePose{Vec3(0.3, -0.2, 1.0), rng.rotation(kPi)};
  c.n2 = NodePose{c.n1.r + L * c.E0.col(0), rng.rotation(kPi)};
  c.beam = CorotationalBeam::fromReference(c.n1, c.n2, c.E0.col(1), s);
  return c;
}

double tipRotationAbout(const Cantilever& c, const NodePose& n2, const Vec3& axis) {
  return logSO3(n2.A * c.n2.A.transpose()).dot(axis);
}

}  // namespace

TEST(CorotationalBeam, CantileverMatchesLinearTimoshenko) {
  const BeamSection s = steelRectangle(0.03, 0.05);
  const Cantilever c = makeCantilever(s);
  const double L = c.beam.L0;
  const Vec3 ex = c.E0.col(0), ey = c.E0.col(1), ez = c.E0.col(2);
  // Loads giving deflections ~1e-5 L, so geometric nonlinearity (relative
  // (w/L)^2) stays far below the tolerance.
  const double P = 1e-5 * 3.0 * s.EIz / (L * L);
  int iterations = 0;

  // Tip force along y: w = P L^3/(3 EIz) + P L/(k G A_y), rotation P L^2/(2 EIz).
  NodePose tip = solveCantilever(c.beam, c.n1, c.n2, P * ey, Vec3::Zero(), &iterations);
  const double wy = P * L * L * L / (3 * s.EIz) + P * L / s.GAy;
  std::printf("[ cantilever] shear part %.1f%%, tip deflection rel. error %.2e, %d iterations\n",
              100 * (P * L / s.GAy) / wy, (tip.r - c.n2.r).dot(ey) / wy - 1.0, iterations);
  EXPECT_NEAR((tip.r - c.n2.r).dot(ey) / wy, 1.0, 1e-6);
  EXPECT_NEAR(tipRotationAbout(c, tip, ez) / (P * L * L / (2 * s.EIz)), 1.0, 1e-6);
  EXPECT_LE(iterations, 6);

  // Tip force along z bends about y.
  tip = solveCantilever(c.beam, c.n1, c.n2, P * ez, Vec3::Zero());
  const double wz = P * L * L * L / (3 * s.EIy) + P * L / s.GAz;
  EXPECT_NEAR((tip.r - c.n2.r).dot(ez) / wz, 1.0, 1e-6);

  // Axial force and torque.
  const double N = 1e-5 * s.EA;
  tip = solveCantilever(c.beam, c.n1, c.n2, N * ex, Vec3::Zero());
  EXPECT_NEAR((tip.r - c.n2.r).dot(ex) / (N * L / s.EA), 1.0, 1e-6);
  const double T = 1e-5 * s.GJ / L;
  tip = solveCantilever(c.beam, c.n1, c.n2, Vec3::Zero(), T * ex);
  EXPECT_NEAR(tipRotationAbout(c, tip, ex) / (T * L / s.GJ), 1.0, 1e-6);

  // Section resultants: constant shear P, root moment P L, tip moment 0.
  const NodeVelocity still;
  tip = solveCantilever(c.beam, c.n1, c.n2, P * ey, Vec3::Zero());
  const SectionForces sf =
      sectionForces(c.beam, c.n1, tip, internalForces(c.beam, c.n1, tip, still, still, 0).f);
  EXPECT_NEAR(sf.force1.y() / P, 1.0, 1e-4);
  EXPECT_NEAR(sf.force2.y() / P, 1.0, 1e-4);
  EXPECT_NEAR(sf.moment1.z() / (P * L), 1.0, 1e-4);
  EXPECT_NEAR(sf.moment2.norm() / (P * L), 0.0, 1e-8);
}

TEST(CorotationalBeam, ZeroShearStiffnessGivesEulerBernoulli) {
  BeamSection s = steelRectangle(0.03, 0.05);
  s.GAy = 0.0;                                      // flag: shear-rigid
  s.GAz = std::numeric_limits<double>::infinity();  // same, spelled as infinity
  const Cantilever c = makeCantilever(s);
  const double L = c.beam.L0, P = 1e-5 * 3.0 * s.EIz / (L * L);
  for (int axis = 1; axis <= 2; ++axis) {
    const double EI = axis == 1 ? s.EIz : s.EIy;
    const NodePose tip = solveCantilever(c.beam, c.n1, c.n2, P * c.E0.col(axis), Vec3::Zero());
    EXPECT_NEAR((tip.r - c.n2.r).dot(c.E0.col(axis)) / (P * L * L * L / (3 * EI)), 1.0, 1e-6);
  }
}

// ---------------------------------------------------------------------------
// Large rotations in an assembled mesh: a cantilever of n elements rolled up
// into a full circle by an end moment M = 2 pi EI / L. The discrete solution
// is known in closed form: every element bends by alpha = M L_e / EI, free
// of axial force, so its shallow-arch strain u / L_e + alpha^2 / 24 vanishes
// and the nodes are the vertices of a regular polygon with chords
// L_e (1 - alpha^2 / 24), the circle's own chords 2 R sin(alpha / 2) to
// O(alpha^4).
// ---------------------------------------------------------------------------
namespace {

// A straight chain of n elements along x, node 0 clamped, a world moment M
// at the last node.
struct ClampedChain {
  std::vector<NodePose> nodes;
  std::vector<CorotationalBeam> elements;

  ClampedChain(int n, double L, const BeamSection& s) : nodes(n + 1) {
    for (int i = 0; i <= n; ++i) nodes[i].r = Vec3(i * L / n, 0, 0);
    for (int i = 0; i < n; ++i) {
      elements.push_back(CorotationalBeam::fromReference(nodes[i], nodes[i + 1], Vec3::UnitY(), s));
    }
  }

  // One Newton iteration on the free nodes; returns the residual norm
  // before the update (negative if an element frame was undefined).
  double newtonIteration(const Vec3& M) {
    const int n = static_cast<int>(elements.size()), dofs = 6 * n;
    Eigen::VectorXd r = Eigen::VectorXd::Zero(6 * (n + 1));
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(6 * (n + 1), 6 * (n + 1));
    const NodeVelocity still;
    for (int e = 0; e < n; ++e) {
      const BeamForces F = internalForces(elements[e], nodes[e], nodes[e + 1], still, still, 0);
      if (!F.valid) return -1.0;
      r.segment<12>(6 * e) += F.f;
      K.block<12, 12>(6 * e, 6 * e) += F.K;
    }
    const Vec3 Mnode = nodes[n].A.transpose() * M;  // fixed world moment
    r.segment<3>(6 * n + 3) -= Mnode;
    K.block<3, 3>(6 * n + 3, 6 * n + 3) -= skew(Mnode);
    const Eigen::VectorXd dq = -K.bottomRightCorner(dofs, dofs).partialPivLu().solve(r.tail(dofs));
    for (int i = 1; i <= n; ++i) {
      nodes[i].r += dq.segment<3>(6 * (i - 1));
      nodes[i].A = nodes[i].A * expSO3(dq.segment<3>(6 * (i - 1) + 3));
    }
    return r.tail(dofs).norm();
  }
};

}  // namespace

TEST(CorotationalBeam, EndMomentRollsCantileverIntoExactPolygon) {
  const int n = 16;
  const double L = 1.0, Le = L / n;
  const BeamSection s = balancedSection();
  ClampedChain chain(n, L, s);
  const double Mfull = 2 * kPi * s.EIz / L;
  int maxIterations = 0;
  for (int step = 1; step <= 8; ++step) {
    const Vec3 M = Vec3::UnitZ() * Mfull * step / 8.0;
    int it = 0;
    for (double residual = 1.0; residual > 1e-10 * Mfull; ++it) {
      ASSERT_LT(it, 20) << "no convergence at load step " << step;
      residual = chain.newtonIteration(M);
      ASSERT_GE(residual, 0.0);
    }
    maxIterations = std::max(maxIterations, it - 1);
  }
  const double alpha = Mfull * Le / s.EIz;  // = 2 pi / n
  const double chord = Le * (1.0 - alpha * alpha / 24.0), R = L / (2 * kPi);
  Vec3 expected = Vec3::Zero();
  double worst = 0.0, offCircle = 0.0;
  for (int i = 1; i <= n; ++i) {
    const double chordAngle = (i - 0.5) * alpha;
    expected += chord * Vec3(std::cos(chordAngle), std::sin(chordAngle), 0);
    worst = std::max(worst, (chain.nodes[i].r - expected).norm() / L);
    const Vec3 onCircle(R * std::sin(i * alpha), R * (1.0 - std::cos(i * alpha)), 0.0);
    offCircle = std::max(offCircle, (chain.nodes[i].r - onCircle).norm() / L);
    // node i is turned by i alpha about z
    EXPECT_LT(logSO3(expSO3(Vec3(0, 0, -i * alpha)) * chain.nodes[i].A).norm(), 1e-9);
  }
  std::printf("[ roll-up   ] max node position error / L: %.2e (polygon), %.2e (circle), Newton iterations <= %d\n",
              worst, offCircle, maxIterations);
  EXPECT_LT(worst, 1e-9);
  // alpha^4 / 1920 per chord (1.2e-5 at 16 elements), adding up around the circle.
  EXPECT_LT(offCircle, 1e-5);
  EXPECT_LT(chain.nodes[n].r.norm(), 1e-9);  // the circle closes
  EXPECT_LE(maxIterations, 6);
}

// ---------------------------------------------------------------------------
// Sections and nodal inertia
// ---------------------------------------------------------------------------
TEST(BeamSection, ReferenceValues) {
  const BeamMaterial steel{210e9, 210e9 / 2.6, 7850.0};  // nu = 0.3
  const BeamSection sq = rectangleSection(steel, 0.1, 0.1);
  // Square torsion constant 0.1406 a^4 (Timoshenko-Goodier table).
  EXPECT_NEAR(sq.GJ / (steel.G * 1e-4) / 0.1406, 1.0, 1e-3);
  EXPECT_NEAR(sq.GAy / (steel.G * 0.01), 10 * 1.3 / (12 + 11 * 0.3), 1e-12);  // Cowper
  const BeamSection r = rectangleSection(steel, 0.02, 0.06);
  EXPECT_NEAR(r.EIy / (steel.E * 0.02 * std::pow(0.06, 3) / 12), 1.0, 1e-12);
  EXPECT_NEAR(r.EIz / (steel.E * 0.06 * std::pow(0.02, 3) / 12), 1.0, 1e-12);
  EXPECT_NEAR(r.rhoJ.x(), r.rhoJ.y() + r.rhoJ.z(), 1e-18);
  const BeamSection c = circleSection(steel, 0.04), t = tubeSection(steel, 0.02, 0.0);
  EXPECT_NEAR(c.GAy / (steel.G * kPi * 4e-4), 6 * 1.3 / (7 + 6 * 0.3), 1e-12);
  EXPECT_NEAR(t.GAy / c.GAy, 1.0, 1e-12);
  EXPECT_NEAR(t.GJ / c.GJ, 1.0, 1e-12);
  EXPECT_THROW(tubeSection(steel, 0.02, 0.02), std::invalid_argument);
}

TEST(NodalInertia, GyroscopicTangentMatchesFiniteDifferences) {
  Rng rng;
  double worst = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    const Mat3 Q = rng.rotation(kPi);
    const NodalInertia I{2.5, Q * rng.vector(0.5, 3.0).asDiagonal() * Q.transpose()};
    const NodeVelocity v{rng.vector(-1, 1), rng.vector(-10, 10)};
    const NodeAcceleration a{rng.vector(-1, 1), rng.vector(-5, 5)};
    const NodalInertiaForces F = nodalInertiaForces(I, v, a);
    Mat6 Gfd;
    const double h = 1e-5;
    for (int c = 0; c < 6; ++c) {
      NodeVelocity p = v, m = v;
      (c < 3 ? p.v : p.omega)[c % 3] += h;
      (c < 3 ? m.v : m.omega)[c % 3] -= h;
      Gfd.col(c) = (nodalInertiaForces(I, p, a).f - nodalInertiaForces(I, m, a).f) / (2 * h);
    }
    worst = std::max(worst, (F.G - Gfd).cwiseAbs().maxCoeff() / F.G.cwiseAbs().maxCoeff());
    Eigen::Matrix<double, 6, 1> acc;
    acc << a.a, a.omegaDot;
    EXPECT_LT((F.M * acc + nodalInertiaForces(I, v, NodeAcceleration{}).f - F.f).norm(),
              1e-12 * F.f.norm());
  }
  std::printf("[ inertia   ] max rel error gyroscopic tangent: %.2e\n", worst);
  EXPECT_LT(worst, 1e-9);
  // Euler: J = diag(1,2,3), omega = (1,1,0): omega x J omega = (0,0,1).
  const NodalInertiaForces F = nodalInertiaForces(
      NodalInertia{1.0, Vec3(1, 2, 3).asDiagonal()}, NodeVelocity{Vec3::Zero(), Vec3(1, 1, 0)}, {});
  EXPECT_NEAR((F.f.tail<3>() - Vec3(0, 0, 1)).norm(), 0.0, 1e-15);
}

TEST(CorotationalBeam, LumpedInertiaIsHalfTheElementInTheNodeFrame) {
  Rng rng;
  const Element e = randomElement(rng, balancedSection());
  const NodalInertia I1 = lumpedNodalInertia(e.beam, 1);
  EXPECT_NEAR(I1.m, 0.5 * 2.0 * e.beam.L0, 1e-15);
  // Seen from the element frame it is diag(rhoJ) L0/2.
  const Mat3 Jelem = e.beam.C1.transpose() * I1.J * e.beam.C1;
  EXPECT_LT((Jelem - Mat3(Vec3(0.03, 0.01, 0.02).asDiagonal()) * 0.5 * e.beam.L0).norm(), 1e-15);
}
