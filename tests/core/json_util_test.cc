// ParseJsonText (core/json_util.h): any bad JSON is one ParseError naming the
// file and the line, including what nlohmann reports without a position (a
// number too large for a double), found by the hand_layout fuzzer.
#include "core/json_util.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace csw {
namespace {

std::string ParseErrorOf(const std::string& text) {
  try {
    ParseJsonText(text, "f.json");
  } catch (const ParseError& e) {
    return e.what();
  }
  return "(no ParseError)";
}

TEST(JsonUtil, BadJsonIsOneParseErrorWithTheLine) {
  EXPECT_EQ(ParseJsonText("{\"a\": [1, 2.5]}", "f.json")["a"][1].get<double>(), 2.5);
  const std::string cut = ParseErrorOf("{\n  \"a\": [1,\n");
  EXPECT_EQ(cut.rfind("f.json: line 3: invalid JSON: parse error", 0), 0u) << cut;
  // 1e999 overflows a double: nlohmann's out_of_range, no byte position.
  const std::string big = ParseErrorOf("{\n  \"a\": 1,\n  \"b\": 1e999\n}");
  EXPECT_EQ(big.rfind("f.json: line 3: invalid JSON: number overflow parsing '1e999'", 0), 0u) << big;
}

}  // namespace
}  // namespace csw
