#include "math/rotation.hpp"

#include "math/rotation_series.hpp"

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
  if (cosT > 0.0 && s2 < kArcsineSeriesLimit) return w * arcsineRatio(s2);
  const double sinT = std::sqrt(s2);
  const double t = std::atan2(sinT, cosT);  // t > 0.2 here
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
  // with S^2 = theta theta^T - t^2 I (no 3 x 3 product)
  const double e = inverseTangentE(theta.squaredNorm());
  Mat3 Tinv = e * theta * theta.transpose() + 0.5 * skew(theta);
  Tinv.diagonal().array() += 1.0 - e * theta.squaredNorm();
  return Tinv;
}

Mat3 tangentSO3InverseDerivative(const Vec3& theta, const Vec3& x, bool transposed) {
  const InverseTangentCoefficients k = inverseTangentCoefficients(theta.squaredNorm());
  const Mat3 X = skew(x);
  const Vec3 SSx = theta.cross(theta.cross(x));
  return (transposed ? 0.5 : -0.5) * X - k.e * (skew(theta.cross(x)) + skew(theta) * X) +
         k.dEoverT * SSx * theta.transpose();
}

Vector3<double> relativeRotationVectorExact(const Vector3<double>& e1, const Vector3<double>& e2,
                                            const Vector3<double>& e3, const Matrix3<double>& R) {
  auto toEigen = [](const Vector3<double>& a) { return Vec3(a.x, a.y, a.z); };
  Mat3 Rr, A;
  Rr << toEigen(e1), toEigen(e2), toEigen(e3);
  A << toEigen(R.col[0]), toEigen(R.col[1]), toEigen(R.col[2]);
  const Vec3 theta = logSO3(Rr.transpose() * A);
  return {theta.x(), theta.y(), theta.z()};
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
