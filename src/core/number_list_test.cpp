#include "core/number_list.h"

#include <array>

#include <gtest/gtest.h>

namespace ferry {
namespace {

TEST(NumberList, ReadsExactlyTheNumbersAskedFor) {
  std::array<float, 3> v{};
  ASSERT_TRUE(parseNumberList("1,-2.5,3e2", v));
  EXPECT_EQ(v, (std::array<float, 3>{1, -2.5f, 300}));
  std::array<float, 4> w{};
  ASSERT_TRUE(parseNumberList("0,0.5,0.25,1", w));
  EXPECT_EQ(w, (std::array<float, 4>{0, 0.5f, 0.25f, 1}));
}

TEST(NumberList, RefusesAnythingElse) {
  std::array<float, 3> v{};
  for (const char* bad :
       {"", "1,2", "1,2,3,4", "1,,3", "1,2,x", "1,2,3 ", "1;2;3", "1,2,inf", "1,2,nan", ",1,2"})
    EXPECT_FALSE(parseNumberList(bad, v)) << bad;
}

}  // namespace
}  // namespace ferry
