#include "render/pixel_set.h"

#include <gtest/gtest.h>

#include <vector>

namespace ferry {
namespace {

std::vector<uint32_t> members(const PixelSet& set) {
  std::vector<uint32_t> out;
  set.forEachRun([&](uint32_t b, uint32_t e) {
    EXPECT_LT(b, e);
    for (uint32_t p = b; p != e; ++p) out.push_back(p);
  });
  return out;
}

TEST(PixelSet, ARangeHoldsEveryPixelOfIt) {
  EXPECT_EQ(members(PixelSet::range(3, 7)), (std::vector<uint32_t>{3, 4, 5, 6}));
  EXPECT_EQ(PixelSet::range(3, 7).size(), 4u);
  EXPECT_TRUE(members(PixelSet::range(5, 5)).empty());
}

// The takers' bands cover the range once, in order within each taker, and
// contains() agrees with the runs.
TEST(PixelSet, InterleavedBandsCoverTheRangeOnce) {
  for (uint32_t takers : {1u, 2u, 3u, 5u}) {
    for (uint32_t band : {1u, 4u, 7u, 100u}) {
      const uint32_t first = 11, last = 11 + 523;
      std::vector<int> seen(last, 0);
      for (uint32_t j = 0; j < takers; ++j) {
        const PixelSet set = PixelSet::interleaved(first, last, band, takers, j);
        const std::vector<uint32_t> mine = members(set);
        EXPECT_EQ(mine.size(), set.size());
        EXPECT_TRUE(std::is_sorted(mine.begin(), mine.end()));
        for (uint32_t p : mine) ++seen[p];
        for (uint32_t p = 0; p < last + 5; ++p)
          EXPECT_EQ(set.contains(p), std::count(mine.begin(), mine.end(), p) == 1) << p;
      }
      for (uint32_t p = 0; p < last; ++p) EXPECT_EQ(seen[p], p >= first ? 1 : 0) << p;
    }
  }
  // Two takers of bands of 10 out of [0, 35): 0-9 and 20-29; 10-19 and 30-34.
  EXPECT_EQ(PixelSet::interleaved(0, 35, 10, 2, 1).size(), 15u);
}

}  // namespace
}  // namespace ferry
