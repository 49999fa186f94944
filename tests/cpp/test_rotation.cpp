// SO(3) maps against their definitions and finite differences.
#include <gtest/gtest.h>

#include <random>

#include "math/rotation.hpp"

using namespace mfbd;

namespace {
Vec3 randomVector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return Vec3(u(rng), u(rng), u(rng)) * scale;
}
}  // namespace

TEST(Rotation, ExpIsOrthogonalAndLogInvertsIt) {
  std::mt19937 rng(1);
  for (double scale : {1e-9, 1e-5, 1e-2, 0.5, 1.5, 3.0}) {
    for (int k = 0; k < 50; ++k) {
      Vec3 theta = randomVector(rng, scale);
      if (theta.norm() > 3.1) theta *= 3.1 / theta.norm();
      const Mat3 R = expSO3(theta);
      EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), 1e-15 * 10);
      EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
      EXPECT_LT((logSO3(R) - theta).norm(), 1e-12 * std::max(1.0, theta.norm()));
    }
  }
}

TEST(Rotation, LogNearPiKeepsTheAxis) {
  const Vec3 axis = Vec3(1.0, -2.0, 0.5).normalized();
  for (double angle : {M_PI - 1e-3, M_PI - 1e-7, M_PI}) {
    const Vec3 theta = logSO3(expSO3(axis * angle));
    EXPECT_NEAR(theta.norm(), angle, 1e-9);
    EXPECT_LT((expSO3(theta) - expSO3(axis * angle)).norm(), 1e-12);
  }
}

TEST(Rotation, TangentOperatorMatchesFiniteDifferences) {
  // exp(theta + d) = exp(theta) exp(T(theta) d) + O(d^2)
  std::mt19937 rng(2);
  for (int k = 0; k < 30; ++k) {
    const Vec3 theta = randomVector(rng, k < 5 ? 1e-6 : 2.5);
    const Mat3 T = tangentSO3(theta);
    Mat3 fd;
    const double h = 1e-6;
    for (int i = 0; i < 3; ++i) {
      const Vec3 e = Vec3::Unit(i) * h;
      const Mat3 dR = expSO3(theta).transpose() * expSO3(theta + e) - (expSO3(theta).transpose() * expSO3(theta - e));
      fd.col(i) = unskew(dR) / (2.0 * h);
    }
    EXPECT_LT((T - fd).norm(), 1e-8);
    EXPECT_LT((tangentSO3Inverse(theta) * T - Mat3::Identity()).norm(), 1e-12);
  }
}

TEST(Rotation, ManyIncrementsStayOrthogonal) {
  // A million incremental updates as the solver makes them: the exact map,
  // then the polar step of an accepted time step.
  Mat3 R = Mat3::Identity();
  const Vec3 w(0.3, -1.1, 2.0);
  for (int i = 0; i < 1000000; ++i) R = polarStep(R * expSO3(w * 1e-3));
  EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), 1e-13);
  // ... and still the rotation the exact map gives (1000 s at |w| rad/s).
  EXPECT_LT((R - expSO3(w * 1000.0)).norm(), 1e-8);
}
