#include "dist/forwarding.h"

#include <gtest/gtest.h>

#include <bit>

#include "core/random.h"

namespace ferry {
namespace {

float uniform(uint32_t a, uint32_t b, uint32_t seed) {
  return random01(RandomKey{a, b, 0, seed}, RandomDim::OwnerPick);
}

std::vector<Proxy> randomProxies(int count, int ranks, uint32_t seed) {
  std::vector<Proxy> proxies;
  for (int i = 0; i < count; ++i) {
    Box3f b;
    b.extend(Vec3f(uniform(i, 0, seed), uniform(i, 1, seed), uniform(i, 2, seed)) * 10.0f);
    b.extend(Vec3f(uniform(i, 3, seed), uniform(i, 4, seed), uniform(i, 5, seed)) * 10.0f);
    RankMask owners = RankMask(1) << int(uniform(i, 6, seed) * ranks);
    if (uniform(i, 7, seed) < 0.3f) owners |= RankMask(1) << int(uniform(i, 8, seed) * ranks);
    proxies.push_back({b, RankSet::fromMask(owners)});
  }
  return proxies;
}

Path64 randomRay(uint32_t k, uint32_t seed) {
  Path64 p{};
  p.origin = Vec3f(uniform(k, 10, seed), uniform(k, 11, seed), uniform(k, 12, seed)) * 10.0f;
  p.setDir(normalize(Vec3f(uniform(k, 13, seed), uniform(k, 14, seed), uniform(k, 15, seed)) - Vec3f(0.5f)));
  p.tmax = kInfinity;
  p.setPixelAndFlags(k, 0);
  p.setWeight(Vec3f(1));
  return p;
}

}  // namespace

TEST(Forwarding, PickOwnerIsDeterministicAndPicksAnOwner) {
  Path8 ray{};
  ray.setPixelAndFlags(1234, 0);
  ray.origin = {1, 2, 3};
  for (RankMask owners : {RankMask(0b1), RankMask(0b1010), RankMask(0b11111111), RankMask(1) << 63}) {
    int r = pickOwner(owners, ray);
    EXPECT_TRUE(owners & (RankMask(1) << r));
    EXPECT_EQ(r, pickOwner(owners, ray));
  }
  // Different rays spread over the owners.
  int counts[4] = {0, 0, 0, 0};
  for (uint32_t pixel = 0; pixel < 4000; ++pixel) {
    ray.setPixelAndFlags(pixel, 0);
    ++counts[pickOwner(RankMask(0b1111), ray)];
  }
  for (int c : counts) EXPECT_GT(c, 800);
}

TEST(Forwarding, FinishedRayIsShadedWhereItsHitIs) {
  Path8 ray{};
  ray.setPixelAndFlags(7, 0);
  ray.hitOwners = 0b0100;
  EXPECT_EQ(finishTraversal(ray, 2).kind, ForwardDecision::ShadeHere);
  ForwardDecision d = finishTraversal(ray, 0);
  EXPECT_EQ(d.kind, ForwardDecision::Send);
  EXPECT_EQ(d.rank, 2);
  EXPECT_TRUE(d.toShade);
  ray.hitOwners = 0;
  EXPECT_EQ(finishTraversal(ray, 5).kind, ForwardDecision::ShadeHere);  // a miss is shaded anywhere
  Path8 shadow{};
  shadow.setPixelAndFlags(7, kPathShadow | kPathOccluded);
  EXPECT_EQ(finishTraversal(shadow, 1).kind, ForwardDecision::Drop);
}

TEST(Forwarding, RingVisitsEveryRankOnceThenFinishes) {
  Path8 ray{};
  ray.setPixelAndFlags(1, 0);
  ray.tmax = kInfinity;
  int rank = 2, visits = 1;
  ray.visited = uint8_t(1u << rank);
  for (;;) {
    ForwardDecision d = forwardByRing(ray, rank, 5);
    if (d.kind != ForwardDecision::Send) break;
    EXPECT_FALSE(ray.visited & (1u << d.rank));
    rank = d.rank;
    ray.visited |= uint8_t(1u << rank);
    ++visits;
  }
  EXPECT_EQ(visits, 5);
}

// The proxy walk never revisits a rank, and ends: a forwarded ray's next rank
// is always unvisited, so at most `ranks` visits.
TEST(Forwarding, ProxyWalkNeverRevisitsARank) {
  for (int ranks : {2, 3, 8, 64}) {
    ProxyBvh bvh(randomProxies(200, ranks, 5 + ranks));
    for (uint32_t k = 0; k < 500; ++k) {
      Path64 ray = randomRay(k, 99);
      int rank = int(uniform(k, 20, 1) * ranks);
      ray.visited = RankMask(1) << rank;
      int steps = 0;
      for (;;) {
        ForwardDecision d = forwardByProxies(bvh, ray, rank);
        if (d.kind != ForwardDecision::Send || d.toShade) break;
        ASSERT_FALSE(ray.visited & (RankMask(1) << d.rank));
        rank = d.rank;
        ray.visited |= RankMask(1) << rank;
        ASSERT_LE(++steps, ranks);
      }
    }
  }
}

// The paper's replay: the visited set recomputed from the generating rank
// alone equals the mask carried by the ray, at every step of its walk.
// (Without local hits, tmax stays put, which is when the two must agree exactly;
// with a shrinking tmax replay returns the visits that still matter.)
TEST(Forwarding, ReplayReproducesTheVisitedMask) {
  for (int ranks : {2, 5, 8, 64}) {
    ProxyBvh bvh(randomProxies(150, ranks, 77 + ranks));
    for (uint32_t k = 0; k < 400; ++k) {
      Path64 ray = randomRay(k, 1234);
      int generating = int(uniform(k, 30, 2) * ranks);
      ray.visited = RankMask(1) << generating;
      int rank = generating;
      for (;;) {
        ASSERT_EQ(replayVisited(bvh, ray, generating, rank), RankMask(ray.visited))
            << "ranks " << ranks << " ray " << k;
        ForwardDecision d = forwardByProxies(bvh, ray, rank);
        if (d.kind != ForwardDecision::Send || d.toShade) break;
        rank = d.rank;
        ray.visited |= RankMask(1) << rank;
      }
    }
  }
}

TEST(Forwarding, ModesParseAndUnknownModeIsAnError) {
  EXPECT_EQ(parseForwardingMode("proxies"), ForwardingMode::Proxies);
  EXPECT_EQ(parseForwardingMode("ring"), ForwardingMode::Ring);
  EXPECT_EQ(parseForwardingMode("broadcast"), ForwardingMode::Broadcast);
  EXPECT_THROW(parseForwardingMode("telepathy"), std::exception);
}

}  // namespace ferry
