#include "scene/time_function.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "math/number_text.hpp"

namespace mfbd {

TimeFunction::TimeFunction(const std::string& expression, const std::map<std::string, double>& parameters)
    : expression_(expression, parameters, "t") {}

// Moments M_i = S''(t_i) of the clamped spline (S' = 0 at both ends) from
// the tridiagonal system of slope continuity (de Boor, "A practical guide to
// splines", ch. IV), h_i = t_{i+1} - t_i, d_i = (y_{i+1} - y_i) / h_i:
//   2 h_0 M_0 + h_0 M_1                                    = 6 d_0
//   h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1}  = 6 (d_i - d_{i-1})
//   h_{n-1} M_{n-1} + 2 h_{n-1} M_n                        = -6 d_{n-1}
// solved by the Thomas algorithm (diagonally dominant: no pivoting needed).
TimeFunction TimeFunction::table(const std::vector<double>& times, const std::vector<double>& values) {
  const std::size_t n = times.size();
  if (n < 2) throw std::invalid_argument("expected at least 2 [t, value] points, got " + std::to_string(n));
  if (values.size() != n) throw std::invalid_argument("expected as many values as times");
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(times[i]) || !std::isfinite(values[i]))
      throw std::invalid_argument("point " + std::to_string(i) + ": expected finite numbers");
    if (i > 0 && !(times[i] > times[i - 1]))
      throw std::invalid_argument("point " + std::to_string(i) + ": expected times increasing, got " +
                                  numberText(times[i]) + " after " + numberText(times[i - 1]));
  }
  std::vector<double> h(n - 1), d(n - 1), diagonal(n), upper(n), rhs(n);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    h[i] = times[i + 1] - times[i];
    d[i] = (values[i + 1] - values[i]) / h[i];
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double left = i > 0 ? h[i - 1] : 0.0, right = i + 1 < n ? h[i] : 0.0;
    diagonal[i] = 2.0 * (left + right);
    upper[i] = right;  // lower[i] = left = upper[i - 1]
    rhs[i] = 6.0 * ((i + 1 < n ? d[i] : 0.0) - (i > 0 ? d[i - 1] : 0.0));
  }
  for (std::size_t i = 1; i < n; ++i) {  // eliminate the lower diagonal h_{i-1}
    const double factor = h[i - 1] / diagonal[i - 1];
    diagonal[i] -= factor * upper[i - 1];
    rhs[i] -= factor * rhs[i - 1];
  }
  TimeFunction f;
  f.times_ = times;
  f.values_ = values;
  f.moments_.assign(n, 0.0);
  for (std::size_t i = n; i-- > 0;)
    f.moments_[i] = (rhs[i] - (i + 1 < n ? upper[i] * f.moments_[i + 1] : 0.0)) / diagonal[i];
  return f;
}

// On [t_i, t_{i+1}] with a = t_{i+1} - t, b = t - t_i:
//   S = M_i a^3/(6h) + M_{i+1} b^3/(6h) + (y_i/h - M_i h/6) a + (y_{i+1}/h - M_{i+1} h/6) b.
Expression::Jet TimeFunction::spline(double t) const {
  if (t <= times_.front()) return {values_.front(), 0.0, 0.0};
  if (t >= times_.back()) return {values_.back(), 0.0, 0.0};
  const std::size_t i = std::size_t(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1;
  const double h = times_[i + 1] - times_[i], a = times_[i + 1] - t, b = t - times_[i];
  const double Mi = moments_[i], Mj = moments_[i + 1];
  const double ci = values_[i] / h - Mi * h / 6.0, cj = values_[i + 1] / h - Mj * h / 6.0;
  return {(Mi * a * a * a + Mj * b * b * b) / (6.0 * h) + ci * a + cj * b,
          (Mj * b * b - Mi * a * a) / (2.0 * h) + cj - ci, (Mi * a + Mj * b) / h};
}

double TimeFunction::operator()(double t) const {
  return times_.empty() ? expression_(t) : spline(t).value;
}

double TimeFunction::rate(double t) const { return jet(t).first; }

double TimeFunction::acceleration(double t) const { return jet(t).second; }

Expression::Jet TimeFunction::jet(double t) const {
  if (!times_.empty()) return spline(t);
  return expression_.jet(t);
}

const Expression::Jet& TimeFunction::jet(double t, Sample& kept) const {
  if (!(kept.t == t)) kept = {t, jet(t)};
  return kept.jet;
}

}  // namespace mfbd
