// SO(3) maps against their definitions and finite differences.
#include <gtest/gtest.h>

#include <random>

#include <quadmath.h>

#include <algorithm>
#include <cmath>

#include "math/rotation.hpp"
#include "math/rotation_series.hpp"

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

// ---------------------------------------------------------------------------
// The coefficients of math/rotation_series.hpp against their closed forms
// evaluated in quadruple precision (__float128: 113-bit significand), so
// the reference holds to far below a double's ulp even where the closed
// forms cancel. Near 0 the series: a few ulp. Away from 0 the closed forms
// in double, which lose digits to cancellation in proportion to how small
// the result is against its terms: the stated tolerances.
// ---------------------------------------------------------------------------
namespace {

constexpr double kUlp = 2.220446049250313e-16;

double relative(double value, __float128 reference) {
  return double(fabsq((__float128(value) - reference) / reference));
}

// Angles from 1e-6 rad to 3 rad: every branch of every series (the short
// ones below 1e-3 / 1e-2 rad, the long ones, the switches at 0.2 and 0.3)
// and the closed forms.
const double kAngles[] = {1e-6, 3e-5, 9.9e-4, 1.01e-3, 4e-3, 9.9e-3, 0.0101, 0.05, 0.1, 0.1999,
                          0.2001, 0.25, 0.2999, 0.3001, 0.5, 1.0, 2.0, 3.0};

}  // namespace

TEST(RotationSeries, ExpCoefficientsMatchTheClosedForms) {
  for (const double t : kAngles) {
    const double t2 = t * t;
    const ExpCoefficients k = expCoefficients<true>(t2);
    const __float128 tq = sqrtq(__float128(t2)), sinHalf = sinq(tq / 2);
    const __float128 a = sinq(tq) / tq, b = 2 * sinHalf * sinHalf / (tq * tq), c = (tq - sinq(tq)) / (tq * tq * tq);
    // Series below t = 0.2; beyond, (1 - cos t) and (t - sin t) cancel.
    const double tolerance = t2 < 0.04 ? 4 * kUlp : 1e-13;
    EXPECT_LT(relative(k.a, a), tolerance) << "t = " << t;
    EXPECT_LT(relative(k.b, b), tolerance) << "t = " << t;
    EXPECT_LT(relative(k.c, c), tolerance) << "t = " << t;
  }
}

TEST(RotationSeries, ArcsineRatioMatchesAsinOverS) {
  for (const double t : kAngles) {
    if (!(t < 0.2)) continue;  // the series' range: s^2 < 0.04
    const double s = std::sin(t), s2 = s * s;
    const __float128 sq = sqrtq(__float128(s2));
    EXPECT_LT(relative(arcsineRatio(s2), asinq(sq) / sq), 4 * kUlp) << "t = " << t;
  }
}

TEST(RotationSeries, InverseTangentCoefficientsMatchTheClosedForms) {
  for (const double t : kAngles) {
    const double t2 = t * t;
    const InverseTangentCoefficients k = inverseTangentCoefficients(t2);
    const __float128 tq = sqrtq(__float128(t2)), t2q = __float128(t2);
    const __float128 cotHalf = 1 / tanq(tq / 2), sinHalf = sinq(tq / 2);
    const __float128 e = (1 - tq / 2 * cotHalf) / t2q;
    const __float128 dEoverT = -2 / (t2q * t2q) + cotHalf / (2 * t2q * tq) + 1 / (4 * t2q * sinHalf * sinHalf);
    // Series below t = 0.3; beyond, e's closed form cancels like t^2 / 12
    // against 1, e'/t's terms of size 2/t^4 against 1/360.
    const bool series = t2 < 0.09;
    EXPECT_LT(relative(k.e, e), series ? 4 * kUlp : 1e-13) << "t = " << t;
    // Below 1e-3 rad e'/t's closed form cancels beyond even quadruple
    // precision (2/t^4 against 1/360): there its leading terms 1/360 +
    // t^2/7560 + t^4/201600 (the next below 1e-20 relative) are the reference.
    const __float128 dReference = t < 1e-3 ? 1 / __float128(360) + t2q / 7560 + t2q * t2q / 201600 : dEoverT;
    EXPECT_LT(relative(k.dEoverT, dReference), series ? 4 * kUlp : 1e-10) << "t = " << t;
    EXPECT_LT(relative(inverseTangentE(t2), e), series ? 4 * kUlp : 1e-13) << "t = " << t;
  }
}

// The Lanes forms (the beam's four-lane kernel) give each lane what the
// double forms give, to the ulps of the series: lanes of mixed sizes take
// the series that holds in all of them.
TEST(RotationSeries, LanesGiveTheDoubleValues) {
  const double small[4] = {1e-4, 2e-4, 5e-5, 9e-4}, mixed[4] = {1e-4, 0.05, 0.15, 0.3};
  for (const double* angles : {small, mixed}) {
    Lanes t2;
    for (int i = 0; i < 4; ++i) t2.set(i, angles[i] * angles[i]);
    const Lanes e = inverseTangentE(t2);
    Lanes s2;
    for (int i = 0; i < 4; ++i) s2.set(i, std::pow(std::sin(std::min(angles[i], 0.19)), 2));
    const Lanes ratio = arcsineRatio(s2);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(e[i], inverseTangentE(t2[i]), 4 * kUlp * e[i]) << angles[i];
      EXPECT_NEAR(ratio[i], arcsineRatio(s2[i]), 4 * kUlp * ratio[i]) << angles[i];
    }
  }
}

// T^-1 (math/rotation_series.hpp's e) inverts T (its a, b, c) near 0 and
// away from it; the relative rotation vector of the beam kernel (series or
// log map) inverts the exponential map.
TEST(RotationSeries, InverseTangentAndRelativeRotationInvertTheirMaps) {
  std::mt19937 rng(7);
  for (const double t : kAngles) {
    const Vec3 theta = randomVector(rng, 1.0).normalized() * t;
    EXPECT_LT((tangentSO3Inverse(theta) * tangentSO3(theta) - Mat3::Identity()).norm(), 4 * kUlp) << t;
    const Mat3 Rr = expSO3(randomVector(rng, 2.0)), R = Rr * expSO3(theta);
    auto column = [](const Mat3& M, int j) { return Vector3<double>{M(0, j), M(1, j), M(2, j)}; };
    const Vector3<double> v = relativeRotationVector(column(Rr, 0), column(Rr, 1), column(Rr, 2),
                                                     Matrix3<double>{{column(R, 0), column(R, 1), column(R, 2)}});
    EXPECT_LT((Vec3(v.x, v.y, v.z) - theta).norm(), 8 * kUlp * std::max(1.0, t)) << t;
  }
}
