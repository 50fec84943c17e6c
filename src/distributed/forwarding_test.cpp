#include "distributed/forwarding.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>

#include "core/error.h"
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
    RankSet owners = RankSet::single(int(uniform(i, 6, seed) * ranks));
    if (uniform(i, 7, seed) < 0.3f) owners.insert(int(uniform(i, 8, seed) * ranks));
    if (uniform(i, 9, seed) < 0.1f) owners.insert(int(uniform(i, 10, seed) * ranks));
    proxies.push_back({b, owners});
  }
  return proxies;
}

Path64 randomRay(uint32_t k, uint32_t seed) {
  Path64 p{};
  p.origin = Vec3f(uniform(k, 10, seed), uniform(k, 11, seed), uniform(k, 12, seed)) * 10.0f;
  p.setDir(normalize(Vec3f(uniform(k, 13, seed), uniform(k, 14, seed), uniform(k, 15, seed)) -
                     Vec3f(0.5f)));
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
  for (RankMask owners :
       {RankMask(0b1), RankMask(0b1010), RankMask(0b11111111), RankMask(1) << 63}) {
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

// A replica goes to the owner whose own proxies carry the ray farthest. Along
// +x: a replicated box [0,1] on ranks 1 and 2, then rank 2's box [1,3],
// rank 1's [2.5,3] and rank 3's [4,5]. From rank 0 every ray is sent to 2,
// whatever its hash: the first box not held by 2 starts at 2.5, the first
// not held by 1 at 1.
TEST(Forwarding, AReplicaGoesToTheOwnerThatReachesFarthest) {
  auto box = [](float x0, float x1) {
    Box3f b;
    b.extend({x0, -1, -1});
    b.extend({x1, 1, 1});
    return b;
  };
  RankSet replicated = RankSet::single(1);
  replicated.insert(2);
  const std::vector<Proxy> proxies = {{box(0, 1), replicated},
                                      {box(1, 3), RankSet::single(2)},
                                      {box(2.5f, 3), RankSet::single(1)},
                                      {box(4, 5), RankSet::single(3)}};
  for (int ownRank : {-1, 0}) {
    const ProxyBvh bvh(proxies, ownRank);
    int toRankOne = 0;
    for (uint32_t pixel = 0; pixel < 64; ++pixel) {
      Path8 ray{};
      ray.origin = {-1, 0, 0};
      ray.setDir({1, 0, 0});
      ray.tmax = kInfinity;
      ray.setPixelAndFlags(pixel, 0);
      ray.visited = 1;  // traced on rank 0
      const ForwardDecision d = forwardByProxies(bvh, ray, 0);
      ASSERT_EQ(d.kind, ForwardDecision::Send);
      EXPECT_EQ(d.rank, 2) << "pixel " << pixel;
      EXPECT_EQ(d.queries, 3u);  // the closest proxy, then the reach of each owner
      toRankOne += pickOwner(RankMask(0b110), ray) == 1;  // what a hash would have picked
      // The same from the set form (the replay layout).
      EXPECT_EQ(forwardByProxies(bvh, ray, 0, RankSet::single(0)).rank, 2);
    }
    EXPECT_GT(toRankOne, 0);  // the hash alone would have sent some rays to rank 1
    // An unreplicated proxy costs one query, as before.
    Path8 ray{};
    ray.origin = {1.5f, 0, 0};
    ray.setDir({1, 0, 0});
    ray.tmax = kInfinity;
    ray.visited = 0b0101;  // ranks 0 and 2
    const ForwardDecision d = forwardByProxies(bvh, ray, 2);
    EXPECT_EQ(d.rank, 1);
    EXPECT_EQ(d.queries, 1u);
    // Reach is measured past tmax: a short ray chooses as a long one does.
    uint32_t queries = 0;
    const ProxyBvh::Hit first = bvh.closest({-1, 0, 0}, {1, 0, 0}, 1.5f, RankMask(1));
    ASSERT_TRUE(first.found());
    EXPECT_EQ(reachingOwners(bvh, first, {-1, 0, 0}, {1, 0, 0}, RankSet::single(0), queries),
              RankSet::single(2));
    EXPECT_EQ(queries, 2u);
  }
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

// The paper's replay, property-tested against the mask: random proxies (with
// replicas), random rays, and at every rank a random local hit that shrinks
// tmax (anywhere, even before the entry of the proxy that brought the ray
// there), including on the generating rank before its first decision. At every
// arrival, the visited set replayed from the generating rank with the arrival
// tmax equals the carried mask, and the replay layout's next rank equals the
// mask layout's. Above 64 ranks the reference carries a RankSet instead.
void checkReplayAgainstCarriedSet(int ranks, uint32_t seed, int rays) {
  ProxyBvh bvh(randomProxies(150, ranks, seed));
  int forwards = 0, shrinks = 0;
  for (uint32_t k = 0; k < uint32_t(rays); ++k) {
    Path64 mask = randomRay(k, seed * 31);
    if (k % 3 == 0) mask.setPixelAndFlags(k, kPathShadow);  // shadow rays walk the same way
    PathReplay replay{};
    static_cast<PathCore&>(replay) = static_cast<const PathCore&>(mask);
    replay.clearHistory();
    const int generating = int(uniform(k, 30, seed) * ranks);
    replay.markTraced(generating);
    ASSERT_EQ(int(replay.generatingRank), generating);
    RankSet carried = RankSet::single(generating);
    if (ranks <= 64) mask.visited = RankMask(1) << generating;
    int rank = generating;
    uint32_t decisionQueries = 0;  // of the decisions that brought the ray here
    for (int step = 0;; ++step) {
      ASSERT_LE(step, ranks);
      if (rank != generating) {
        // Arrival: replay with the tmax the ray arrived with.
        ReplayResult r = replayWalk(bvh, replay, generating, rank);
        ASSERT_TRUE(r.reached) << "ranks " << ranks << " ray " << k << " step " << step;
        ASSERT_EQ(r.visited, carried) << "ranks " << ranks << " ray " << k << " step " << step;
        // The replay makes the decisions again: their queries (replicas: one
        // more per owner weighed).
        EXPECT_EQ(r.queries, decisionQueries);
      }
      // The local trace: sometimes a hit, which shrinks tmax.
      if (uniform(k * 64 + uint32_t(step), 31, seed) < 0.4f) {
        float t = uniform(k * 64 + uint32_t(step), 32, seed) * std::min(mask.tmax, 25.0f);
        mask.tmax = replay.tmax = t;
        mask.hitOwners = RankMask(1) << (rank % 64);
        replay.setHit(rank, 0);
        ++shrinks;
      }
      ForwardDecision byReplay = forwardByProxies(bvh, replay, rank, carried);
      ForwardDecision bySet = forwardByProxies(bvh, mask, rank, carried);
      if (ranks <= 64) {
        ForwardDecision byMask = forwardByProxies(bvh, mask, rank);
        ASSERT_EQ(byMask.kind, bySet.kind);
        ASSERT_EQ(byMask.rank, bySet.rank);
      }
      const bool forwarded = byReplay.kind == ForwardDecision::Send && !byReplay.toShade;
      ASSERT_EQ(forwarded, bySet.kind == ForwardDecision::Send && !bySet.toShade) << "ray " << k;
      if (!forwarded) break;
      ASSERT_EQ(byReplay.rank, bySet.rank) << "ranks " << ranks << " ray " << k << " step " << step;
      ASSERT_FALSE(carried.contains(byReplay.rank)) << "a revisit";
      ASSERT_EQ(byReplay.queries, bySet.queries);
      decisionQueries += byReplay.queries;
      rank = byReplay.rank;
      carried.insert(rank);
      if (ranks <= 64) mask.visited |= RankMask(1) << rank;
      ++forwards;
    }
  }
  // The test means something: rays moved, and tmax shrank on the way.
  EXPECT_GT(forwards, rays / 2);
  EXPECT_GT(shrinks, rays / 4);
}

TEST(Forwarding, ReplayReproducesTheVisitedMaskAndTheNextRank) {
  for (int ranks : {2, 3, 5, 8, 64}) checkReplayAgainstCarriedSet(ranks, 77 + uint32_t(ranks), 400);
}

TEST(Forwarding, ReplayReproducesTheVisitedSetAbove64Ranks) {
  for (int ranks : {65, 100, 300}) checkReplayAgainstCarriedSet(ranks, 5 + uint32_t(ranks), 300);
}

TEST(Forwarding, PickOwnerFromASetPicksAsFromAMask) {
  Path8 ray{};
  ray.origin = {0.25f, 2, 3};
  for (uint32_t pixel = 0; pixel < 500; ++pixel) {
    ray.setPixelAndFlags(pixel, 0);
    RankMask m = RankMask(randomBits(RandomKey{pixel, 1, 0, 3}, 0)) | 1;
    ASSERT_EQ(pickOwner(RankSet::fromMask(m), ray), pickOwner(m, ray));
    RankSet wide = RankSet::fromMask(m);
    wide.insert(64 + int(pixel % 200));
    int r = pickOwner(wide, ray);
    ASSERT_TRUE(wide.contains(r));
  }
}

TEST(Forwarding, ReplayLayoutFinishesOnTheRankThatFoundTheHit) {
  PathReplay ray{};
  ray.setPixelAndFlags(7, 0);
  ray.clearHistory();
  ray.markTraced(3);
  EXPECT_EQ(ray.generatingRank, 3);
  ray.markTraced(5);  // only the first trace is the generating rank
  EXPECT_EQ(ray.generatingRank, 3);
  EXPECT_FALSE(ray.hasHit());
  EXPECT_EQ(finishTraversal(ray, 9).kind, ForwardDecision::ShadeHere);  // a miss is shaded anywhere
  ray.setHit(70, 0);
  EXPECT_TRUE(ray.hasHit());
  EXPECT_EQ(finishTraversal(ray, 70).kind, ForwardDecision::ShadeHere);
  ForwardDecision d = finishTraversal(ray, 2);
  EXPECT_EQ(d.kind, ForwardDecision::Send);
  EXPECT_EQ(d.rank, 70);
  EXPECT_TRUE(d.toShade);
}

TEST(Forwarding, ReplayRingVisitsEveryRankOnceFromTheGeneratingRank) {
  for (int ranks : {2, 5, 70}) {
    PathReplay ray{};
    ray.setPixelAndFlags(1, 0);
    ray.tmax = kInfinity;
    ray.clearHistory();
    const int generating = ranks / 2;
    ray.markTraced(generating);
    Path64 mask{};
    mask.setPixelAndFlags(1, 0);
    mask.visited = RankMask(1) << generating;
    RankSet seen = RankSet::single(generating);
    int rank = generating;
    for (;;) {
      ForwardDecision d = forwardByRing(ray, rank, ranks);
      if (ranks <= 64) {
        ForwardDecision m = forwardByRing(mask, rank, ranks);
        ASSERT_EQ(m.kind, d.kind);
        ASSERT_EQ(m.rank, d.rank);
      }
      if (d.kind != ForwardDecision::Send) break;
      ASSERT_FALSE(seen.contains(d.rank));
      rank = d.rank;
      seen.insert(rank);
      mask.visited |= RankMask(1) << (rank % 64);
    }
    EXPECT_EQ(seen.count(), ranks);
  }
}

TEST(Forwarding, ModesParseAndUnknownModeIsAnError) {
  EXPECT_EQ(parseForwardingMode("proxies"), ForwardingMode::Proxies);
  EXPECT_EQ(parseForwardingMode("ring"), ForwardingMode::Ring);
  EXPECT_EQ(parseForwardingMode("broadcast"), ForwardingMode::Broadcast);
  EXPECT_THROW(parseForwardingMode("telepathy"), std::exception);
  for (ForwardingMode mode :
       {ForwardingMode::Proxies, ForwardingMode::Ring, ForwardingMode::Broadcast})
    EXPECT_EQ(parseForwardingMode(toString(mode)), mode);
  try {
    parseForwardingMode("Ring");
    FAIL() << "a name differing in case was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "forwarding 'Ring': expected proxies, ring or broadcast");
  }
}

}  // namespace ferry
