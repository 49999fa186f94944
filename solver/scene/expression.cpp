#include "scene/expression.hpp"

#include <algorithm>
#include <cctype>
#include <vector>
#include <cmath>
#include <stdexcept>

namespace mfbd {
namespace {

// Recursive descent emitting a postfix program: sum := product (('+'|'-')
// product)*, product := power (('*'|'/') power)*, power := unary ('^' power)?,
// unary := '-' unary | primary, primary := number | name | name '(' sum ')' |
// '(' sum ')'.
class Parser {
 public:
  using Op = Expression::Op;
  Parser(const std::string& text, const std::map<std::string, double>& parameters, const std::string& variable,
         std::vector<Expression::Instruction>& program)
      : s_(text), params_(parameters), variable_(variable), program_(program) {}

  void parse() {
    sum();
    skipSpace();
    if (pos_ != s_.size()) fail("unexpected '" + s_.substr(pos_, 1) + "'");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument("in expression \"" + s_ + "\": " + what);
  }
  void emit(Op op, double value = 0.0, double (*function)(double) = nullptr) {
    program_.push_back({op, value, function});
  }
  void skipSpace() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skipSpace();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void sum() {
    product();
    for (;;) {
      if (accept('+')) product(), emit(Op::Add);
      else if (accept('-')) product(), emit(Op::Subtract);
      else return;
    }
  }
  void product() {
    power();
    for (;;) {
      if (accept('*')) power(), emit(Op::Multiply);
      else if (accept('/')) power(), emit(Op::Divide);
      else return;
    }
  }
  void power() {
    unary();
    if (accept('^')) power(), emit(Op::Power);
  }
  void unary() {
    if (accept('-')) unary(), emit(Op::Negate);
    else if (accept('+')) unary();
    else primary();
  }
  void primary() {
    skipSpace();
    if (accept('(')) {
      sum();
      if (!accept(')')) fail("missing ')'");
      return;
    }
    if (pos_ >= s_.size()) fail("unexpected end");
    const char c = s_[pos_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return nameOrCall();
    fail("unexpected '" + std::string(1, c) + "'");
  }
  void number() {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(s_.substr(pos_), &used);
    } catch (const std::out_of_range&) {
      fail("number out of range");
    } catch (const std::exception&) {
      fail("bad number");
    }
    pos_ += used;
    emit(Op::Number, value);
  }
  void nameOrCall() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
      ++pos_;
    const std::string name = s_.substr(start, pos_ - start);
    if (accept('(')) {
      std::size_t n = 1;
      sum();
      while (accept(',')) sum(), ++n;
      if (!accept(')')) fail("missing ')' after " + name + "(");
      return call(name, n);
    }
    if (!variable_.empty() && name == variable_) return emit(Op::Variable);
    if (name == "pi") return emit(Op::Number, M_PI);
    const auto it = params_.find(name);
    if (it == params_.end()) fail("unknown parameter '" + name + "'");
    emit(Op::Number, it->second);
  }
  void call(const std::string& f, std::size_t n) {
    auto arity = [&](std::size_t want) {
      if (n != want) fail(f + "() takes " + std::to_string(want) + " argument(s), got " + std::to_string(n));
    };
    if (f == "min" || f == "max") {
      arity(2);
      return emit(f == "min" ? Op::Min : Op::Max);
    }
    if (f == "if") {  // if(c, a, b): a where c > 0, else b
      arity(3);
      return emit(Op::If);
    }
    static const std::map<std::string, double (*)(double)> functions = {
        {"sqrt", [](double x) { return std::sqrt(x); }}, {"sin", [](double x) { return std::sin(x); }},
        {"cos", [](double x) { return std::cos(x); }},   {"tan", [](double x) { return std::tan(x); }},
        {"asin", [](double x) { return std::asin(x); }}, {"acos", [](double x) { return std::acos(x); }},
        {"atan", [](double x) { return std::atan(x); }}, {"exp", [](double x) { return std::exp(x); }},
        {"log", [](double x) { return std::log(x); }},   {"abs", [](double x) { return std::abs(x); }}};
    const auto it = functions.find(f);
    if (it == functions.end()) fail("unknown function '" + f + "'");
    arity(1);
    emit(Op::Function, 0.0, it->second);
  }

  const std::string& s_;
  const std::map<std::string, double>& params_;
  const std::string& variable_;
  std::vector<Expression::Instruction>& program_;
  std::size_t pos_ = 0;
};

}  // namespace

Expression::Expression(const std::string& text, const std::map<std::string, double>& parameters,
                       const std::string& variable) {
  program_.clear();
  Parser(text, parameters, variable, program_).parse();
}

// A stack machine over the postfix program; the parser's grammar bounds the
// depth by the program length.
double Expression::operator()(double variable) const {
  constexpr std::size_t kSmall = 32;
  double small[kSmall] = {};
  std::vector<double> large;
  double* stack = small;
  if (program_.size() > kSmall) {
    large.resize(program_.size());
    stack = large.data();
  }
  std::size_t top = 0;  // number of values on the stack
  for (const Instruction& i : program_) {
    switch (i.op) {
      case Op::Number: stack[top++] = i.value; break;
      case Op::Variable: stack[top++] = variable; break;
      case Op::Negate: stack[top - 1] = -stack[top - 1]; break;
      case Op::Function: stack[top - 1] = i.function(stack[top - 1]); break;
      case Op::If:
        top -= 2;
        stack[top - 1] = stack[top - 1] > 0.0 ? stack[top] : stack[top + 1];
        break;
      default: {
        const double b = stack[--top];
        double& a = stack[top - 1];
        switch (i.op) {
          case Op::Add: a += b; break;
          case Op::Subtract: a -= b; break;
          case Op::Multiply: a *= b; break;
          case Op::Divide: a /= b; break;
          case Op::Power: a = b == 2.0 ? a * a : std::pow(a, b); break;  // squares are the common case
          case Op::Min: a = std::min(a, b); break;
          case Op::Max: a = std::max(a, b); break;
          default: break;
        }
      }
    }
  }
  return stack[0];
}

double evaluateExpression(const std::string& text, const std::map<std::string, double>& parameters) {
  return Expression(text, parameters)();
}

}  // namespace mfbd
