#include "scene/expression.hpp"

#include <algorithm>
#include <cctype>
#include <vector>
#include <cmath>
#include <stdexcept>

namespace mfbd {
namespace {

// Recursive descent: sum := product (('+'|'-') product)*,
// product := power (('*'|'/') power)*, power := unary ('^' power)?,
// unary := '-' unary | primary, primary := number | name | name '(' sum ')' | '(' sum ')'.
class Parser {
 public:
  Parser(const std::string& text, const std::map<std::string, double>& parameters)
      : s_(text), params_(parameters) {}

  double parse() {
    const double value = sum();
    skipSpace();
    if (pos_ != s_.size()) fail("unexpected '" + s_.substr(pos_, 1) + "'");
    return value;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument("in expression \"" + s_ + "\": " + what);
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
  double sum() {
    double value = product();
    for (;;) {
      if (accept('+')) value += product();
      else if (accept('-')) value -= product();
      else return value;
    }
  }
  double product() {
    double value = power();
    for (;;) {
      if (accept('*')) value *= power();
      else if (accept('/')) value /= power();
      else return value;
    }
  }
  double power() {
    const double base = unary();
    if (accept('^')) return std::pow(base, power());
    return base;
  }
  double unary() {
    if (accept('-')) return -unary();
    if (accept('+')) return unary();
    return primary();
  }
  double primary() {
    skipSpace();
    if (accept('(')) {
      const double value = sum();
      if (!accept(')')) fail("missing ')'");
      return value;
    }
    if (pos_ >= s_.size()) fail("unexpected end");
    const char c = s_[pos_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return nameOrCall();
    fail("unexpected '" + std::string(1, c) + "'");
  }
  double number() {
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
    return value;
  }
  double nameOrCall() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
      ++pos_;
    const std::string name = s_.substr(start, pos_ - start);
    if (accept('(')) {
      std::vector<double> args = {sum()};
      while (accept(',')) args.push_back(sum());
      if (!accept(')')) fail("missing ')' after " + name + "(");
      return call(name, args);
    }
    if (name == "pi") return M_PI;
    const auto it = params_.find(name);
    if (it == params_.end()) fail("unknown parameter '" + name + "'");
    return it->second;
  }
  double call(const std::string& f, const std::vector<double>& a) const {
    const std::size_t n = a.size();
    auto arity = [&](std::size_t want) {
      if (n != want) fail(f + "() takes " + std::to_string(want) + " argument(s), got " + std::to_string(n));
    };
    if (f == "min" || f == "max") {
      arity(2);
      return f == "min" ? std::min(a[0], a[1]) : std::max(a[0], a[1]);
    }
    if (f == "if") {  // if(c, a, b): a where c > 0, else b
      arity(3);
      return a[0] > 0.0 ? a[1] : a[2];
    }
    arity(1);
    const double x = a[0];
    if (f == "sqrt") return std::sqrt(x);
    if (f == "sin") return std::sin(x);
    if (f == "cos") return std::cos(x);
    if (f == "tan") return std::tan(x);
    if (f == "asin") return std::asin(x);
    if (f == "acos") return std::acos(x);
    if (f == "atan") return std::atan(x);
    if (f == "exp") return std::exp(x);
    if (f == "log") return std::log(x);
    if (f == "abs") return std::abs(x);
    fail("unknown function '" + f + "'");
  }

  const std::string& s_;
  const std::map<std::string, double>& params_;
  std::size_t pos_ = 0;
};

}  // namespace

double evaluateExpression(const std::string& text, const std::map<std::string, double>& parameters) {
  return Parser(text, parameters).parse();
}

TimeFunction::TimeFunction(std::string expression, std::map<std::string, double> parameters)
    : expression_(std::move(expression)), parameters_(std::move(parameters)) {
  parameters_["t"] = 0.0;
}

double TimeFunction::operator()(double t) const {
  std::map<std::string, double> p = parameters_;
  p["t"] = t;
  return evaluateExpression(expression_, p);
}

// Steps balance truncation (h^2) against round-off (eps/h, eps/h^2).
double TimeFunction::rate(double t) const {
  const double h = 1e-5 * std::max(1.0, std::abs(t));
  return ((*this)(t + h) - (*this)(t - h)) / (2.0 * h);
}

double TimeFunction::acceleration(double t) const {
  const double h = 1e-4 * std::max(1.0, std::abs(t));
  return ((*this)(t + h) - 2.0 * (*this)(t) + (*this)(t - h)) / (h * h);
}

}  // namespace mfbd
