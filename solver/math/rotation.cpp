#include "math/rotation.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace mfbd {

Mat3 skew(const Vec3& a) {
  Mat3 S;
  S << 0.0, -a.z(), a.y(),
       a.z(), 0.0, -a.x(),
      -a.y(), a.x(), 0.0;
  return S;
}

Vec3 unskew(const Mat3& S) {
  return Vec3(S(2, 1) - S(1, 2), S(0, 2) - S(2, 0), S(1, 0) - S(0, 1)) * 0.5;
}

namespace {
// Coefficients of exp/T with Taylor series below a small angle, where the
// closed forms lose digits to cancellation.
struct ExpCoefficients {
  double a;  // sin(t)/t
  double b;  // (1-cos t)/t^2
  double c;  // (t - sin t)/t^3
};

ExpCoefficients expCoefficients(double t) {
  const double t2 = t * t;
  if (t < 1e-4) {
    return {1.0 - t2 / 6.0 + t2 * t2 / 120.0, 0.5 - t2 / 24.0 + t2 * t2 / 720.0,
            1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0};
  }
  const double s = std::sin(t), c = std::cos(t);
  return {s / t, (1.0 - c) / t2, (t - s) / (t2 * t)};
}
}  // namespace

Mat3 expSO3(const Vec3& theta) {
  const ExpCoefficients k = expCoefficients(theta.norm());
  const Mat3 S = skew(theta);
  return Mat3::Identity() + k.a * S + k.b * S * S;
}

Vec3 logSO3(const Mat3& R) {
  const double cosT = std::clamp((R.trace() - 1.0) * 0.5, -1.0, 1.0);
  const Vec3 w = unskew(R);  // = sin(t) * axis
  const double sinT = w.norm();
  const double t = std::atan2(sinT, cosT);
  if (t < 1e-4) return w * (1.0 + t * t / 6.0);  // t/sin(t) by series
  if (t < 3.0) return w * (t / sinT);
  // Near pi, sin(t) is tiny: take the axis from the symmetric part,
  // R + R^T = 2 cos t I + 2 (1 - cos t) n n^T, and its sign from w.
  const Mat3 B = (R + R.transpose()) * 0.5 - cosT * Mat3::Identity();
  int k;
  B.diagonal().maxCoeff(&k);
  Vec3 n = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
  n.normalize();
  if (n.dot(w) < 0.0) n = -n;
  return n * t;
}

Mat3 tangentSO3(const Vec3& theta) {
  const ExpCoefficients k = expCoefficients(theta.norm());
  const Mat3 S = skew(theta);
  return Mat3::Identity() - k.b * S + k.c * S * S;
}

Mat3 tangentSO3Inverse(const Vec3& theta) {
  const double t = theta.norm();
  const Mat3 S = skew(theta);
  // T^-1 = I + S/2 + (1/t^2)(1 - (t/2) cot(t/2)) S^2
  double e;
  if (t < 1e-4) {
    e = 1.0 / 12.0 + t * t / 720.0;
  } else {
    e = (1.0 - 0.5 * t / std::tan(0.5 * t)) / (t * t);
  }
  return Mat3::Identity() + 0.5 * S + e * S * S;
}

Mat3 rotateIncrementally(const Mat3& R, const Vec3& theta) {
  const Mat3 Rn = R * expSO3(theta);
  return 0.5 * Rn * (3.0 * Mat3::Identity() - Rn.transpose() * Rn);
}

Mat3 nearestRotation(const Mat3& M) {
  Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

Mat3 frameFromZAxis(const Vec3& zIn) {
  const Vec3 z = zIn.normalized();
  // Seed x with the global axis least aligned with z.
  Vec3 seed = Vec3::UnitX();
  if (std::abs(z.x()) > 0.9) seed = Vec3::UnitY();
  const Vec3 x = (seed - seed.dot(z) * z).normalized();
  Mat3 A;
  A.col(0) = x;
  A.col(1) = z.cross(x);
  A.col(2) = z;
  return A;
}

}  // namespace mfbd
