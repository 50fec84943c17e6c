#include "partition/rank_set.h"

#include <gtest/gtest.h>

#include <bit>
#include <set>

#include "core/random.h"

namespace ferry {
namespace {

TEST(RankSet, BehavesAsAMaskBelow64) {
  RankSet s = RankSet::fromMask(0b101001);
  EXPECT_TRUE(s.fitsInMask());
  EXPECT_EQ(s.count(), 3);
  EXPECT_EQ(s.nth(0), 0);
  EXPECT_EQ(s.nth(1), 3);
  EXPECT_EQ(s.nth(2), 5);
  EXPECT_EQ(s.highest(), 5);
  EXPECT_TRUE(s.contains(3));
  EXPECT_FALSE(s.contains(4));
  EXPECT_EQ(s.mask(), 0b101001u);
  EXPECT_EQ(RankSet::single(63).mask(), uint64_t(1) << 63);
  EXPECT_EQ(RankSet::firstN(64).count(), 64);
  EXPECT_TRUE(RankSet::firstN(64).fitsInMask());
  EXPECT_EQ(s.toString(), "{0, 3, 5}");
}

// Random sets against std::set: every operation, across word boundaries.
TEST(RankSet, MatchesAStdSetAtAnySize) {
  for (uint32_t k = 0; k < 300; ++k) {
    const int ranks = 1 + int(randomBits(RandomKey{k, 0, 0, 1}, 0) % 300);
    auto make = [&](uint32_t salt, std::set<int>& ref) {
      RankSet s;
      for (int r = 0; r < ranks; ++r)
        if (random01(RandomKey{k, uint32_t(r), salt, 2}, RandomDim::OwnerPick) < 0.1f) {
          s.insert(r);
          ref.insert(r);
        }
      return s;
    };
    std::set<int> ra, rb;
    RankSet a = make(1, ra), b = make(2, rb);
    ASSERT_EQ(a.count(), int(ra.size()));
    ASSERT_EQ(a.ranks(), std::vector<int>(ra.begin(), ra.end()));
    ASSERT_EQ(a.fitsInMask(), ra.empty() || *ra.rbegin() < 64);
    ASSERT_EQ(a.highest(), ra.empty() ? -1 : *ra.rbegin());
    int i = 0;
    for (int r : ra) ASSERT_EQ(a.nth(i++), r);
    bool intersects = false, subset = true;
    for (int r : ra) {
      intersects = intersects || rb.count(r);
      subset = subset && rb.count(r);
    }
    ASSERT_EQ(a.intersects(b), intersects);
    ASSERT_EQ(a.isSubsetOf(b), subset);
    std::set<int> ru = ra;
    ru.insert(rb.begin(), rb.end());
    RankSet u = a | b;
    ASSERT_EQ(u.ranks(), std::vector<int>(ru.begin(), ru.end()));
    ASSERT_TRUE(a.isSubsetOf(u));
    ASSERT_TRUE(b.isSubsetOf(u));
    // Through words and back (part files), with extra zero words.
    std::vector<uint64_t> words;
    for (size_t w = 0; w < u.wordCount() + 2; ++w) words.push_back(u.word(w));
    ASSERT_EQ(RankSet::fromWords(words.data(), words.size()), u);
  }
}

TEST(RankSet, EqualSetsCompareEqualWhateverTheirHistory) {
  RankSet a = RankSet::single(200);
  RankSet b = RankSet::single(7);
  b.insert(200);
  RankSet c = RankSet::single(7);
  EXPECT_NE(a, b);
  EXPECT_EQ(a | c, b);
  uint64_t words[4] = {uint64_t(1) << 7, 0, 0, 0};
  EXPECT_EQ(RankSet::fromWords(words, 4), c);
  EXPECT_TRUE(RankSet::fromWords(words, 4).fitsInMask());
  EXPECT_EQ(rankSetWords(64), 1u);
  EXPECT_EQ(rankSetWords(65), 2u);
  EXPECT_EQ(rankSetWords(1), 1u);
}

}  // namespace
}  // namespace ferry
