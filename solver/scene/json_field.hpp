// Reading scene JSON with checks: a JSON value together with its path, so
// every error names where it is and what was expected (internal to scene/).
#pragma once
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/expression.hpp"
#include "scene/time_function.hpp"
#include "scene/scene.hpp"

namespace mfbd {

using json = nlohmann::json;

inline std::string typeName(const json& j) {
  if (j.is_null()) return "null";
  if (j.is_boolean()) return "a boolean";
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "an array";
  return "an object";
}

// A JSON object together with its path, for reading fields with checks.
class Field {
 public:
  Field(const json& value, std::string path, const std::map<std::string, double>& params)
      : j_(value), path_(std::move(path)), params_(params) {}

  const json& raw() const { return j_; }
  const std::map<std::string, double>& parameters() const { return params_; }

  // A function of time: an expression of t (a string, or a number) or
  // {"table": [[t, value], ...]}; finite at t = 0 (`what` names the
  // quantity in the error).
  TimeFunction timeFunction(const std::string& what) const;
  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& message) const { throw SceneError(path_, message); }

  Field at(const std::string& key) const {
    return Field(j_.at(key), path_.empty() ? key : path_ + "." + key, params_);
  }
  Field at(std::size_t i) const { return Field(j_.at(i), path_ + "[" + std::to_string(i) + "]", params_); }
  bool has(const std::string& key) const { return j_.contains(key); }

  // This must be an object with only `allowed` keys and all `required` ones.
  void expectObject(const std::set<std::string>& allowed, const std::set<std::string>& required) const {
    if (!j_.is_object()) fail("expected an object, got " + typeName(j_));
    for (const auto& item : j_.items()) {
      if (!allowed.count(item.key())) {
        std::string list;
        for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
        throw SceneError(path_.empty() ? item.key() : path_ + "." + item.key(),
                         "unknown key; expected one of: " + list);
      }
    }
    for (const auto& key : required)
      if (!j_.contains(key))
        throw SceneError(path_.empty() ? key : path_ + "." + key, "missing required field");
  }

  std::size_t arraySize() const {
    if (!j_.is_array()) fail("expected an array, got " + typeName(j_));
    return j_.size();
  }

  std::string string() const {
    if (!j_.is_string()) fail("expected a string, got " + typeName(j_));
    return j_.get<std::string>();
  }

  std::string identifier() const {
    const std::string s = string();
    bool ok = !s.empty() && (std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_');
    for (char c : s) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
    if (!ok) fail("expected a name of letters, digits and '_' not starting with a digit, got \"" + s + "\"");
    return s;
  }

  bool boolean() const {
    if (!j_.is_boolean()) fail("expected true or false, got " + typeName(j_));
    return j_.get<bool>();
  }

  // A number or an expression over user parameters; always finite.
  double number() const {
    double value;
    if (j_.is_number()) {
      value = j_.get<double>();
    } else if (j_.is_string()) {
      try {
        value = evaluateExpression(j_.get<std::string>(), params_);
      } catch (const std::exception& e) {
        fail(e.what());
      }
    } else {
      fail("expected a number or a parameter expression, got " + typeName(j_));
    }
    if (!std::isfinite(value)) fail("expected a finite number, got " + std::to_string(value));
    return value;
  }

  // A number in full precision as expression text.
  std::string expressionText() const {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", number());
    return text;
  }

  int integer() const {
    if (!j_.is_number_integer()) fail("expected an integer, got " + typeName(j_));
    return j_.get<int>();
  }

  std::vector<double> numbers() const {
    std::vector<double> out(arraySize());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = at(i).number();
    return out;
  }

  Vec3 vec3() const {
    if (arraySize() != 3) fail("expected 3 numbers, got " + std::to_string(j_.size()));
    return Vec3(at(0).number(), at(1).number(), at(2).number());
  }

  Vec3 direction() const {
    const Vec3 v = vec3();
    if (v.norm() < 1e-12) fail("expected a non-zero direction, got a zero-length vector");
    return v.normalized();
  }

  double positive() const {
    const double v = number();
    if (!(v > 0.0)) fail("expected a positive number, got " + std::to_string(v));
    return v;
  }

  double nonNegative() const {
    const double v = number();
    if (v < 0.0) fail("expected a number >= 0, got " + std::to_string(v));
    return v;
  }

 private:
  const json& j_;
  std::string path_;
  const std::map<std::string, double>& params_;
};

// A joint's or force element's end: a body name ("ground" allowed), or a
// flexible node {"flexible": name, "node": i} or {"flexible": name, "at": s}
// (then `body` stays empty until the assembly makes its virtual body).
inline void parseEnd(const Field& f, std::string& body, std::optional<NodeReference>& node) {
  if (!f.raw().is_object()) {
    body = f.identifier();
    return;
  }
  f.expectObject({"flexible", "node", "at"}, {"flexible"});
  if (f.has("node") == f.has("at")) f.fail("expected exactly one of \"node\" (an index) or \"at\" (a distance)");
  NodeReference r;
  r.flexibleBody = f.at("flexible").identifier();
  r.path = f.path();
  if (f.has("node")) {
    r.node = f.at("node").integer();
    if (r.node < 0) f.at("node").fail("expected a node index >= 0");
  } else {
    r.at = f.at("at").nonNegative();
  }
  body.clear();
  node = r;
}

// [[t0, v0], [t1, v1], ...]: at least two points, times increasing.
inline TimeFunction timeTable(const Field& f) {
  const std::size_t n = f.arraySize();
  if (n < 2) f.fail("expected at least 2 [t, value] points, got " + std::to_string(n));
  std::vector<double> times(n), values(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Field point = f.at(i);
    if (point.arraySize() != 2) point.fail("expected a [t, value] pair");
    times[i] = point.at(0).number();
    values[i] = point.at(1).number();
    if (i > 0 && !(times[i] > times[i - 1]))
      point.at(0).fail("expected times increasing, got " + std::to_string(times[i]) + " after " +
                       std::to_string(times[i - 1]));
  }
  try {
    return TimeFunction::table(times, values);
  } catch (const std::invalid_argument& e) {
    f.fail(e.what());
  }
}

inline TimeFunction Field::timeFunction(const std::string& what) const {
  TimeFunction f;
  if (j_.is_object()) {
    expectObject({"table"}, {"table"});
    f = timeTable(at("table"));
  } else if (j_.is_number()) {
    f = TimeFunction(expressionText(), params_);
  } else if (j_.is_string()) {
    try {
      f = TimeFunction(j_.get<std::string>(), params_);
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
  } else {
    fail("expected an expression of t or {\"table\": [[t, value], ...]}, got " + typeName(j_));
  }
  if (!std::isfinite(f(0.0))) fail("expected a finite " + what + " at t = 0");
  return f;
}

}  // namespace mfbd
