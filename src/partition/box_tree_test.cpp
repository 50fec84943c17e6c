#include "partition/box_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace ferry {
namespace {

// The tree reports exactly the boxes a brute-force slab test finds.
TEST(BoxTree, FindsEveryBoxTheSegmentMeetsAndNoOther) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-10, 10), ext(0, 2);
  std::vector<Box3f> boxes;
  for (int i = 0; i < 500; ++i) {
    const Vec3f c(pos(rng), pos(rng), pos(rng));
    const Vec3f h(ext(rng), ext(rng), i % 10 == 0 ? 0.0f : ext(rng));  // some flat ones
    boxes.push_back({c - h, c + h});
  }
  boxes.push_back(Box3f{});  // empty: never reported
  const BoxTree tree(boxes);
  auto meets = [](const Box3f& b, Vec3f o, Vec3f d, float tmax) {
    float t0 = 0, t1 = tmax;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0) {
        if (o[a] < b.lower[a] || o[a] > b.upper[a]) return false;
        continue;
      }
      float lo = (b.lower[a] - o[a]) / d[a], hi = (b.upper[a] - o[a]) / d[a];
      if (lo > hi) std::swap(lo, hi);
      t0 = std::max(t0, lo);
      t1 = std::min(t1, hi);
    }
    return t0 <= t1;
  };
  size_t total = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3f o(pos(rng), pos(rng), pos(rng));
    Vec3f d = normalize(Vec3f(pos(rng), pos(rng), pos(rng)));
    if (i % 7 == 0) d = Vec3f(0, 1, 0);  // axis-aligned rays too
    const float tmax = i % 3 == 0 ? kInfinity : ext(rng) * 8;
    std::vector<uint32_t> got;
    tree.boxesAlong(o, d, tmax, got);
    std::sort(got.begin(), got.end());
    std::vector<uint32_t> want;
    for (uint32_t b = 0; b < boxes.size(); ++b)
      if (!boxes[b].empty() && meets(boxes[b], o, d, tmax)) want.push_back(b);
    EXPECT_EQ(got, want) << "ray " << i;
    total += want.size();
  }
  EXPECT_GT(total, 300u);  // the rays do meet boxes
}

TEST(BoxTree, EmptyTreeFindsNothing) {
  const BoxTree tree({Box3f{}});
  std::vector<uint32_t> got;
  tree.boxesAlong({0, 0, 0}, {1, 0, 0}, kInfinity, got);
  EXPECT_TRUE(got.empty());
}

}  // namespace
}  // namespace ferry
