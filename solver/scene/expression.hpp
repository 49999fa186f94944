// Arithmetic expressions over user parameters, for numeric scene fields:
// numbers, parameter names, + - * / ^, parentheses, unary minus, pi, and the
// functions sqrt sin cos tan asin acos atan exp log abs, min(a, b), max(a, b)
// and if(c, a, b) (a where c > 0, else b). Time functions see the variable t.
#pragma once
#include <map>
#include <string>

namespace mfbd {

// Throws std::invalid_argument with a message naming the offending token.
double evaluateExpression(const std::string& text, const std::map<std::string, double>& parameters);

// A function of time t given by the scene as an expression over its
// parameters and t ("6*t", "if(15 - t, ..., ...)"); "1" when not given.
class TimeFunction {
 public:
  TimeFunction() = default;
  TimeFunction(std::string expression, std::map<std::string, double> parameters);
  double operator()(double t) const;
  // d/dt and d2/dt2 by central differences (smooth expressions assumed).
  double rate(double t) const;
  double acceleration(double t) const;
  const std::string& expression() const { return expression_; }

 private:
  std::string expression_ = "1";
  std::map<std::string, double> parameters_;
};

}  // namespace mfbd
