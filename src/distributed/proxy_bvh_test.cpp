#include "distributed/proxy_bvh.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"

namespace ferry {
namespace {

float uniform(uint32_t a, uint32_t b) {
  return random01(RandomKey{a, b, 0, 42}, RandomDim::OwnerPick);
}

std::vector<Proxy> randomProxies(int count, int ranks, uint32_t seed) {
  std::vector<Proxy> proxies;
  for (int i = 0; i < count; ++i) {
    Box3f b;
    b.extend(Vec3f(uniform(seed + i, 0), uniform(seed + i, 1), uniform(seed + i, 2)) * 10.0f);
    b.extend(Vec3f(uniform(seed + i, 3), uniform(seed + i, 4), uniform(seed + i, 5)) * 10.0f);
    RankSet owners = RankSet::single(int(uniform(seed + i, 6) * ranks));
    if (uniform(seed + i, 7) < 0.3f) owners.insert(int(uniform(seed + i, 8) * ranks));
    proxies.push_back({b, owners});
  }
  return proxies;
}

ProxyBvh::Hit bruteForce(const std::vector<Proxy>& proxies, Vec3f o, Vec3f d, float tmax,
                         const RankSet& excluded) {
  ProxyBvh::Hit best;
  Vec3f inv{1 / d.x, 1 / d.y, 1 / d.z};
  for (size_t i = 0; i < proxies.size(); ++i) {
    if (proxies[i].owners.intersects(excluded)) continue;
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
    EXPECT_EQ(bvh.proxyCount(), proxies.size());
    // Every rank holds every proxy: the tree is all it keeps of them (8-wide
    // nodes, about 90 B a proxy on the island; docs/memory.md).
    EXPECT_LT(bvh.bytes(), 160 * proxies.size());
    for (uint32_t k = 0; k < 2000; ++k) {
      Vec3f o = Vec3f(uniform(k, 10), uniform(k, 11), uniform(k, 12)) * 14.0f - Vec3f(2);
      Vec3f d = normalize(Vec3f(uniform(k, 13), uniform(k, 14), uniform(k, 15)) - Vec3f(0.5f));
      float tmax = uniform(k, 16) < 0.3f ? kInfinity : uniform(k, 17) * 20;
      RankMask excluded = RankMask(randomBits(RandomKey{k, 0, 0, 7}, 0)) &
                          ((ranks == 64) ? ~RankMask(0) : ((RankMask(1) << ranks) - 1));
      excluded &= RankMask(randomBits(RandomKey{k, 1, 0, 7}, 0));
      ProxyBvh::Hit a = bvh.closest(o, d, tmax, excluded);
      ProxyBvh::Hit b = bruteForce(proxies, o, d, tmax, RankSet::fromMask(excluded));
      ASSERT_EQ(a.proxy, b.proxy) << "ray " << k << " ranks " << ranks;
      if (a.found()) {
        EXPECT_EQ(a.tEnter, b.tEnter);
        // The tree keeps no list of proxies: the owners come with the answer.
        ASSERT_EQ(a.owners(), proxies[size_t(a.proxy)].owners) << "ray " << k;
      }
      // The set query answers the same.
      ProxyBvh::Hit c = bvh.closest(o, d, tmax, RankSet::fromMask(excluded));
      ASSERT_EQ(c.proxy, a.proxy);
      ASSERT_EQ(c.owners(), a.owners());
    }
  }
}

// Above 64 ranks the BVH keeps owner sets per node; same answers as brute force.
TEST(ProxyBvh, WideOwnerSetsMatchBruteForce) {
  for (int ranks : {65, 130, 1000}) {
    std::vector<Proxy> proxies = randomProxies(300, ranks, uint32_t(ranks) * 1000);
    ProxyBvh bvh(proxies);
    EXPECT_FALSE(bvh.narrow());
    for (uint32_t k = 0; k < 1000; ++k) {
      Vec3f o = Vec3f(uniform(k, 10), uniform(k, 11), uniform(k, 12)) * 14.0f - Vec3f(2);
      Vec3f d = normalize(Vec3f(uniform(k, 13), uniform(k, 14), uniform(k, 15)) - Vec3f(0.5f));
      float tmax = uniform(k, 16) < 0.3f ? kInfinity : uniform(k, 17) * 20;
      RankSet excluded;
      for (int r = 0; r < ranks; ++r)
        if (uniform(k * 7919 + uint32_t(r), 18) < 0.4f) excluded.insert(r);
      ProxyBvh::Hit a = bvh.closest(o, d, tmax, excluded);
      ProxyBvh::Hit b = bruteForce(proxies, o, d, tmax, excluded);
      ASSERT_EQ(a.proxy, b.proxy) << "ray " << k << " ranks " << ranks;
      if (a.found()) {
        EXPECT_EQ(a.tEnter, b.tEnter);
        ASSERT_NE(a.ownerSet, nullptr);  // wide: the set the tree holds
        ASSERT_EQ(a.owners(), proxies[size_t(a.proxy)].owners) << "ray " << k;
      }
    }
  }
}

TEST(ProxyBvh, AnEmptyBoxIsNeverEntered) {
  // An empty box's slab distances swap (lower above upper), so a plain slab
  // test lets every ray in; the tree leaves such proxies out.
  std::vector<Proxy> proxies = randomProxies(100, 4, 7);
  for (size_t k = 0; k < proxies.size(); k += 3) proxies[k].bounds = Box3f{};
  proxies[1].bounds = {{0, 0, 0}, {-1, 1, 1}};  // empty on one axis
  const ProxyBvh bvh(proxies);
  int found = 0;
  for (uint32_t i = 0; i < 2000; ++i) {
    auto u = [&](uint32_t k) { return uniform(90000 + i, k); };
    const Vec3f o{u(0) * 30 - 10, u(1) * 30 - 10, u(2) * 30 - 10};
    const Vec3f d = normalize(Vec3f{u(3) - 0.5f, u(4) - 0.5f, u(5) - 0.5f});
    const ProxyBvh::Hit a = bvh.closest(o, d, kInfinity, RankMask(0));
    ProxyBvh::Hit b;
    const Vec3f inv{1 / d.x, 1 / d.y, 1 / d.z};
    for (size_t k = 0; k < proxies.size(); ++k) {  // brute force over the non-empty boxes
      float t;
      if (!proxies[k].bounds.empty() && intersectBox(proxies[k].bounds, o, inv, kInfinity, t) &&
          t < b.tEnter)
        b = {int32_t(k), t};
    }
    ASSERT_EQ(a.proxy, b.proxy);
    if (a.found()) {
      EXPECT_FALSE(proxies[size_t(a.proxy)].bounds.empty());
      ++found;
    }
  }
  EXPECT_GT(found, 100);
}

// What the replay layout relies on: the answer with a finite tmax is the
// answer with no limit if that enters before tmax, and nothing otherwise.
TEST(ProxyBvh, SmallerTmaxOnlyCutsTheFarEnd) {
  for (int ranks : {3, 8, 70}) {
    std::vector<Proxy> proxies = randomProxies(300, ranks, uint32_t(ranks) * 77);
    ProxyBvh bvh(proxies);
    for (uint32_t k = 0; k < 2000; ++k) {
      Vec3f o = Vec3f(uniform(k, 20), uniform(k, 21), uniform(k, 22)) * 14.0f - Vec3f(2);
      Vec3f d = normalize(Vec3f(uniform(k, 23), uniform(k, 24), uniform(k, 25)) - Vec3f(0.5f));
      RankSet excluded = RankSet::single(int(uniform(k, 26) * ranks));
      ProxyBvh::Hit far = bvh.closest(o, d, kInfinity, excluded);
      float tmax = uniform(k, 27) * 20;
      ProxyBvh::Hit near = bvh.closest(o, d, tmax, excluded);
      if (far.found() && far.tEnter < tmax) {
        ASSERT_EQ(near.proxy, far.proxy) << "ray " << k;
      } else {
        ASSERT_FALSE(near.found()) << "ray " << k;
      }
    }
  }
}

// The query tests a node's children eight at a time; every lane must answer
// as the scalar box test does, ties included. Boxes on an integer grid, many
// duplicated and nested (equal entry distances), rays from grid points along
// the axes (origins on slab planes, zero direction components: the NaN case
// of the slab test) and diagonals, against brute force.
TEST(ProxyBvh, TiesAndFlatRaysMatchBruteForce) {
  std::vector<Proxy> proxies;
  for (int i = 0; i < 3000; ++i) {
    const auto cell = [&](int d) { return float(int(uniform(uint32_t(i), d) * 12)); };
    Box3f b;
    b.extend(Vec3f(cell(0), cell(1), cell(2)));
    b.extend(Vec3f(cell(0), cell(1), cell(2)) + Vec3f(float(1 + i % 3)));
    proxies.push_back({b, RankSet::single(int(uniform(uint32_t(i), 3) * 8))});
    if (i % 5 == 0) proxies.push_back({b, RankSet::single(int(uniform(uint32_t(i), 4) * 8))});
  }
  ProxyBvh bvh(proxies);
  const Vec3f directions[] = {{1, 0, 0},
                              {-1, 0, 0},
                              {0, 1, 0},
                              {0, 0, -1},
                              normalize(Vec3f(1, 1, 0)),
                              normalize(Vec3f(-1, 1, 1))};
  int ties = 0;
  for (uint32_t k = 0; k < 3000; ++k) {
    const Vec3f o(float(int(uniform(k, 30) * 14)) - 1, float(int(uniform(k, 31) * 14)) - 1,
                  float(int(uniform(k, 32) * 14)) - 1);
    const Vec3f d = directions[k % 6];
    const float tmax = k % 3 == 0 ? kInfinity : float(k % 7);
    const RankMask excluded = RankMask(1) << (k % 8);
    const ProxyBvh::Hit a = bvh.closest(o, d, tmax, excluded);
    const ProxyBvh::Hit b = bruteForce(proxies, o, d, tmax, RankSet::fromMask(excluded));
    ASSERT_EQ(a.proxy, b.proxy) << "ray " << k;
    if (!a.found()) continue;
    EXPECT_EQ(a.tEnter, b.tEnter);
    // Count the answers another proxy enters at the same distance: the tie rule was needed.
    const Vec3f inv{1 / d.x, 1 / d.y, 1 / d.z};
    for (size_t i = 0; i < proxies.size(); ++i) {
      float t;
      if (int32_t(i) != a.proxy && !proxies[i].owners.intersects(RankSet::fromMask(excluded)) &&
          intersectBox(proxies[i].bounds, o, inv, tmax, t) && t == a.tEnter) {
        ++ties;
        break;
      }
    }
  }
  EXPECT_GT(ties, 100);  // the case is exercised
}

// Centres spaced exponentially make the binned SAH split off a few proxies
// per level (a deep, lopsided tree); answers as brute force.
TEST(ProxyBvh, SkewedProxiesMatchBruteForce) {
  std::vector<Proxy> proxies;
  for (int i = 0; i < 400; ++i) {
    const float x = std::ldexp(1.0f, i / 4) * (1 + float(i % 4) / 4);
    proxies.push_back({{{x, 0, 0}, {x * 1.001f, 1, 1}}, RankSet::single(i % 3)});
  }
  ProxyBvh bvh(proxies);
  for (uint32_t k = 0; k < 2000; ++k) {
    const Vec3f o(std::ldexp(1.0f, int(uniform(k, 40) * 100)), uniform(k, 41), -1);
    const Vec3f d = normalize(Vec3f(uniform(k, 42) - 0.5f, 0.0f, 1.0f));
    const RankMask excluded = RankMask(1) << (k % 3);
    const ProxyBvh::Hit a = bvh.closest(o, d, kInfinity, excluded);
    const ProxyBvh::Hit b = bruteForce(proxies, o, d, kInfinity, RankSet::fromMask(excluded));
    ASSERT_EQ(a.proxy, b.proxy) << "ray " << k;
  }
}

// A rank's own proxies in a tree of their own (the tree its forwarding
// decisions never enter) leave every answer as it was: with and without the
// own rank excluded, on random boxes with replicas, on the tie grid, at and
// above 64 ranks, and when the own rank owns every proxy or none.
TEST(ProxyBvh, OwnTreeLeavesTheAnswersUnchanged) {
  std::vector<Proxy> grid;  // many equal entry distances
  for (int i = 0; i < 2000; ++i) {
    const auto cell = [&](int d) { return float(int(uniform(uint32_t(i), d) * 10)); };
    Box3f b;
    b.extend(Vec3f(cell(0), cell(1), cell(2)));
    b.extend(Vec3f(cell(0), cell(1), cell(2)) + Vec3f(float(1 + i % 3)));
    RankSet owners = RankSet::single(int(uniform(uint32_t(i), 3) * 4));
    if (i % 4 == 0) owners.insert(int(uniform(uint32_t(i), 4) * 4));
    grid.push_back({b, owners});
  }
  struct Case {
    std::vector<Proxy> proxies;
    int ranks, own;
  };
  const Case cases[] = {{randomProxies(400, 3, 5), 3, 0},
                        {randomProxies(400, 8, 6), 8, 5},
                        {randomProxies(400, 70, 7), 70, 66},  // set owners
                        {grid, 4, 2},
                        {randomProxies(100, 1, 8), 1, 0},   // every proxy the own rank's
                        {randomProxies(100, 4, 9), 4, 9}};  // none of them
  for (const Case& c : cases) {
    const ProxyBvh one(c.proxies);
    const ProxyBvh split(c.proxies, c.own);
    if (c.own < c.ranks) {
      EXPECT_GT(split.ownOnlyCount(), 0u) << c.ranks;
    }
    if (c.ranks == 1) {
      EXPECT_EQ(split.ownOnlyCount(), c.proxies.size());
    }
    for (uint32_t k = 0; k < 3000; ++k) {
      const Vec3f o =
          c.ranks == 4 && c.own == 2
              ? Vec3f(float(int(uniform(k, 50) * 12)) - 1, float(int(uniform(k, 51) * 12)) - 1,
                      float(int(uniform(k, 52) * 12)) - 1)
              : Vec3f(uniform(k, 50), uniform(k, 51), uniform(k, 52)) * 14.0f - Vec3f(2);
      Vec3f d = normalize(Vec3f(uniform(k, 53), uniform(k, 54), uniform(k, 55)) - Vec3f(0.5f));
      if (k % 3 == 0) d = Vec3f(k % 2 ? 1.0f : -1.0f, 0, 0);  // flat: ties and NaN slabs
      const float tmax = k % 4 == 0 ? kInfinity : uniform(k, 56) * 20;
      RankSet excluded;
      if (k % 2 == 0) excluded.insert(c.own);  // a forwarding decision
      for (int r = 0; r < c.ranks; ++r)
        if (uniform(k * 131 + uint32_t(r), 57) < 0.3f) excluded.insert(r);
      const ProxyBvh::Hit a = split.closest(o, d, tmax, excluded);
      const ProxyBvh::Hit b = one.closest(o, d, tmax, excluded);
      const ProxyBvh::Hit brute = bruteForce(c.proxies, o, d, tmax, excluded);
      ASSERT_EQ(a.proxy, b.proxy) << "ray " << k << " ranks " << c.ranks;
      ASSERT_EQ(a.proxy, brute.proxy) << "ray " << k << " ranks " << c.ranks;
      if (a.found()) {
        EXPECT_EQ(a.tEnter, b.tEnter);
      }
      if (c.ranks <= 64) {
        const ProxyBvh::Hit m = split.closest(o, d, tmax, excluded.mask());
        ASSERT_EQ(m.proxy, a.proxy) << "ray " << k;
      }
    }
  }
}

TEST(ProxyBvh, AxisParallelRaysAndOriginInside) {
  std::vector<Proxy> proxies = {{{{0, 0, 0}, {1, 1, 1}}, RankSet::single(0)},
                                {{{2, 0, 0}, {3, 1, 1}}, RankSet::single(1)}};
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

namespace ferry {
namespace {

// Instanced proxies among plain ones: random shapes of a few boxes, placed by
// random rotations, scales and translations. The brute force takes each
// instanced proxy's entry as the least entry into its boxes in object space
// (what an instance of a mesh is to Embree), so the tree must agree with
// that, not with the boxes' world box.
struct InstancedCase {
  std::vector<Proxy> proxies;
  std::vector<ProxyShape> shapes;
  std::vector<Affine3f> placements;
};

constexpr int kInstancedShapes = 7;

InstancedCase instancedCase(int ranks, uint32_t seed) {
  InstancedCase c;
  c.proxies = randomProxies(100, ranks, seed);
  // Shapes of 1 to 5 boxes, and two whose boxes need a tree of their own
  // (ProxyBvh::ShapeNode): 100 boxes (two levels), 900 small ones (four).
  for (int s = 0; s < kInstancedShapes; ++s) {
    ProxyShape shape;
    if (s >= 5) {
      const int count = s == 5 ? 100 : 900;
      const float size = s == 5 ? 0.5f : 0.08f;
      for (int b = 0; b < count; ++b) {
        const uint32_t k = seed + 3000 * uint32_t(s) + uint32_t(b);
        const Vec3f corner = Vec3f(uniform(k, 26), uniform(k, 27), uniform(k, 28)) * 2.0f;
        Box3f box;
        box.extend(corner);
        box.extend(corner + Vec3f(uniform(k, 29), uniform(k, 30), uniform(k, 31)) * size);
        shape.boxes.push_back(box);
      }
      c.shapes.push_back(shape);
      continue;
    }
    for (int b = 0; b < 1 + s; ++b) {
      Box3f box;
      box.extend(Vec3f(uniform(seed + 50 * s + b, 20), uniform(seed + 50 * s + b, 21),
                       uniform(seed + 50 * s + b, 22)) *
                 2.0f);
      box.extend(Vec3f(uniform(seed + 50 * s + b, 23), uniform(seed + 50 * s + b, 24),
                       uniform(seed + 50 * s + b, 25)) *
                 2.0f);
      shape.boxes.push_back(box);
    }
    c.shapes.push_back(shape);
  }
  for (int i = 0; i < 200; ++i) {
    const uint32_t k = seed + 7000 + uint32_t(i);
    Proxy p;
    p.shape = int32_t(uniform(k, 30) * kInstancedShapes);
    p.placement = int32_t(c.placements.size());
    c.placements.push_back(
        Affine3f::translate(Vec3f(uniform(k, 31), uniform(k, 32), uniform(k, 33)) * 10.0f) *
        Affine3f::rotate(Vec3f(uniform(k, 34), uniform(k, 35), uniform(k, 36)) + Vec3f(0.1f),
                         uniform(k, 37) * 6.0f) *
        Affine3f::scale(Vec3f(0.5f + uniform(k, 38))));
    for (const Box3f& b : c.shapes[size_t(p.shape)].boxes)
      p.bounds.extend(c.placements.back().transformBox(b));
    p.owners = RankSet::single(int(uniform(k, 39) * ranks));
    c.proxies.push_back(p);
  }
  return c;
}

ProxyBvh::Hit bruteForceInstanced(const InstancedCase& c, Vec3f o, Vec3f d, float tmax,
                                  const RankSet& excluded) {
  ProxyBvh::Hit best;
  for (size_t i = 0; i < c.proxies.size(); ++i) {
    const Proxy& p = c.proxies[i];
    if (p.owners.intersects(excluded)) continue;
    float t = kInfinity;
    if (p.shape < 0) {
      const Vec3f inv{1 / d.x, 1 / d.y, 1 / d.z};
      if (!intersectBox(p.bounds, o, inv, tmax, t)) continue;
    } else {
      const Affine3f toObject = c.placements[size_t(p.placement)].inverse();
      const Vec3f oo = toObject.transformPoint(o), dd = toObject.transformVector(d);
      const Vec3f inv{1 / dd.x, 1 / dd.y, 1 / dd.z};
      for (const Box3f& b : c.shapes[size_t(p.shape)].boxes) {
        float tb;
        if (intersectBox(b, oo, inv, tmax, tb)) t = std::min(t, tb);
      }
      if (t == kInfinity) continue;
    }
    if (t < best.tEnter) best = {int32_t(i), t};
  }
  return best;
}

}  // namespace

TEST(ProxyBvh, InstancedProxiesAreEnteredWhereTheirObjectSpaceBoxesAre) {
  for (int ranks : {3, 8}) {
    for (int ownRank : {-1, 1}) {
      const InstancedCase c = instancedCase(ranks, uint32_t(ranks) * 100);
      ProxyBvh bvh(c.proxies, ownRank, c.shapes, c.placements);
      EXPECT_EQ(bvh.instancedCount(), 200u);
      int missedByShape = 0;  // rays in an instanced proxy's world box that miss its boxes
      for (uint32_t k = 0; k < 3000; ++k) {
        const Vec3f o = Vec3f(uniform(k, 10), uniform(k, 11), uniform(k, 12)) * 14.0f - Vec3f(2);
        const Vec3f d =
            normalize(Vec3f(uniform(k, 13), uniform(k, 14), uniform(k, 15)) - Vec3f(0.5f));
        const float tmax = uniform(k, 16) < 0.3f ? kInfinity : uniform(k, 17) * 20;
        const RankSet excluded = RankSet::single(int(uniform(k, 18) * ranks));
        const ProxyBvh::Hit a = bvh.closest(o, d, tmax, excluded);
        const ProxyBvh::Hit b = bruteForceInstanced(c, o, d, tmax, excluded);
        ASSERT_EQ(a.proxy, b.proxy) << "ray " << k;
        if (a.found()) {
          EXPECT_EQ(a.tEnter, b.tEnter);
          EXPECT_EQ(a.owners(), c.proxies[size_t(a.proxy)].owners);
        }
        const Vec3f inv{1 / d.x, 1 / d.y, 1 / d.z};
        for (const Proxy& p : c.proxies) {
          float t;
          if (p.shape >= 0 && intersectBox(p.bounds, o, inv, tmax, t)) {
            InstancedCase one{{p}, c.shapes, c.placements};
            missedByShape += !bruteForceInstanced(one, o, d, tmax, RankSet()).found();
          }
        }
      }
      EXPECT_GT(missedByShape, 100) << "the shapes were never tighter than their world boxes";
    }
  }
}

// A pixel's cone: no ray from the eye inside it (or within the margin of
// it) enters a proxy of another rank before the cone's clearance, and the
// clearance is where the nearest such proxy's box is, not a trivial 0.
TEST(ProxyBvh, ConeClearanceBoundsEveryRayOfTheCone) {
  int bounded = 0, cones = 0;
  for (int ranks : {2, 4, 8}) {
    for (int own : {-1, 1}) {
      std::vector<Proxy> proxies = randomProxies(300, ranks, uint32_t(ranks) * 77 + 5);
      ProxyBvh bvh(proxies, own);
      for (uint32_t k = 0; k < 300; ++k) {
        const Vec3f eye = Vec3f(uniform(k, 20), uniform(k, 21), uniform(k, 22)) * 14.0f - Vec3f(2);
        const Vec3f axis =
            normalize(Vec3f(uniform(k, 23), uniform(k, 24), uniform(k, 25)) - Vec3f(0.5f));
        const Frame frame(axis);
        const float halfAngle = 0.001f + 0.1f * uniform(k, 26);
        const float s = std::tan(halfAngle);
        const std::array<Vec3f, 4> corners{frame.toWorld({-s, -s, 1}), frame.toWorld({s, -s, 1}),
                                           frame.toWorld({s, s, 1}), frame.toWorld({-s, s, 1})};
        const int rank = int(uniform(k, 27) * ranks);
        const RankMask excluded = RankMask(1) << rank;
        const float clearance = bvh.coneClearance(eye, corners, excluded);
        ++cones;
        if (clearance > 0) ++bounded;
        for (uint32_t j = 0; j < 64; ++j) {
          // Inside the cone, or just outside by up to half the margin.
          const float reach = 1 + (j % 4 == 0 ? ProxyBvh::kConeMargin * 0.5f / s : 0.0f);
          const float a = (2 * uniform(k * 64 + j, 28) - 1) * reach;
          const float b = (2 * uniform(k * 64 + j, 29) - 1) * reach;
          const Vec3f d = normalize(frame.toWorld({a * s, b * s, 1}));
          const ProxyBvh::Hit hit = bruteForce(proxies, eye, d, kInfinity, RankSet::single(rank));
          ASSERT_GE(hit.tEnter, clearance * (1 - 1e-5f))
              << "cone " << k << " ray " << j << " ranks " << ranks;
        }
      }
    }
  }
  // Random eyes often stand inside another rank's box (clearance 0).
  EXPECT_GT(bounded, cones / 4);
}

TEST(ProxyBvh, ConeClearanceIsTheNearestOtherRanksBoxInTheCone) {
  auto box = [](Vec3f lo, Vec3f hi) {
    Box3f b;
    b.extend(lo);
    b.extend(hi);
    return b;
  };
  // Eye at the origin, looking down -z through a cone of about 0.01 rad.
  const std::vector<Proxy> proxies{
      {box({-1, -1, -9}, {1, 1, -8}), RankSet::single(1)},  // ahead at 8: rank 1
      {box({-1, -1, -3}, {1, 1, -2}), RankSet::single(0)},  // ahead at 2: this rank's
      {box({3, -1, -5}, {4, 1, -4}), RankSet::single(2)},   // nearer, outside the cone
      {box({-1, -1, 20}, {1, 1, 21}), RankSet::single(3)},  // behind the eye
  };
  const float s = 0.005f;
  const std::array<Vec3f, 4> corners{Vec3f(-s, -s, -1), Vec3f(s, -s, -1), Vec3f(s, s, -1),
                                     Vec3f(-s, s, -1)};
  for (int own : {-1, 0}) {
    ProxyBvh bvh(proxies, own);
    EXPECT_EQ(bvh.coneClearance(Vec3f(0), corners, RankMask(1) << 0), 8.0f);
    // Excluding rank 1 too leaves nothing in the cone.
    EXPECT_EQ(bvh.coneClearance(Vec3f(0), corners, 0b11), kInfinity);
    // Another rank's view: this rank's box at 2 is the nearest.
    EXPECT_EQ(bvh.coneClearance(Vec3f(0), corners, RankMask(1) << 3), 2.0f);
  }
}

}  // namespace ferry
