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
  int depth_ = 0;
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
