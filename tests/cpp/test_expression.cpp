// Expressions of scene fields: long and deep input, and numbers at the
// ends of the double range.
#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

#include "scene/expression.hpp"

using namespace mfbd;

namespace {

// The message of the std::invalid_argument that parsing `text` throws.
std::string parseError(const std::string& text) {
  try {
    evaluateExpression(text, {});
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

// One pass over the text: a generated sum of 200,000 terms parses (the old
// parser copied the rest of the text at every number: quadratic, minutes
// for a million terms) and sums exactly (integers below 2^53).
TEST(Expression, LongSumParsesAndSumsExactly) {
  std::string text = "1";
  for (int i = 2; i <= 200000; ++i) text += "+" + std::to_string(i);
  EXPECT_EQ(evaluateExpression(text, {}), 200000.0 * 200001.0 / 2.0);
  // An error in it is reported with the start of the text and the place.
  const std::string message = parseError(text + "*");
  EXPECT_NE(message.find("in expression \"1+2+3+"), std::string::npos) << message;
  EXPECT_NE(message.find("...\" at character " + std::to_string(text.size() + 2) + ": unexpected end"),
            std::string::npos)
      << message;
  EXPECT_LT(message.size(), 200u);
}

// Nesting is limited, so no input overflows the stack (10,000 parentheses
// did); 100 levels of each kind parse.
TEST(Expression, NestingIsLimitedNotFatal) {
  auto nested = [](const std::string& open, const std::string& close, int depth) {
    std::string text;
    for (int i = 0; i < depth; ++i) text += open;
    text += "2";
    for (int i = 0; i < depth; ++i) text += close;
    return text;
  };
  EXPECT_EQ(evaluateExpression(nested("(", ")", 100), {}), 2.0);
  EXPECT_EQ(evaluateExpression(nested("abs(", ")", 100), {}), 2.0);
  EXPECT_EQ(evaluateExpression(nested("-", "", 100), {}), 2.0);
  EXPECT_EQ(evaluateExpression(nested("1^", "", 100), {}), 1.0);
  for (const std::string& text : {nested("(", ")", 10000), nested("abs(", ")", 101), nested("-", "", 10000),
                                  nested("+", "", 101), nested("1^", "", 10000)})
    EXPECT_NE(parseError(text).find("nested deeper than 100 levels"), std::string::npos) << text.substr(0, 20);
}

// A literal means what the JSON reader makes of the same number: a
// subnormal stays itself (the scene's range check judges it, for both
// alike), below the subnormals it is 0, beyond the largest double an error.
TEST(Expression, NumbersAtTheEndsOfTheRangeReadAsInJson) {
  EXPECT_EQ(evaluateExpression("1e-320", {}), std::strtod("1e-320", nullptr));
  EXPECT_EQ(evaluateExpression("4.9e-324", {}), 4.9406564584124654e-324);
  EXPECT_EQ(evaluateExpression("1e-400", {}), 0.0);
  EXPECT_EQ(evaluateExpression("0.0001e-321", {}), 0.0);
  EXPECT_EQ(evaluateExpression("-2.5e-99999999999999999999", {}), 0.0);
  EXPECT_EQ(evaluateExpression("1.7976931348623157e308", {}), 1.7976931348623157e308);
  EXPECT_NE(parseError("1e309").find("number out of range"), std::string::npos);
  EXPECT_NE(parseError("10000e305").find("number out of range"), std::string::npos);
  EXPECT_EQ(evaluateExpression(".5 + 2. + 1e+1", {}), 12.5);
  // A number runs into no name: hexadecimal and a missing operator are errors.
  EXPECT_NE(parseError("0x10").find("bad number"), std::string::npos);
  EXPECT_NE(parseError("2pi").find("bad number"), std::string::npos);
  EXPECT_NE(parseError("1e").find("bad number"), std::string::npos);
}
