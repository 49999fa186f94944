// Arithmetic expressions over user parameters, for numeric scene fields:
// numbers, parameter names, + - * / ^, parentheses, unary minus, pi, and the
// functions sqrt sin cos tan asin acos atan exp log abs.
#pragma once
#include <map>
#include <string>

namespace mfbd {

// Throws std::invalid_argument with a message naming the offending token.
double evaluateExpression(const std::string& text, const std::map<std::string, double>& parameters);

}  // namespace mfbd
