#include "scene/expression.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace mfbd {
namespace {

// Nesting deeper than this (parentheses, function calls, signs, powers) is
// refused: each level is a few stack frames of the recursive descent, and
// 10,000 of them overflowed the stack of the packer and of fmi2Instantiate.
// No expression a person writes nests 100 deep.
constexpr int kMaxNesting = 100;

// Recursive descent emitting a postfix program: sum := product (('+'|'-')
// product)*, product := power (('*'|'/') power)*, power := unary ('^' power)?,
// unary := '-' unary | primary, primary := number | name | name '(' sum ')' |
// '(' sum ')'. One pass over the text: the work is linear in its length.
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
  // The message quotes the expression, shortened to its start when long
  // (a generated sum of 1e6 terms), and says where the error is.
  [[noreturn]] void fail(const std::string& what) const {
    constexpr std::size_t kShown = 60;
    const std::string shown = s_.size() <= kShown ? s_ : s_.substr(0, kShown) + "...";
    const std::string where = s_.size() <= kShown ? "" : " at character " + std::to_string(pos_ + 1);
    throw std::invalid_argument("in expression \"" + shown + "\"" + where + ": " + what);
  }
  // Counts the nesting of the recursive descent (see kMaxNesting).
  struct Nesting {
    explicit Nesting(Parser& p) : p_(p) {
      if (++p_.depth_ > kMaxNesting)
        p_.fail("nested deeper than " + std::to_string(kMaxNesting) + " levels (parentheses, calls, signs, '^')");
    }
    ~Nesting() { --p_.depth_; }
    Parser& p_;
  };
  void emit(Op op, double value = 0.0, const Expression::Function* function = nullptr) {
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
    if (accept('^')) {
      const Nesting level(*this);
      power(), emit(Op::Power);
    }
  }
  void unary() {
    if (accept('-')) {
      const Nesting level(*this);
      unary(), emit(Op::Negate);
    } else if (accept('+')) {
      const Nesting level(*this);
      unary();
    } else {
      primary();
    }
  }
  void primary() {
    skipSpace();
    if (accept('(')) {
      const Nesting level(*this);
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
  // A decimal number, read in place (no copy of the rest of the text) and
  // whatever the C locale says about decimal points. Subnormal numbers read
  // as they are and a number below them as 0, as the JSON reader does (so
  // "1e-320" and 1e-320 give one value; Field::number judges it).
  void number() {
    const char* begin = s_.data() + pos_;
    const char* end = s_.data() + s_.size();
    double value = 0.0;
    const auto [stop, error] = std::from_chars(begin, end, value);
    if (error == std::errc::invalid_argument) fail("bad number");
    if (error == std::errc::result_out_of_range) {
      if (!belowSubnormals(begin, stop)) fail("number out of range (beyond 1.8e308)");
      value = 0.0;
    }
    pos_ += std::size_t(stop - begin);
    if (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_' || s_[pos_] == '.'))
      fail("bad number");
    emit(Op::Number, value);
  }
  // Out of range and below 1 in magnitude (so below the subnormals): the
  // decimal exponent of the first significant digit is negative.
  static bool belowSubnormals(const char* begin, const char* end) {
    long integerDigits = 0, leadingZeros = 0;  // significant digits before '.', zeros after it
    bool point = false, significant = false;
    const char* p = begin;
    for (; p < end && *p != 'e' && *p != 'E'; ++p) {
      if (*p == '.') point = true;
      else if (*p != '0' || significant) significant = true, integerDigits += !point;
      else if (point) ++leadingZeros;
    }
    long exponent = 0;
    if (p < end && std::from_chars(p + 1 + (p[1] == '+'), end, exponent).ec == std::errc::result_out_of_range)
      return p[1] == '-';  // an exponent beyond 19 digits
    return (integerDigits > 0 ? integerDigits - 1 : -leadingZeros - 1) + exponent < 0;
  }
  void nameOrCall() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
      ++pos_;
    const std::string name = s_.substr(start, pos_ - start);
    if (accept('(')) {
      const Nesting level(*this);
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
    static const std::map<std::string, Expression::Function> functions = {
        {"sqrt", {[](double x) { return std::sqrt(x); }, [](double x) { return 0.5 / std::sqrt(x); },
                  [](double x) { return -0.25 / (x * std::sqrt(x)); }}},
        {"sin", {[](double x) { return std::sin(x); }, [](double x) { return std::cos(x); },
                 [](double x) { return -std::sin(x); }}},
        {"cos", {[](double x) { return std::cos(x); }, [](double x) { return -std::sin(x); },
                 [](double x) { return -std::cos(x); }}},
        {"tan", {[](double x) { return std::tan(x); }, [](double x) { return 1.0 + std::tan(x) * std::tan(x); },
                 [](double x) { return 2.0 * std::tan(x) * (1.0 + std::tan(x) * std::tan(x)); }}},
        {"asin", {[](double x) { return std::asin(x); }, [](double x) { return 1.0 / std::sqrt(1.0 - x * x); },
                  [](double x) { return x / std::pow(1.0 - x * x, 1.5); }}},
        {"acos", {[](double x) { return std::acos(x); }, [](double x) { return -1.0 / std::sqrt(1.0 - x * x); },
                  [](double x) { return -x / std::pow(1.0 - x * x, 1.5); }}},
        {"atan", {[](double x) { return std::atan(x); }, [](double x) { return 1.0 / (1.0 + x * x); },
                  [](double x) { return -2.0 * x / ((1.0 + x * x) * (1.0 + x * x)); }}},
        {"exp", {[](double x) { return std::exp(x); }, [](double x) { return std::exp(x); },
                 [](double x) { return std::exp(x); }}},
        {"log", {[](double x) { return std::log(x); }, [](double x) { return 1.0 / x; },
                 [](double x) { return -1.0 / (x * x); }}},
        {"abs", {[](double x) { return std::abs(x); }, [](double x) { return x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0; },
                 [](double) { return 0.0; }}}};
    const auto it = functions.find(f);
    if (it == functions.end()) fail("unknown function '" + f + "'");
    arity(1);
    emit(Op::Function, 0.0, &it->second);
  }

  const std::string& s_;
  const std::map<std::string, double>& params_;
  const std::string& variable_;
  std::vector<Expression::Instruction>& program_;
  std::size_t pos_ = 0;
  int depth_ = 0;
};

}  // namespace

Expression::Expression(const std::string& text, const std::map<std::string, double>& parameters,
                       const std::string& variable) {
  program_.clear();
  Parser(text, parameters, variable, program_).parse();
}

// The operations of the stack machine on a value (double) and on a Jet,
// whose first and second derivatives follow by the product, quotient and
// chain rules.
namespace {

using Jet = Expression::Jet;

double apply(const Expression::Function& f, double x) { return f.value(x); }
Jet apply(const Expression::Function& f, const Jet& x) {
  const double d1 = f.first(x.value);
  return {f.value(x.value), d1 * x.first, f.second(x.value) * x.first * x.first + d1 * x.second};
}
double value(double x) { return x; }
double value(const Jet& x) { return x.value; }

Jet operator-(const Jet& a) { return {-a.value, -a.first, -a.second}; }
Jet operator+(const Jet& a, const Jet& b) { return {a.value + b.value, a.first + b.first, a.second + b.second}; }
Jet operator-(const Jet& a, const Jet& b) { return {a.value - b.value, a.first - b.first, a.second - b.second}; }
Jet operator*(const Jet& a, const Jet& b) {
  return {a.value * b.value, a.first * b.value + a.value * b.first,
          a.second * b.value + 2.0 * a.first * b.first + a.value * b.second};
}
Jet operator/(const Jet& a, const Jet& b) {
  const double q = a.value / b.value, q1 = (a.first - q * b.first) / b.value;
  return {q, q1, (a.second - 2.0 * q1 * b.first - q * b.second) / b.value};
}

double power(double a, double b) { return b == 2.0 ? a * a : std::pow(a, b); }  // squares are the common case
// a^b: a constant exponent differentiates as b a^(b-1) (any a); a varying
// one as exp(b log a) (a > 0).
Jet power(const Jet& a, const Jet& b) {
  const double p = power(a.value, b.value);
  if (b.first == 0.0 && b.second == 0.0) {
    const double n = b.value;
    // n = 0 and 1 spelled out: a = 0 would make them 0 * inf.
    const double d1 = n == 0.0 ? 0.0 : n * std::pow(a.value, n - 1.0);
    const double d2 = n == 0.0 || n == 1.0 ? 0.0 : n * (n - 1.0) * std::pow(a.value, n - 2.0);
    return {p, d1 * a.first, d2 * a.first * a.first + d1 * a.second};
  }
  const Jet log = {std::log(a.value), a.first / a.value,
                   a.second / a.value - (a.first / a.value) * (a.first / a.value)};
  const Jet w = b * log;
  return {p, p * w.first, p * (w.second + w.first * w.first)};
}

}  // namespace

// A stack machine over the postfix program; the parser's grammar bounds the
// depth by the program length.
template <class T>
T Expression::evaluate(const T& variable) const {
  constexpr std::size_t kSmall = 32;
  T small[kSmall] = {};
  std::vector<T> large;
  T* stack = small;
  if (program_.size() > kSmall) {
    large.resize(program_.size());
    stack = large.data();
  }
  std::size_t top = 0;  // number of values on the stack
  for (const Instruction& i : program_) {
    switch (i.op) {
      case Op::Number: stack[top++] = T{i.value}; break;
      case Op::Variable: stack[top++] = variable; break;
      case Op::Negate: stack[top - 1] = -stack[top - 1]; break;
      case Op::Function: stack[top - 1] = apply(*i.function, stack[top - 1]); break;
      case Op::If:
        top -= 2;
        stack[top - 1] = value(stack[top - 1]) > 0.0 ? stack[top] : stack[top + 1];
        break;
      default: {
        const T b = stack[--top];
        T& a = stack[top - 1];
        switch (i.op) {
          case Op::Add: a = a + b; break;
          case Op::Subtract: a = a - b; break;
          case Op::Multiply: a = a * b; break;
          case Op::Divide: a = a / b; break;
          case Op::Power: a = power(a, b); break;
          case Op::Min: a = value(b) < value(a) ? b : a; break;
          case Op::Max: a = value(a) < value(b) ? b : a; break;
          default: break;
        }
      }
    }
  }
  return stack[0];
}

double Expression::operator()(double variable) const { return evaluate(variable); }

Expression::Jet Expression::jet(double variable) const { return evaluate(Jet{variable, 1.0, 0.0}); }

double evaluateExpression(const std::string& text, const std::map<std::string, double>& parameters) {
  return Expression(text, parameters)();
}

}  // namespace mfbd
