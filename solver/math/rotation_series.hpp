// The scalar coefficients of the rotation formulas (math/rotation.hpp) and
// the small-angle series that replace their closed forms where those lose
// digits to cancellation, written once: over double, and where the
// vectorised beam kernel needs them over Lanes (math/lanes.hpp), where a
// series is taken only when it holds in every lane.
//
// exp(S) = I + a S + b S^2,  T(theta) = I - b S + c S^2,
//   a = sin t / t,  b = (1 - cos t) / t^2,  c = (t - sin t) / t^3;
// log: theta = (t / sin t) w with w = sin t n the skew part of R;
// T^-1(theta) = I + S/2 + e S^2,  e = (1 - (t/2) cot(t/2)) / t^2,
// and e'(t)/t for its derivative (S = skew(theta), t = |theta|).
#pragma once
#include <cmath>

#include "math/lanes.hpp"

namespace mfbd {

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
    // Taylor series in t^2, up to t^10 for t < 0.2, t^6 for t < 0.01, t^4
    // for t < 1e-3: the first omitted term is below 1e-18 relative in each
    // range.
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

// t / sin(t) = asin(s) / s = sum_n c_n s^2n from s^2 = sin(t)^2, for
// s^2 < kArcsineSeriesLimit and cos t > 0 (t < ~0.2: the local rotations of
// a beam element, the relative rotations of a Newton step), without atan2;
// c_n = c_(n-1) (2n-1)^2 / (2n (2n+1)), to s^20 (first omitted term below
// 1e-17 relative).
constexpr double kArcsineSeriesLimit = 0.04;

template <class T>
inline T arcsineRatio(const T& s2) {
  static constexpr double c[11] = {1.0, 1.0 / 6.0, 3.0 / 40.0, 5.0 / 112.0, 35.0 / 1152.0, 63.0 / 2816.0,
                                   231.0 / 13312.0, 143.0 / 10240.0, 6435.0 / 557056.0, 12155.0 / 1245184.0,
                                   46189.0 / 5505024.0};
  // Below 1e-3 rad three terms reach 1e-19 (the usual case); above, the
  // series in two halves (Estrin) for a shorter dependency chain.
  if (allLess(s2, 1e-6)) return T(c[0]) + s2 * (T(c[1]) + s2 * T(c[2]));
  const T s4 = s2 * s2, s10 = s4 * s4 * s2;
  const T low = (T(c[0]) + s2 * T(c[1])) + s4 * ((T(c[2]) + s2 * T(c[3])) + s4 * T(c[4]));
  const T high = (T(c[5]) + s2 * T(c[6])) + s4 * ((T(c[7]) + s2 * T(c[8])) + s4 * (T(c[9]) + s2 * T(c[10])));
  return low + s10 * high;
}

// e(t) of T^-1 and e'(t)/t, from t2 = t^2. The closed forms cancel for small
// t (e'/t: terms of size 2/t^4 cancel to 1/360, ~1e-9 lost at t = 0.3);
// below t = 0.3 the Taylor series from x cot x = sum (-4)^n B_2n x^2n /
// (2n)! (Bernoulli numbers, x = t/2): e = sum_n |B_2n| / (2n)! t^(2n-2),
// to t^14 (consecutive terms shrink by ~t^2 / (2 pi)^2, so the first
// omitted one is below 1e-17 relative in e and in e'/t).
struct InverseTangentCoefficients {
  double e = 0.0, dEoverT = 0.0;
};

inline InverseTangentCoefficients inverseTangentCoefficients(double t2) {
  InverseTangentCoefficients k;
  if (t2 < 0.09) {  // t < 0.3
    // t^2 .. t^14 of e
    const double c[7] = {1.0 / 720.0, 1.0 / 30240.0, 1.0 / 1209600.0, 1.0 / 47900160.0,
                         691.0 / 1307674368000.0, 1.0 / 74724249600.0, 3617.0 / 10670622842880000.0};
    double e = c[6], dEoverT = 14 * c[6];
    for (int n = 5; n >= 0; --n) {
      e = e * t2 + c[n];
      dEoverT = dEoverT * t2 + 2 * (n + 1) * c[n];
    }
    k.e = 1.0 / 12.0 + t2 * e;
    k.dEoverT = dEoverT;
  } else {
    const double t = std::sqrt(t2), cotHalf = 1.0 / std::tan(0.5 * t), sinHalf = std::sin(0.5 * t);
    k.e = (1.0 - 0.5 * t * cotHalf) / t2;
    k.dEoverT = -2.0 / (t2 * t2) + cotHalf / (2.0 * t2 * t) + 1.0 / (4.0 * t2 * sinHalf * sinHalf);
  }
  return k;
}

// e alone, for T^-1 itself: below t = 0.01 three terms (next below 1e-17
// relative), beyond that inverseTangentCoefficients (lane by lane).
template <class T>
inline T inverseTangentE(const T& t2) {
  if (allLess(t2, 1e-4)) return T(1.0 / 12.0) + t2 * (T(1.0 / 720.0) + t2 * T(1.0 / 30240.0));
  return eachLane(t2, [](double x) { return inverseTangentCoefficients(x).e; });
}

// T^-1(theta) y and T^-T y, e = inverseTangentE(t^2), without forming T^-1 = e theta theta^T + S/2 + (1 - e t^2) I.
template <class T>
Vector3<T> inverseTangentTimes(const Vector3<T>& theta, const T& e, const Vector3<T>& y, bool transposed) {
  const Vector3<T> half = T(0.5) * cross(theta, y);
  return (T(1.0) - e * squaredNorm(theta)) * y + (e * dot(theta, y)) * theta + (transposed ? -half : half);
}

// log(Rr^T R), Rr = [e1 e2 e3] and R rotations (columns): the relative
// rotation vector, from the trace and the skew part of Rr^T R without
// forming the product, by arcsineRatio where that holds (in every lane),
// else by logSO3 (lane by lane).
Vector3<double> relativeRotationVectorExact(const Vector3<double>& e1, const Vector3<double>& e2,
                                            const Vector3<double>& e3, const Matrix3<double>& R);

inline Vector3<Lanes> relativeRotationVectorExact(const Vector3<Lanes>& e1, const Vector3<Lanes>& e2,
                                                  const Vector3<Lanes>& e3, const Matrix3<Lanes>& R) {
  Vector3<Lanes> out;
  for (int i = 0; i < Lanes::kCount; ++i)
    setLane(out, i, relativeRotationVectorExact(lane(e1, i), lane(e2, i), lane(e3, i), lane(R, i)));
  return out;
}

template <class T>
Vector3<T> relativeRotationVector(const Vector3<T>& e1, const Vector3<T>& e2, const Vector3<T>& e3,
                                  const Matrix3<T>& R) {
  const Vector3<T>&c0 = R.col[0], &c1 = R.col[1], &c2 = R.col[2];
  const T cosT = (dot(e1, c0) + dot(e2, c1) + dot(e3, c2) - T(1.0)) * T(0.5);
  const Vector3<T> w{T(0.5) * (dot(e3, c1) - dot(e2, c2)), T(0.5) * (dot(e1, c2) - dot(e3, c0)),
                     T(0.5) * (dot(e2, c0) - dot(e1, c1))};
  const T s2 = squaredNorm(w);
  if (!(allGreater(cosT, 0.0) && allLess(s2, kArcsineSeriesLimit))) return relativeRotationVectorExact(e1, e2, e3, R);
  return arcsineRatio(s2) * w;
}

}  // namespace mfbd
