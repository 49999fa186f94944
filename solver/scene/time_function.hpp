// A function of time given by the scene: an expression of t over the scene's
// parameters ("6*t", "if(15 - t, ..., ...)"), or a table of (t, value)
// points. Used for load scales, driven supports of flexible nodes and rigid
// joint drives, whose rate and acceleration are used too.
#pragma once
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "scene/expression.hpp"

namespace mfbd {

class TimeFunction {
 public:
  TimeFunction() = default;  // the constant 1
  // Throws std::invalid_argument naming the offending token.
  TimeFunction(const std::string& expression, const std::map<std::string, double>& parameters);

  // The C2 cubic spline through the points (times[i], values[i]) with zero
  // slope at both ends, held at the end values outside [times.front(),
  // times.back()]. Zero end slopes because the held values have zero rate:
  // value and rate are then continuous for all t (a rate jump at a table's
  // end would be an infinite acceleration of a drive); the acceleration is
  // continuous inside the table. A table sampled from a smooth function
  // that is at rest at both ends is reproduced to O(dt^4) (rate O(dt^3),
  // acceleration O(dt^2)). Two points give the smooth step between them.
  // Throws std::invalid_argument (naming the point) for fewer than 2 points,
  // sizes that differ, times not strictly increasing or non-finite numbers.
  static TimeFunction table(const std::vector<double>& times, const std::vector<double>& values);

  double operator()(double t) const;
  // d/dt and d2/dt2, exact (the spline's, or the expression's by
  // forward-mode differentiation); jet: all three at once.
  double rate(double t) const;
  double acceleration(double t) const;
  Expression::Jet jet(double t) const;
  // The jet kept for the last time asked: the many residuals of a substep
  // all ask at its end time. Workspace of whoever asks (a pure function of
  // t, nothing to save with a state).
  struct Sample {
    double t = std::numeric_limits<double>::quiet_NaN();
    Expression::Jet jet;
  };
  const Expression::Jet& jet(double t, Sample& kept) const;

 private:
  // The table spline's value, rate and acceleration at t.
  Expression::Jet spline(double t) const;

  Expression expression_;
  std::vector<double> times_, values_, moments_;  // table: moments = second derivatives at the points
};

}  // namespace mfbd
