// Numbers in messages: the shortest text that reads back to the same double
// ("1e-300", "1e+300", "0.1"), so a message never shows 1e-300 as 0.000000
// nor 1e300 as 301 digits (std::to_string prints fixed-point).
#pragma once
#include <charconv>
#include <string>

namespace mfbd {

inline std::string numberText(double x) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, x).ptr;
  return std::string(text, end);
}

// A vector (anything with size() and operator[]) as "[1, 0.5, 1e-300]".
template <class Vector>
std::string vectorText(const Vector& v) {
  std::string out = "[";
  for (decltype(v.size()) i = 0; i < v.size(); ++i) out += (i ? ", " : "") + numberText(v[i]);
  return out + "]";
}

}  // namespace mfbd
