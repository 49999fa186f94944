// Scene expressions (compiled once, evaluated per call) and tabulated time
// functions (C2 cubic spline with zero end slopes, held outside the table).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "math/number_text.hpp"
#include "scene/time_function.hpp"

using namespace mfbd;

namespace {

constexpr double kPi = 3.14159265358979323846;

TimeFunction sampled(double (*f)(double), double t0, double t1, int intervals) {
  std::vector<double> t, y;
  for (int i = 0; i <= intervals; ++i) {
    t.push_back(t0 + (t1 - t0) * i / intervals);
    y.push_back(f(t.back()));
  }
  return TimeFunction::table(t, y);
}

// A cycloidal ramp from 0 to 1 over [0, 1]: at rest (zero rate and
// acceleration) at both ends.
double ramp(double t) { return t - std::sin(2 * kPi * t) / (2 * kPi); }
double rampRate(double t) { return 1 - std::cos(2 * kPi * t); }
double rampAcceleration(double t) { return 2 * kPi * std::sin(2 * kPi * t); }

struct Errors {
  double value = 0, rate = 0, acceleration = 0;
};

Errors maxErrors(const TimeFunction& f) {
  Errors e;
  for (int k = 0; k <= 1000; ++k) {
    const double t = k / 1000.0;
    e.value = std::max(e.value, std::abs(f(t) - ramp(t)));
    e.rate = std::max(e.rate, std::abs(f.rate(t) - rampRate(t)));
    e.acceleration = std::max(e.acceleration, std::abs(f.acceleration(t) - rampAcceleration(t)));
  }
  return e;
}

}  // namespace

TEST(Expression, PrecedenceFunctionsAndTheTimeVariable) {
  const std::map<std::string, double> p = {{"a", 2.0}, {"b", 3.0}};
  EXPECT_DOUBLE_EQ(evaluateExpression("1 + a*b^2 - -4/2", p), 1 + 2 * 9 + 2);
  EXPECT_DOUBLE_EQ(evaluateExpression("2^3^2", p), 512.0);  // right-associative
  EXPECT_DOUBLE_EQ(evaluateExpression("-2^2", p), 4.0);     // unary minus binds first
  EXPECT_DOUBLE_EQ(evaluateExpression("min(a, b) + max(a, b) + if(a - b, 10, 20)", p), 2 + 3 + 20);
  EXPECT_DOUBLE_EQ(evaluateExpression("sqrt(16) + abs(-1) + exp(0) + log(1) + cos(0)", p), 7.0);
  EXPECT_NEAR(evaluateExpression("sin(pi/6) + tan(pi/4) + asin(1) + acos(1) + atan(1)", p),
              0.5 + 1 + kPi / 2 + kPi / 4, 1e-15);
  const TimeFunction f("a*t^2 + if(t - 1, b, 0)", p);
  EXPECT_DOUBLE_EQ(f(0.5), 0.5);
  EXPECT_DOUBLE_EQ(f(2.0), 11.0);
  EXPECT_DOUBLE_EQ(f.rate(0.5), 2.0);
  EXPECT_DOUBLE_EQ(f.acceleration(0.5), 4.0);
  EXPECT_DOUBLE_EQ(TimeFunction()(3.0), 1.0);
  EXPECT_THROW(evaluateExpression("t + 1", p), std::invalid_argument);  // no time outside time functions
  EXPECT_THROW(evaluateExpression("sin(1, 2)", p), std::invalid_argument);
  EXPECT_THROW(evaluateExpression("foo(1)", p), std::invalid_argument);
  EXPECT_THROW(evaluateExpression("(1 + 2", p), std::invalid_argument);
  EXPECT_THROW(TimeFunction("t * c", p), std::invalid_argument);
}

