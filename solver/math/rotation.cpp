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

// From the squared angle: the series need no square root, and small
// increments (every Newton correction) need few terms. withC: also c
// (only the tangent operator needs it, not the exponential map).
template <bool withC>
inline ExpCoefficients expCoefficients(double t2) {
  if (t2 < 0.04) {
    // Taylor series in t^2 (no sin/cos), more accurate than the closed
    // forms, which cancel as t -> 0. Up to t^10 for t < 0.2, t^6 for
    // t < 0.01, t^4 for t < 1e-3: the first omitted term is below 1e-18
    // relative in each range.
    static constexpr double a[6] = {1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0};
    static constexpr double b[6] = {1.0 / 2.0, -1.0 / 24.0, 1.0 / 720.0, -1.0 / 40320.0, 1.0 / 3628800.0,
                                    -1.0 / 479001600.0};
    static constexpr double c[6] = {1.0 / 6.0, -1.0 / 120.0, 1.0 / 5040.0, -1.0 / 362880.0, 1.0 / 39916800.0,
                                    -1.0 / 6227020800.0};
    const int last = t2 < 1e-6 ? 2 : t2 < 1e-4 ? 3 : 5;
    auto series = [t2, last](const double* k) {  // sum_n k_n t^2n, Horner
      double sum = k[last];
      for (int n = last - 1; n >= 0; --n) sum = sum * t2 + k[n];
      return sum;
    };
    return {series(a), series(b), withC ? series(c) : 0.0};
  }
  const double t = std::sqrt(t2);
  const double s = std::sin(t), c = std::cos(t);
  return {s / t, (1.0 - c) / t2, (t - s) / (t2 * t)};
}
}  // namespace

Mat3 expSO3(const Vec3& theta) {
  const double t2 = theta.squaredNorm();
  const ExpCoefficients k = expCoefficients<false>(t2);
  // I + a S + b S^2 with S^2 = theta theta^T - t^2 I (no 3 x 3 product).
  Mat3 E = (k.b * theta) * theta.transpose();
  E.diagonal().array() += 1.0 - k.b * t2;
  const Vec3 as = k.a * theta;
  E(0, 1) -= as.z();
  E(1, 0) += as.z();
  E(0, 2) += as.y();
  E(2, 0) -= as.y();
  E(1, 2) -= as.x();
  E(2, 1) += as.x();
  return E;
}

Vec3 logSO3(const Mat3& R) {
  const double cosT = std::clamp((R.trace() - 1.0) * 0.5, -1.0, 1.0);
  const Vec3 w = unskew(R);  // = sin(t) * axis
  const double s2 = w.squaredNorm();
  if (cosT > 0.0 && s2 < 0.04) {
    // t < ~0.2 (the local rotations of a beam element, the relative
    // rotations of a Newton step): t / sin(t) = asin(s)/s = sum_n c_n s^2n,
    // c_n = c_(n-1) (2n-1)^2 / (2n (2n+1)), to s^20 (first omitted term
    // below 1e-17 relative), without atan2.
    static constexpr double c[11] = {1.0, 1.0 / 6.0, 3.0 / 40.0, 5.0 / 112.0, 35.0 / 1152.0, 63.0 / 2816.0,
                                     231.0 / 13312.0, 143.0 / 10240.0, 6435.0 / 557056.0, 12155.0 / 1245184.0,
                                     46189.0 / 5505024.0};
    double f = c[10];
    for (int n = 9; n >= 0; --n) f = f * s2 + c[n];
    return w * f;
  }
  const double sinT = std::sqrt(s2);
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
  const ExpCoefficients k = expCoefficients<true>(theta.squaredNorm());
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

Mat3 polarStep(const Mat3& R) { return 0.5 * R * (3.0 * Mat3::Identity() - R.transpose() * R); }

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
