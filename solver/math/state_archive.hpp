// Byte archive of the solver's mutable state (FMU state save and restore).
// Each class lists the members that influence its next result once, in
//   template <class Archive> void visitState(Archive& ar) { ar(a, b, c); }
// StateWriter appends them, StateReader reads them back in the same order,
// so a member added later is one line. Doubles are copied as bytes: a
// restored state continues bit for bit. Native byte order (x86-64, both
// binaries); the FMU layer frames the bytes with a header and checksum.
#pragma once
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

namespace mfbd {

// A blob that does not parse (truncated, or sizes out of range).
struct StateError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class StateWriter {
 public:
  explicit StateWriter(std::vector<unsigned char>& out) : out_(out) {}

  template <class... T>
  void operator()(T&... x) {
    (put(x), ...);
  }

 private:
  template <class T>
  void put(T& x) {
    if constexpr (std::is_arithmetic_v<T>) {
      raw(&x, sizeof x);
    } else if constexpr (std::is_base_of_v<Eigen::PlainObjectBase<T>, T>) {
      count(x.rows());
      count(x.cols());
      raw(x.data(), sizeof(typename T::Scalar) * std::size_t(x.size()));
    } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
      put(x.coeffs());
    } else {
      x.visitState(*this);
    }
  }
  template <class T>
  void put(std::vector<T>& v) {
    count(v.size());
    for (T& x : v) put(x);
  }
  void put(std::pair<int, int>& x) { put(x.first), put(x.second); }
  void put(std::vector<bool>& v) {
    count(v.size());
    for (bool b : v) put(b);
  }
  void put(Eigen::SparseMatrix<double, Eigen::ColMajor, int>& A) {
    A.makeCompressed();
    count(A.rows());
    count(A.cols());
    count(A.nonZeros());
    raw(A.outerIndexPtr(), sizeof(int) * std::size_t(A.cols() + 1));
    raw(A.innerIndexPtr(), sizeof(int) * std::size_t(A.nonZeros()));
    raw(A.valuePtr(), sizeof(double) * std::size_t(A.nonZeros()));
  }
  void count(long long n) { raw(&n, sizeof n); }
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    out_.insert(out_.end(), b, b + n);
  }
  std::vector<unsigned char>& out_;
};

class StateReader {
 public:
  StateReader(const unsigned char* data, std::size_t size) : p_(data), end_(data + size) {}

  template <class... T>
  void operator()(T&... x) {
    (get(x), ...);
  }
  bool atEnd() const { return p_ == end_; }

 private:
  template <class T>
  void get(T& x) {
    if constexpr (std::is_same_v<T, bool>) {
      unsigned char b;
      raw(&b, 1);
      if (b > 1) throw StateError("a flag is neither 0 nor 1");
      x = b == 1;
    } else if constexpr (std::is_arithmetic_v<T>) {
      raw(&x, sizeof x);
    } else if constexpr (std::is_base_of_v<Eigen::PlainObjectBase<T>, T>) {
      // A dimension alone may exceed the bytes left (an empty column vector
      // is 0 x 1, last in a state): its elements' bytes may not.
      const long long rows = dimension(), cols = dimension();
      const long long elements = remaining() / static_cast<long long>(sizeof(typename T::Scalar));
      if ((T::RowsAtCompileTime != Eigen::Dynamic && rows != T::RowsAtCompileTime) ||
          (T::ColsAtCompileTime != Eigen::Dynamic && cols != T::ColsAtCompileTime) ||
          (cols > 0 && rows > elements / cols) || (rows > 0 && cols > elements / rows))
        throw StateError("a matrix has the wrong size");
      x.resize(rows, cols);
      raw(x.data(), sizeof(typename T::Scalar) * std::size_t(x.size()));
    } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
      get(x.coeffs());
    } else {
      x.visitState(*this);
    }
  }
  template <class T>
  void get(std::vector<T>& v) {
    v.resize(std::size_t(count()));
    for (T& x : v) get(x);
  }
  void get(std::pair<int, int>& x) { get(x.first), get(x.second); }
  void get(std::vector<bool>& v) {
    v.resize(std::size_t(count()));
    for (std::size_t i = 0; i < v.size(); ++i) {
      bool b;
      get(b);
      v[i] = b;
    }
  }
  void get(Eigen::SparseMatrix<double, Eigen::ColMajor, int>& A) {
    const long long rows = count(), cols = count(), nonZeros = count();
    if (cols + 1 > remaining() / 4 || nonZeros > remaining() / 12) throw StateError("a sparse matrix is truncated");
    A.resize(rows, cols);
    A.resizeNonZeros(nonZeros);
    raw(A.outerIndexPtr(), sizeof(int) * std::size_t(cols + 1));
    raw(A.innerIndexPtr(), sizeof(int) * std::size_t(nonZeros));
    raw(A.valuePtr(), sizeof(double) * std::size_t(nonZeros));
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    bool valid = outer[0] == 0 && outer[cols] == nonZeros;
    for (long long j = 0; valid && j < cols; ++j) {
      valid = outer[j] <= outer[j + 1];
      for (int k = outer[j]; valid && k < outer[j + 1]; ++k) valid = inner[k] >= 0 && inner[k] < rows;
    }
    if (!valid) throw StateError("a sparse matrix has an invalid pattern");
  }
  // A count, checked against the bytes left (every element takes one at least).
  long long count() {
    long long n;
    raw(&n, sizeof n);
    if (n < 0 || n > remaining()) throw StateError("a size exceeds the state's length");
    return n;
  }
  long long dimension() {
    long long n;
    raw(&n, sizeof n);
    if (n < 0) throw StateError("a matrix has a negative dimension");
    return n;
  }
  long long remaining() const { return static_cast<long long>(end_ - p_); }
  void raw(void* dst, std::size_t n) {
    if (n > std::size_t(end_ - p_)) throw StateError("the state ends early");
    if (n > 0) std::memcpy(dst, p_, n);
    p_ += n;
  }
  const unsigned char* p_;
  const unsigned char* end_;
};

}  // namespace mfbd