// A drive's rate and acceleration are the expression's derivatives by
// forward-mode differentiation: against the closed forms, to round-off, for
// every function and operation (a varying exponent included), and against
// central differences of the value.
TEST(TimeFunction, ExpressionDerivativesAreExact) {
  struct Case {
    const char* text;
    double (*f1)(double);
    double (*f2)(double);
  };
  const Case cases[] = {
      {"sqrt(1 + t)", [](double t) { return 0.5 / std::sqrt(1 + t); },
       [](double t) { return -0.25 / std::pow(1 + t, 1.5); }},
      {"sin(3*t)", [](double t) { return 3 * std::cos(3 * t); }, [](double t) { return -9 * std::sin(3 * t); }},
      {"cos(t^2)", [](double t) { return -2 * t * std::sin(t * t); },
       [](double t) { return -2 * std::sin(t * t) - 4 * t * t * std::cos(t * t); }},
      {"tan(t)", [](double t) { return 1 / (std::cos(t) * std::cos(t)); },
       [](double t) { return 2 * std::tan(t) / (std::cos(t) * std::cos(t)); }},
      {"asin(t/2) - acos(t/2)", [](double t) { return 2 / std::sqrt(4 - t * t); },
       [](double t) { return 2 * t / std::pow(4 - t * t, 1.5); }},
      {"atan(2*t)", [](double t) { return 2 / (1 + 4 * t * t); },
       [](double t) { return -16 * t / ((1 + 4 * t * t) * (1 + 4 * t * t)); }},
      {"exp(-t)*log(2 + t)", [](double t) { return std::exp(-t) * (1 / (2 + t) - std::log(2 + t)); },
       [](double t) { return std::exp(-t) * (std::log(2 + t) - 2 / (2 + t) - 1 / ((2 + t) * (2 + t))); }},
      {"t^3 - 1/(1 + t^2)", [](double t) { return 3 * t * t + 2 * t / ((1 + t * t) * (1 + t * t)); },
       [](double t) { return 6 * t + (2 - 6 * t * t) / std::pow(1 + t * t, 3); }},
      {"2^t + t^t", [](double t) { return std::pow(2, t) * std::log(2) + std::pow(t, t) * (1 + std::log(t)); },
       [](double t) {
         return std::pow(2, t) * std::log(2) * std::log(2) +
                std::pow(t, t) * ((1 + std::log(t)) * (1 + std::log(t)) + 1 / t);
       }},
      {"abs(t - 1) + min(t, 1) + max(t^2, 0) + if(t - 0.5, t^2, -t)",
       [](double t) { return -1 + 1 + 2 * t + (t > 0.5 ? 2 * t : -1.0); },
       [](double t) { return 2 + (t > 0.5 ? 2.0 : 0.0); }},
  };
  for (const Case& c : cases) {
    const TimeFunction f(c.text, {});
    for (double t : {0.3, 0.7}) {
      SCOPED_TRACE(std::string(c.text) + " at t = " + numberText(t));
      const Expression::Jet jet = f.jet(t);
      EXPECT_DOUBLE_EQ(jet.value, f(t));
      EXPECT_NEAR(jet.first, c.f1(t), 1e-14 * (1 + std::abs(c.f1(t))));
      EXPECT_NEAR(jet.second, c.f2(t), 1e-13 * (1 + std::abs(c.f2(t))));
      EXPECT_EQ(f.rate(t), jet.first);
      EXPECT_EQ(f.acceleration(t), jet.second);
      const double h = 1e-4;
      EXPECT_NEAR(jet.first, (f(t + h) - f(t - h)) / (2 * h), 1e-7 * (1 + std::abs(jet.first)));
      EXPECT_NEAR(jet.second, (f(t + h) - 2 * f(t) + f(t - h)) / (h * h), 1e-4 * (1 + std::abs(jet.second)));
    }
  }
}

TEST(TimeFunction, TableReproducesACubicAtRestAtItsEnds) {
  // The smooth step 3 s^2 - 2 s^3 on [1, 3] is a cubic with zero end slopes:
  // the spline through any of its samples is the step itself.
  auto step = [](double t) {
    const double s = (t - 1) / 2;
    return s * s * (3 - 2 * s);
  };
  const std::vector<double> t = {1.0, 1.3, 2.1, 2.2, 3.0};
  std::vector<double> y;
  for (double ti : t) y.push_back(step(ti));
  const TimeFunction f = TimeFunction::table(t, y);
  for (double x = 1.005; x < 3.0; x += 0.01) {  // inside: the acceleration jumps to 0 at the ends
    const double s = (x - 1) / 2;
    EXPECT_NEAR(f(x), step(x), 1e-14);
    EXPECT_NEAR(f.rate(x), 3 * s * (1 - s), 1e-13);
    EXPECT_NEAR(f.acceleration(x), 1.5 * (1 - 2 * s), 1e-12);
  }
  // Held outside, at rest.
  EXPECT_EQ(f(0.0), 0.0);
  EXPECT_EQ(f(5.0), 1.0);
  EXPECT_EQ(f.rate(5.0), 0.0);
  EXPECT_EQ(f.acceleration(-1.0), 0.0);
  // Two points: the same smooth step.
  const TimeFunction two = TimeFunction::table({1.0, 3.0}, {0.0, 1.0});
  EXPECT_NEAR(two(1.7), step(1.7), 1e-15);
}

TEST(TimeFunction, TableConvergesAtFourthOrderForASmoothRamp) {
  const Errors coarse = maxErrors(sampled(ramp, 0.0, 1.0, 10));
  const Errors fine = maxErrors(sampled(ramp, 0.0, 1.0, 20));
  std::printf("[ table ] 10 -> 20 intervals: value %.2e -> %.2e, rate %.2e -> %.2e, acceleration %.2e -> %.2e\n",
              coarse.value, fine.value, coarse.rate, fine.rate, coarse.acceleration, fine.acceleration);
  EXPECT_LT(fine.value, 1e-5);
  EXPECT_GT(std::log2(coarse.value / fine.value), 3.8);
  EXPECT_GT(std::log2(coarse.rate / fine.rate), 2.8);
  EXPECT_GT(std::log2(coarse.acceleration / fine.acceleration), 1.8);
}

TEST(TimeFunction, BadTablesAreRejected) {
  EXPECT_THROW(TimeFunction::table({0.0}, {1.0}), std::invalid_argument);
  EXPECT_THROW(TimeFunction::table({0.0, 1.0, 1.0}, {0.0, 1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(TimeFunction::table({0.0, 2.0, 1.0}, {0.0, 1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(TimeFunction::table({0.0, 1.0}, {0.0, NAN}), std::invalid_argument);
  EXPECT_THROW(TimeFunction::table({0.0, 1.0}, {0.0}), std::invalid_argument);
}

TEST(NumberText, ShortestRoundTripNotFixedPoint) {
  EXPECT_EQ(numberText(1e-300), "1e-300");
  EXPECT_EQ(numberText(1e300), "1e+300");
  EXPECT_EQ(numberText(0.1), "0.1");
  EXPECT_EQ(numberText(-2.5), "-2.5");
  for (double x : {1e-320, 3.0000000000000004, 6.02214076e23}) EXPECT_EQ(std::strtod(numberText(x).c_str(), nullptr), x);
}
