// Kernels written once for one element (T = double) and for four at a time
// (T = Lanes: four doubles in one vector register, GCC's vector extension):
// the small 3-vector and 3 x 3 algebra they need, and the few lane-wise
// decisions (a series that holds in every lane, a check that every lane
// passed). One element's 3-vectors fill vector registers badly (three
// entries in packets of two or four) and chain long latencies (a square
// root, a division) one element after the other; four elements side by side
// fill the registers and share every latency. An operation on four lanes is
// two SSE2 instructions on the baseline x86-64, one with AVX2 (a kernel may
// be compiled for both, see elementForceVectors).
#pragma once
#include <cmath>

namespace mfbd {

struct Lanes {
  static constexpr int kCount = 4;
  using Raw = double __attribute__((vector_size(32)));
  Raw v;
  Lanes() = default;
  Lanes(double x) : v{x, x, x, x} {}  // a constant, in every lane
  explicit Lanes(Raw raw) : v(raw) {}
  double operator[](int i) const { return v[i]; }
  void set(int i, double x) { v[i] = x; }
};

inline Lanes operator+(Lanes a, Lanes b) { return Lanes(a.v + b.v); }
inline Lanes operator-(Lanes a, Lanes b) { return Lanes(a.v - b.v); }
inline Lanes operator*(Lanes a, Lanes b) { return Lanes(a.v * b.v); }
inline Lanes operator/(Lanes a, Lanes b) { return Lanes(a.v / b.v); }
inline Lanes operator-(Lanes a) { return Lanes(-a.v); }
inline Lanes sqrt(Lanes a) {
  Lanes r;
  for (int i = 0; i < Lanes::kCount; ++i) r.v[i] = std::sqrt(a.v[i]);
  return r;
}

// Lane-wise tests that hold when they hold in every lane.
inline bool allLess(double a, double b) { return a < b; }
inline bool allLess(Lanes a, double b) {
  for (int i = 0; i < Lanes::kCount; ++i)
    if (!(a.v[i] < b)) return false;
  return true;
}
inline bool allGreater(double a, double b) { return a > b; }
inline bool allGreater(Lanes a, double b) {
  for (int i = 0; i < Lanes::kCount; ++i)
    if (!(a.v[i] > b)) return false;
  return true;
}
inline bool allFinite(double a) { return std::isfinite(a); }
inline bool allFinite(Lanes a) {
  const Lanes zero(a.v - a.v);  // 0 where finite, NaN elsewhere
  for (int i = 0; i < Lanes::kCount; ++i)
    if (!(zero.v[i] == 0.0)) return false;
  return true;
}
inline bool allZero(double a) { return a == 0.0; }
inline bool allZero(Lanes a) {
  for (int i = 0; i < Lanes::kCount; ++i)
    if (a.v[i] != 0.0) return false;
  return true;
}

// f applied to each lane (a scalar function the kernels take lane by lane).
template <class F>
inline double eachLane(double a, F f) {
  return f(a);
}
template <class F>
inline Lanes eachLane(Lanes a, F f) {
  Lanes r;
  for (int i = 0; i < Lanes::kCount; ++i) r.set(i, f(a[i]));
  return r;
}

template <class T>
struct Vector3 {
  T x, y, z;
};

template <class T>
inline Vector3<T> operator+(const Vector3<T>& a, const Vector3<T>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class T>
inline Vector3<T> operator-(const Vector3<T>& a, const Vector3<T>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class T>
inline Vector3<T> operator-(const Vector3<T>& a) {
  return {-a.x, -a.y, -a.z};
}
template <class T>
inline Vector3<T> operator*(const T& s, const Vector3<T>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class T>
inline Vector3<T> operator/(const Vector3<T>& a, const T& s) {
  return {a.x / s, a.y / s, a.z / s};
}
template <class T>
inline T dot(const Vector3<T>& a, const Vector3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
inline T squaredNorm(const Vector3<T>& a) {
  return dot(a, a);
}
template <class T>
inline Vector3<T> cross(const Vector3<T>& a, const Vector3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// Column-major: the three columns.
template <class T>
struct Matrix3 {
  Vector3<T> col[3];
};

template <class T>
inline Vector3<T> operator*(const Matrix3<T>& M, const Vector3<T>& a) {
  return a.x * M.col[0] + a.y * M.col[1] + a.z * M.col[2];
}
// M^T a
template <class T>
inline Vector3<T> transposeTimes(const Matrix3<T>& M, const Vector3<T>& a) {
  return {dot(M.col[0], a), dot(M.col[1], a), dot(M.col[2], a)};
}

// Lane i of a vector of lanes, and lane i set from one element's vector.
inline Vector3<double> lane(const Vector3<Lanes>& a, int i) { return {a.x[i], a.y[i], a.z[i]}; }
inline void setLane(Vector3<Lanes>& a, int i, const Vector3<double>& b) {
  a.x.set(i, b.x);
  a.y.set(i, b.y);
  a.z.set(i, b.z);
}
inline Matrix3<double> lane(const Matrix3<Lanes>& M, int i) {
  return {{lane(M.col[0], i), lane(M.col[1], i), lane(M.col[2], i)}};
}

}  // namespace mfbd
