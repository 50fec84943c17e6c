#include "trace/proxy_bvh.h"

#include <gtest/gtest.h>

#include "core/random.h"

namespace ferry {
namespace {

float uniform(uint32_t a, uint32_t b) { return random01(RandomKey{a, b, 0, 42}, RandomDim::OwnerPick); }

std::vector<Proxy> randomProxies(int count, int ranks, uint32_t seed) {
  std::vector<Proxy> proxies;
  for (int i = 0; i < count; ++i) {
    Box3f b;
    b.extend(Vec3f(uniform(seed + i, 0), uniform(seed + i, 1), uniform(seed + i, 2)) * 10.0f);
    b.extend(Vec3f(uniform(seed + i, 3), uniform(seed + i, 4), uniform(seed + i, 5)) * 10.0f);
    RankMask owners = RankMask(1) << int(uniform(seed + i, 6) * ranks);
    if (uniform(seed + i, 7) < 0.3f) owners |= RankMask(1) << int(uniform(seed + i, 8) * ranks);
    proxies.push_back({b, owners});
  }
  return proxies;
}

ProxyBvh::Hit bruteForce(const std::vector<Proxy>& proxies, Vec3f o, Vec3f d, float tmax, RankMask excluded) {
  ProxyBvh::Hit best;
  Vec3f inv{1 / d.x, 1 / d.y, 1 / d.z};
  for (size_t i = 0; i < proxies.size(); ++i) {
    if (proxies[i].owners & excluded) continue;
    float t;
    if (intersectBox(proxies[i].bounds, o, inv, tmax, t) && t < best.tEnter) best = {int32_t(i), t};
  }
  return best;
}

}  // namespace

TEST(ProxyBvh, MatchesBruteForceOnRandomProxiesAndRays) {
  for (int ranks : {2, 5, 8, 64}) {
    std::vector<Proxy> proxies = randomProxies(300, ranks, uint32_t(ranks) * 1000);
    ProxyBvh bvh(proxies);
    for (uint32_t k = 0; k < 2000; ++k) {
      Vec3f o = Vec3f(uniform(k, 10), uniform(k, 11), uniform(k, 12)) * 14.0f - Vec3f(2);
      Vec3f d = normalize(Vec3f(uniform(k, 13), uniform(k, 14), uniform(k, 15)) - Vec3f(0.5f));
      float tmax = uniform(k, 16) < 0.3f ? kInfinity : uniform(k, 17) * 20;
      RankMask excluded = RankMask(randomBits(RandomKey{k, 0, 0, 7}, 0)) & ((ranks == 64) ? ~RankMask(0) : ((RankMask(1) << ranks) - 1));
      excluded &= RankMask(randomBits(RandomKey{k, 1, 0, 7}, 0));
      ProxyBvh::Hit a = bvh.closest(o, d, tmax, excluded);
      ProxyBvh::Hit b = bruteForce(proxies, o, d, tmax, excluded);
      ASSERT_EQ(a.proxy, b.proxy) << "ray " << k << " ranks " << ranks;
      if (a.found()) EXPECT_EQ(a.tEnter, b.tEnter);
    }
  }
}

TEST(ProxyBvh, AxisParallelRaysAndOriginInside) {
  std::vector<Proxy> proxies = {{{{0, 0, 0}, {1, 1, 1}}, 1}, {{{2, 0, 0}, {3, 1, 1}}, 2}};
  ProxyBvh bvh(proxies);
  // Inside the first box: enters at 0.
  ProxyBvh::Hit h = bvh.closest({0.5f, 0.5f, 0.5f}, {1, 0, 0}, kInfinity, 0);
  EXPECT_EQ(h.proxy, 0);
  EXPECT_EQ(h.tEnter, 0);
  // Excluding rank 0's proxy, the next one along +x starts at 1.5.
  h = bvh.closest({0.5f, 0.5f, 0.5f}, {1, 0, 0}, kInfinity, 1);
  EXPECT_EQ(h.proxy, 1);
  EXPECT_FLOAT_EQ(h.tEnter, 1.5f);
  // ...but not before tmax.
  EXPECT_FALSE(bvh.closest({0.5f, 0.5f, 0.5f}, {1, 0, 0}, 1.0f, 1).found());
  // A ray parallel to a slab, outside it, misses.
  EXPECT_FALSE(bvh.closest({0.5f, 2, 0.5f}, {1, 0, 0}, kInfinity, 0).found());
}

}  // namespace ferry
