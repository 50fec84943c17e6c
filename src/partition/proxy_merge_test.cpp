#include "partition/proxy_merge.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "builtin/builtin.h"
#include "partition/partitioner.h"
#include "partition/ray_sampler.h"
#include "scene/scene.h"

namespace ferry {
namespace {

Box3f boxAt(Vec3f centre, float half) {
  Box3f b;
  b.extend(centre - Vec3f{half, half, half});
  b.extend(centre + Vec3f{half, half, half});
  return b;
}

// `n` small boxes scattered in a 100-unit cube, owners from a few sets.
std::vector<Proxy> scattered(int n, uint32_t seed) {
  std::vector<Proxy> proxies;
  const RankSet sets[] = {RankSet::single(0), RankSet::single(1),
                          RankSet::single(0) | RankSet::single(2), RankSet::single(70)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  for (int i = 0; i < n; ++i) {
    const Vec3f c{100 * uniform(rng), 100 * uniform(rng), 100 * uniform(rng)};
    proxies.push_back({boxAt(c, 0.5f + uniform(rng)), sets[i % 4]});
  }
  return proxies;
}

// Every original box lies in a merged box with exactly its owners.
void expectCovered(const std::vector<Proxy>& original, const std::vector<Proxy>& merged) {
  for (size_t i = 0; i < original.size(); ++i) {
    bool found = false;
    for (const Proxy& m : merged)
      found = found || (m.owners == original[i].owners && m.bounds.contains(original[i].bounds));
    ASSERT_TRUE(found) << "proxy " << i << " is in no merged box with its owners";
  }
}

}  // namespace

TEST(ProxyMerge, UnderTheBudgetNothingChanges) {
  const std::vector<Proxy> proxies = scattered(100, 1);
  for (uint64_t max : {uint64_t(0), uint64_t(100), uint64_t(1000)}) {
    const std::vector<Proxy> merged = mergeProxies(proxies, max);
    ASSERT_EQ(merged.size(), proxies.size());
    for (size_t i = 0; i < merged.size(); ++i) {
      EXPECT_EQ(merged[i].owners, proxies[i].owners);
      EXPECT_TRUE(merged[i].bounds.contains(proxies[i].bounds) &&
                  proxies[i].bounds.contains(merged[i].bounds));
    }
  }
}

TEST(ProxyMerge, UnitBoxesMergeAsTheProxiesTheyStandFor) {
  // The partitioners merge braided boxes straight from their units: the same
  // boxes, in the same order, as merging the Proxy list.
  const std::vector<Proxy> proxies = scattered(3000, 11);
  std::vector<RankSet> unitOwners;
  std::vector<UnitBox> boxes;
  for (size_t i = 0; i < proxies.size(); ++i) {
    if (i % 3 == 0) unitOwners.push_back(proxies[i].owners);  // a unit per 3 boxes...
    if (!(unitOwners.back() == proxies[i].owners)) unitOwners.push_back(proxies[i].owners);
    boxes.push_back({uint32_t(unitOwners.size() - 1), proxies[i].bounds});
  }
  for (uint64_t max : {uint64_t(0), uint64_t(6), uint64_t(300), uint64_t(5000)}) {
    SCOPED_TRACE(fmt::format("max {}", max));
    const std::vector<Proxy> want = mergeProxies(proxies, max);
    const std::vector<Proxy> got = mergeProxies(boxes, unitOwners, max);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].owners, want[i].owners);
      EXPECT_EQ(got[i].bounds.lower, want[i].bounds.lower);
      EXPECT_EQ(got[i].bounds.upper, want[i].bounds.upper);
    }
  }
}

TEST(ProxyMerge, MergedBoxesCoverEveryProxyWithItsOwnersWithinTheBudget) {
  const std::vector<Proxy> proxies = scattered(2000, 7);
  for (uint64_t max : {4, 5, 17, 256, 1999}) {
    SCOPED_TRACE(fmt::format("max {}", max));
    const std::vector<Proxy> merged = mergeProxies(proxies, max);
    EXPECT_EQ(merged.size(), max);  // 4 owner sets, 2000 proxies: exactly the budget
    expectCovered(proxies, merged);
    // Deterministic.
    const std::vector<Proxy> again = mergeProxies(proxies, max);
    ASSERT_EQ(again.size(), merged.size());
    for (size_t i = 0; i < merged.size(); ++i) {
      EXPECT_EQ(again[i].owners, merged[i].owners);
      EXPECT_EQ(again[i].bounds.lower, merged[i].bounds.lower);
      EXPECT_EQ(again[i].bounds.upper, merged[i].bounds.upper);
    }
  }
}

TEST(ProxyMerge, ABudgetBelowTheOwnerSetsKeepsOneBoxPerSet) {
  const std::vector<Proxy> proxies = scattered(400, 3);
  const std::vector<Proxy> merged = mergeProxies(proxies, 2);
  ASSERT_EQ(merged.size(), 4u);
  std::set<std::string> owners;
  for (const Proxy& p : merged) owners.insert(p.owners.toString());
  EXPECT_EQ(owners.size(), 4u);
  expectCovered(proxies, merged);
}

TEST(ProxyMerge, SplitsTheLargestBoxFirstAlongTheGap) {
  // Two clumps of one owner, far apart: two boxes, one around each clump,
  // not a box spanning the gap.
  std::vector<Proxy> proxies;
  for (int i = 0; i < 50; ++i) {
    proxies.push_back({boxAt({float(i % 5), float(i / 5), 0}, 0.4f), RankSet::single(3)});
    proxies.push_back({boxAt({1000 + float(i % 5), float(i / 5), 0}, 0.4f), RankSet::single(3)});
  }
  const std::vector<Proxy> merged = mergeProxies(proxies, 2);
  ASSERT_EQ(merged.size(), 2u);
  for (const Proxy& p : merged) EXPECT_LT(p.bounds.size().x, 10.0f);
  expectCovered(proxies, merged);
}

TEST(ProxyMerge, EveryPartitionerStillCoversItsContentWithFewProxies) {
  const Scene source = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.05"));
  for (const std::string& name : partitionerNames()) {
    for (int ranks : {3, 8}) {
      SCOPED_TRACE(fmt::format("{} at {} ranks", name, ranks));
      Scene scene = source;
      PartitionerOptions o;
      o.partitioner = &partitionerNamed(name);
      o.maxProxies = 40;
      PartitionStats stats;
      const Partition p = partitionScene(scene, ranks, o, &stats);
      ASSERT_NO_THROW(p.checkCovers(scene));
      EXPECT_EQ(stats.proxies, p.proxies.size());
      std::set<std::string> sets;
      for (const Proxy& proxy : p.proxies) sets.insert(proxy.owners.toString());
      EXPECT_LE(p.proxies.size(), std::max<size_t>(40, sets.size()));
      if (stats.unmergedProxies > 40) {
        EXPECT_LT(stats.proxies, stats.unmergedProxies);
      }
    }
  }
}

}  // namespace ferry
