// Reading scene JSON with checks: a JSON value together with its path, so
// every error names where it is and what was expected (internal to scene/).
#pragma once
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "math/number_text.hpp"
#include "scene/expression.hpp"
#include "scene/scene.hpp"
#include "scene/time_function.hpp"

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

// kLargestNumber and kLargestCoordinate: scene/scene.hpp.

// A JSON object together with its path, for reading fields with checks.
class Field {
 public:
  Field(const json& value, std::string path, const std::map<std::string, double>& params)
      : j_(value), path_(std::move(path)), params_(params) {}

  const json& raw() const { return j_; }
  const std::map<std::string, double>& parameters() const { return params_; }

  // A function of time: an expression of t (a string, or a number) or
  // {"table": [[t, value], ...]}; finite at t = 0 (`what` names the
  // quantity in the error), and so are its rate and acceleration for a
  // prescribed `motion` (drives use them).
  TimeFunction timeFunction(const std::string& what, bool motion) const;
  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& message) const { throw SceneError(path_, message); }

  // The value of a JSON number or of an expression, unchecked.
  double evaluate() const {
    if (j_.is_number()) return j_.get<double>();
    if (!j_.is_string()) fail("expected a number or a parameter expression, got " + typeName(j_));
    try {
      return evaluateExpression(j_.get<std::string>(), params_);
    } catch (const std::exception& e) {
      fail(e.what());
    }
  }

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

  // A string that goes into modelDescription.xml (a description, a unit):
  // only characters XML 1.0 can carry (escaped or not, it has no way to
  // write U+0000 to U+0008, U+000B, U+000C, U+000E to U+001F, U+FFFE or
  // U+FFFF). The JSON reader has already checked the UTF-8.
  std::string text() const {
    const std::string s = string();
    for (std::size_t i = 0; i < s.size(); ++i) {
      const auto c = static_cast<unsigned char>(s[i]);
      const bool control = c < 0x20 && c != '\t' && c != '\n' && c != '\r';
      // U+FFFE and U+FFFF are EF BF BE and EF BF BF in UTF-8.
      const auto last = i + 2 < s.size() ? static_cast<unsigned char>(s[i + 2]) : 0u;
      const bool nonCharacter = s.compare(i, 2, "\xEF\xBF") == 0 && (last == 0xBE || last == 0xBF);
      if (!control && !nonCharacter) continue;
      char code[8];
      std::snprintf(code, sizeof code, "U+%04X", control ? unsigned(c) : 0xFFFEu + (last - 0xBEu));
      fail("character " + std::string(code) + " at byte " + std::to_string(i) +
           " cannot be written to modelDescription.xml (XML 1.0 has no such character); expected printable "
           "text, tab, line feed or carriage return");
    }
    return s;
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

  // A number or an expression over user parameters: finite, 0 or of a
  // magnitude in [2.2e-308, kLargestNumber].
  double number() const { return inRange(evaluate()); }

  // A world coordinate of the design configuration or a joint coordinate:
  // the same, within kLargestCoordinate.
  double coordinate() const { return inRange(evaluate(), kLargestCoordinate, "a coordinate within +-"); }

  // `value` if it is in the range every scene number keeps (see
  // kLargestNumber), its magnitude at most `largest`; else the error.
  double inRange(double value, double largest = kLargestNumber,
                 const std::string& expected = "a magnitude of at most ") const {
    if (!std::isfinite(value)) fail("expected a finite number, got " + numberText(value));
    if (std::abs(value) > largest) fail("expected " + expected + numberText(largest) + ", got " + numberText(value));
    if (value != 0.0 && std::abs(value) < std::numeric_limits<double>::min())
      fail("expected 0 or a magnitude of at least " + numberText(std::numeric_limits<double>::min()) +
           " (subnormal numbers carry fewer digits), got " + numberText(value));
    return value;
  }

  // A number in full precision as expression text.
  std::string expressionText() const {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", number());
    return text;
  }

  // An integer in [lo, hi], checked before any conversion (4294967300 is
  // not 4). A JSON number with a fractional part is refused; 2.0 is 2, as
  // JSON Schema's "integer" has it.
  int integer(int lo, int hi, const std::string& what = "an integer") const {
    const std::string range = "expected " + what + " in " + std::to_string(lo) + ".." + std::to_string(hi);
    if (!j_.is_number()) fail(range + ", got " + typeName(j_));
    if (j_.is_number_unsigned()) {
      const auto u = j_.get<std::uint64_t>();
      if (u > std::uint64_t(hi) || (lo > 0 && u < std::uint64_t(lo))) fail(range + ", got " + std::to_string(u));
      return int(u);
    }
    if (j_.is_number_integer()) {
      const auto i = j_.get<std::int64_t>();
      if (i < lo || i > hi) fail(range + ", got " + std::to_string(i));
      return int(i);
    }
    const double d = j_.get<double>();
    if (!(d >= lo && d <= hi) || d != std::floor(d)) fail(range + ", got " + numberText(d));
    return int(d);
  }

  std::vector<double> numbers() const {
    std::vector<double> out(arraySize());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = at(i).number();
    return out;
  }

  // Three numbers, checked in order (the first bad one is named).
  Vec3 vec3() const {
    if (arraySize() != 3) fail("expected 3 numbers, got " + std::to_string(j_.size()));
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = at(i).number();
    return v;
  }

  // A point in world coordinates of the design configuration.
  Vec3 point() const {
    if (arraySize() != 3) fail("expected 3 numbers, got " + std::to_string(j_.size()));
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = at(i).coordinate();
    return v;
  }

  // A unit vector along any non-zero vector; stableNorm scales before it
  // squares, so [1e20, 1e20, 0] is a direction as [1, 1, 0] is.
  Vec3 direction() const {
    const Vec3 v = vec3();
    const double norm = v.stableNorm();
    if (norm == 0.0) fail("expected a non-zero direction, got a zero-length vector");
    return v / norm;
  }

  double positive() const {
    const double v = number();
    if (!(v > 0.0)) fail("expected a positive number, got " + numberText(v));
    return v;
  }

  double nonNegative() const {
    const double v = number();
    if (v < 0.0) fail("expected a number >= 0, got " + numberText(v));
    return v;
  }

 private:
  const json& j_;
  std::string path_;
  const std::map<std::string, double>& params_;
};

// A body's or element's orientation: quaternion [w,x,y,z], z_axis (+ x_axis)
// or rotation_vector, exactly one (parse.cpp).
Mat3 parseOrientation(const Field& f);

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
    r.node = f.at("node").integer(0, std::numeric_limits<int>::max(), "a node index");  // the count: checked later
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
      point.at(0).fail("expected times increasing, got " + numberText(times[i]) + " after " +
                       numberText(times[i - 1]));
  }
  try {
    return TimeFunction::table(times, values);
  } catch (const std::invalid_argument& e) {
    f.fail(e.what());
  }
}

inline TimeFunction Field::timeFunction(const std::string& what, bool motion) const {
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
  if (!std::isfinite(f(0.0))) fail("expected a finite " + what + " at t = 0, got " + numberText(f(0.0)));
  // A motion's rate and acceleration too (spin_up_beam with T = 0 has a
  // finite angle at t = 0 and an angle rate of NaN).
  if (motion && !(std::isfinite(f.rate(0.0)) && std::isfinite(f.acceleration(0.0))))
    fail("expected a finite " + what + " rate and acceleration at t = 0, got " + numberText(f.rate(0.0)) + " and " +
         numberText(f.acceleration(0.0)));
  return f;
}

}  // namespace mfbd
