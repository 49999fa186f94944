// Arithmetic expressions over user parameters, for numeric scene fields:
// numbers, parameter names, + - * / ^, parentheses, unary minus, pi, and the
// functions sqrt sin cos tan asin acos atan exp log abs, min(a, b), max(a, b)
// and if(c, a, b) (a where c > 0, else b). Time functions see the variable t
// (scene/time_function.hpp).
#pragma once
#include <map>
#include <string>
#include <vector>

namespace mfbd {

// An expression parsed once (parameters bound to their values) into a
// postfix program, then evaluated for any value of its one free variable:
// time functions are evaluated at every residual, so they must not re-parse.
class Expression {
 public:
  Expression() = default;  // the constant 1
  // `variable` (e.g. "t"; empty: none) is free; every other name must be a
  // parameter. Throws std::invalid_argument naming the offending token.
  Expression(const std::string& text, const std::map<std::string, double>& parameters,
             const std::string& variable = "");
  double operator()(double variable = 0.0) const;
  // The value and its first two derivatives in the free variable, exact
  // (forward-mode differentiation of the program, one pass): a drive's
  // rate and acceleration.
  struct Jet {
    double value = 0.0, first = 0.0, second = 0.0;
  };
  Jet jet(double variable) const;

  enum class Op { Number, Variable, Add, Subtract, Multiply, Divide, Power, Negate, Min, Max, If, Function };
  // A function of one argument with its first and second derivatives.
  struct Function {
    double (*value)(double), (*first)(double), (*second)(double);
  };
  struct Instruction {
    Op op = Op::Number;
    double value = 0.0;                  // Number
    const Function* function = nullptr;  // Function
  };

 private:
  template <class T>
  T evaluate(const T& variable) const;
  std::vector<Instruction> program_{Instruction{Op::Number, 1.0, nullptr}};
};

// Parses and evaluates at once (fields that are plain numbers).
double evaluateExpression(const std::string& text, const std::map<std::string, double>& parameters);

}  // namespace mfbd
