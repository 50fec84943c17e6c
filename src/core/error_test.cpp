#include "core/error.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace ferry {
namespace {

// The message of the InternalError that `check` throws ("" if none).
template <typename F>
std::string failureOf(F&& check) {
  try {
    check();
  } catch (const InternalError& e) {
    return e.what();
  }
  return "";
}

// Where the checks below stand: this file, and a line in it.
const std::string kThisFile = __FILE__;

TEST(ErrorCheck, ComparisonMessageHasExpressionBothValuesAndLocation) {
  std::vector<int> hits(12), rays(13);
  const int line = __LINE__ + 1;
  std::string message = failureOf([&] { FERRY_CHECK_EQ(hits.size(), rays.size()); });
  EXPECT_EQ(message, "check failed: hits.size() == rays.size() (12 vs 13) at " + kThisFile + ":" +
                         std::to_string(line));
}

TEST(ErrorCheck, EveryComparisonFailsExactlyWhenItsRelationDoesNot) {
  EXPECT_EQ(failureOf([] { FERRY_CHECK_EQ(3, 3); }), "");
  EXPECT_NE(failureOf([] { FERRY_CHECK_EQ(3, 4); }).find("3 == 4 (3 vs 4)"), std::string::npos);
  EXPECT_EQ(failureOf([] { FERRY_CHECK_NE(3, 4); }), "");
  EXPECT_NE(failureOf([] { FERRY_CHECK_NE(5, 5); }).find("5 != 5 (5 vs 5)"), std::string::npos);
  EXPECT_EQ(failureOf([] { FERRY_CHECK_LT(3, 4); }), "");
  EXPECT_NE(failureOf([] { FERRY_CHECK_LT(4, 4); }).find("4 < 4 (4 vs 4)"), std::string::npos);
  EXPECT_EQ(failureOf([] { FERRY_CHECK_LE(4, 4); }), "");
  EXPECT_NE(failureOf([] { FERRY_CHECK_LE(5, 4); }).find("5 <= 4 (5 vs 4)"), std::string::npos);
  EXPECT_EQ(failureOf([] { FERRY_CHECK_GT(5, 4); }), "");
  EXPECT_NE(failureOf([] { FERRY_CHECK_GT(4, 4); }).find("4 > 4 (4 vs 4)"), std::string::npos);
  EXPECT_EQ(failureOf([] { FERRY_CHECK_GE(4, 4); }), "");
  EXPECT_NE(failureOf([] { FERRY_CHECK_GE(3, 4); }).find("3 >= 4 (3 vs 4)"), std::string::npos);
}

TEST(ErrorCheck, IntegersOfMixedSignednessCompareByValue) {
  // With the built-in operator, -1 converts to SIZE_MAX and is "greater".
  const size_t size = 2;
  const int negative = -1;
  EXPECT_EQ(failureOf([&] { FERRY_CHECK_GT(size, negative); }), "");
  EXPECT_NE(failureOf([&] { FERRY_CHECK_LE(size, negative); }).find("(2 vs -1)"),
            std::string::npos);
  EXPECT_EQ(failureOf([] { FERRY_CHECK_EQ(uint64_t(7), int8_t(7)); }), "");
}

TEST(ErrorCheck, OperandsAreEvaluatedOnce) {
  int calls = 0;
  auto next = [&] { return ++calls; };
  std::string message = failureOf([&] { FERRY_CHECK_EQ(next(), 5); });
  EXPECT_EQ(calls, 1);
  EXPECT_NE(message.find("next() == 5 (1 vs 5)"), std::string::npos) << message;
}

TEST(ErrorCheck, OperandsWithoutAFormatterStillReportTheExpression) {
  struct Opaque {
    int v;
    bool operator==(const Opaque&) const = default;
  };
  std::string message = failureOf([] { FERRY_CHECK_EQ(Opaque{1}, Opaque{2}); });
  EXPECT_NE(message.find("Opaque{1} == Opaque{2} ((not formattable) vs (not formattable))"),
            std::string::npos)
      << message;
}

TEST(ErrorCheck, PlainCheckReportsExpressionAndLocation) {
  const int line = __LINE__ + 1;
  std::string message = failureOf([] { FERRY_CHECK(1 + 1 == 3); });
  EXPECT_EQ(message, "check failed: 1 + 1 == 3 at " + kThisFile + ":" + std::to_string(line));
}

}  // namespace
}  // namespace ferry
