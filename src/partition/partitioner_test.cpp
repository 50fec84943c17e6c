#include "partition/partitioner.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "builtin/builtin.h"
#include "core/error.h"
#include "core/hash64.h"
#include "partition/object_partitioner.h"
#include "partition/ray_guided_partitioner.h"
#include "partition/ray_sampler.h"
#include "partition/scene_split.h"
#include "partition/spatial_partitioner.h"
#include "partition/split_loop.h"
#include "partition/units.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

// Built-ins are generated once per process; tests partition copies.
const Scene& builtinScene(const std::string& spec) {
  static std::map<std::string, Scene> cache;
  auto it = cache.find(spec);
  if (it == cache.end()) it = cache.emplace(spec, generateBuiltin(parseBuiltinSpec(spec))).first;
  return it->second;
}

const char* const kIsland = "builtin:island?scale=0.05";
const char* const kLandscape = "builtin:landscape?scale=0.05";
const char* const kCornell = "builtin:cornell";

// A material model's name and parameters, as a hash.
uint64_t modelHash(const MaterialModel& model) {
  MaterialRecordWriter record;
  model.write(record);
  std::string bytes(model.name());
  bytes.append(record.bytes().begin(), record.bytes().end());
  return hash64(bytes.data(), bytes.size());
}

// Every triangle of the scene as placed in the world, with what shades it
// (the transform, the material's values, the vertex data), as a hash, summed
// into an order-independent fingerprint of the multiset (count and two sums
// of differently mixed hashes): two scenes that render the same give equal
// fingerprints whatever their structure.
std::array<uint64_t, 3> placedTriangles(const Scene& scene) {
  std::vector<std::vector<uint64_t>> perMesh(scene.meshes.size());
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const Mesh& mesh = scene.meshes[m];
    const Material& mat = scene.materials[mesh.material];
    const uint64_t model = modelHash(*mat.model);
    for (const Vec3i& tri : mesh.indices) {
      std::vector<float> r;
      for (int v = 0; v < 3; ++v) {
        for (int i = 0; i < 3; ++i) r.push_back(mesh.positions[tri[v]][i]);
        for (int i = 0; i < 3; ++i)
          r.push_back(mesh.normals.empty() ? -9.0f : mesh.normals[tri[v]][i]);
        for (int i = 0; i < 2; ++i) r.push_back(mesh.uvs.empty() ? -9.0f : mesh.uvs[tri[v]][i]);
      }
      r.push_back(float(mesh.material));
      r.push_back(mat.emission.x + mat.baseColor.y);
      r.push_back(float(mat.alphaTexture));
      r.push_back(float(mat.baseColorTexture));
      const uint64_t h[2] = {hash64(r.data(), r.size() * sizeof(float)), model};
      perMesh[m].push_back(hash64(h, sizeof(h)));
    }
  }
  std::array<uint64_t, 3> out{0, 0, 0};
  for (const Instance& inst : scene.instances) {
    const uint64_t placement = hash64(&inst.transform, sizeof(Affine3f));
    for (int32_t m : scene.objects[inst.object].meshes)
      for (uint64_t t : perMesh[m]) {
        uint64_t h[2] = {t, placement};
        ++out[0];
        out[1] += hash64(h, sizeof(h), 1);
        out[2] += hash64(h, sizeof(h), 2);
      }
  }
  return out;
}

PartitionerOptions named(const std::string& name, bool breakObjects = true) {
  PartitionerOptions o;
  o.partitioner = &partitionerNamed(name);
  o.keepObjectsWhole = !breakObjects;
  return o;
}

}  // namespace

TEST(Partitioners, EveryPartitionerCoversAllContentAtManyRankCounts) {
  for (const char* spec : {kCornell, kIsland, kLandscape}) {
    for (const std::string& name : partitionerNames()) {
      for (bool breakObjects : {true, false}) {
        for (int ranks : {1, 2, 3, 8, 13}) {
          SCOPED_TRACE(fmt::format("{} {} ranks {} break {}", spec, name, ranks, breakObjects));
          Scene scene = builtinScene(spec);
          PartitionStats stats;
          Partition p = partitionScene(scene, ranks, named(name, breakObjects), &stats);
          ASSERT_EQ(p.ranks, ranks);
          ASSERT_EQ(p.instanceOwners.size(), scene.instances.size());
          ASSERT_NO_THROW(p.checkCovers(scene));
          // No rank is left without content (spare ranks hold copies), for the six.
          if (name != "round-robin" && name != "random") {
            for (int r = 0; r < ranks; ++r) EXPECT_FALSE(p.instancesOf(r).empty()) << "rank " << r;
          }
          ASSERT_EQ(stats.rankBytes.size(), size_t(ranks));
          for (int r = 0; r < ranks; ++r)
            EXPECT_EQ(stats.rankBytes[r], ownedMemory(scene, p.instancesOf(r)).total());
        }
      }
    }
  }
}

TEST(Partitioners, RewrittenSceneHasTheSameTrianglesAndMaterials) {
  for (const char* spec : {kCornell, kIsland, kLandscape}) {
    const Scene& original = builtinScene(spec);
    const std::array<uint64_t, 3> before = placedTriangles(original);
    for (const std::string& name : paperPartitionerNames()) {
      SCOPED_TRACE(fmt::format("{} {}", spec, name));
      Scene scene = original;
      PartitionStats stats;
      partitionScene(scene, 4, named(name), &stats);
      scene.validate();
      EXPECT_EQ(placedTriangles(scene), before);
      EXPECT_EQ(stats.split.originalInstance.size(), scene.instances.size());
      if (name == "best" && spec != std::string(kCornell)) {
        EXPECT_GT(stats.split.meshesCut, 0u);  // the terrain is far over 1/256 of the island
        EXPECT_GT(scene.meshes.size(), original.meshes.size());
      }
    }
  }
}

TEST(Partitioners, SplitForPartitioningBreaksSingleInstanceObjectsInPlace) {
  Scene scene = builtinScene(kIsland);
  const std::vector<uint32_t> placements = scene.instanceCountPerObject();
  uint64_t multiMeshSingles = 0, extraInstances = 0;
  for (size_t o = 0; o < scene.objects.size(); ++o)
    if (placements[o] == 1 && scene.objects[o].meshes.size() > 1) {
      ++multiMeshSingles;
      extraInstances += scene.objects[o].meshes.size() - 1;
    }
  ASSERT_GT(multiMeshSingles, 0u)
      << "the island's campfire and lanterns are single-instance, multi-mesh";
  const size_t instances = scene.instances.size();
  SceneSplitReport r = splitForPartitioning(scene, {});
  EXPECT_EQ(r.objectsBroken, multiMeshSingles);
  EXPECT_EQ(scene.instances.size(), instances + extraInstances);
  for (size_t o = 0; o < scene.objects.size(); ++o)
    if (scene.instanceCountPerObject()[o] == 1) {
      EXPECT_EQ(scene.objects[o].meshes.size(), 1u);
    }
  // Instance order is kept: the original indices never decrease.
  EXPECT_TRUE(std::is_sorted(r.originalInstance.begin(), r.originalInstance.end()));
}

TEST(Partitioners, CutPiecesAreBoundedAndCoherent) {
  Scene scene = builtinScene(kIsland);
  const uint64_t limit = 64 * 1024;
  SceneSplitOptions o;
  o.maxPieceBytes = limit;
  SceneSplitReport r = splitForPartitioning(scene, o);
  ASSERT_GT(r.meshesCut, 0u);
  // Pieces come from halving by count, so each is at most about twice the
  // target (plus duplicated boundary vertices).
  const std::vector<uint32_t> placements = scene.instanceCountPerObject();
  for (const Mesh& m : scene.meshes)
    if (m.name.find('#') != std::string::npos) {
      EXPECT_LE(meshCost(m).total(), 3 * limit) << m.name;
    }
}

TEST(Partitioners, UnitCostsEqualOwnedMemory) {
  Scene scene = builtinScene(kLandscape);
  for (UnitGrouping g : {UnitGrouping::Instances, UnitGrouping::Objects}) {
    UnitSet units = extractUnits(scene, {g, false});
    std::vector<uint32_t> every(units.units.size()), some;
    for (uint32_t u = 0; u < every.size(); ++u) {
      every[u] = u;
      if (u % 3 == 1) some.push_back(u);
    }
    auto instancesOf = [&](const std::vector<uint32_t>& members) {
      std::vector<int32_t> out;
      for (uint32_t u : members)
        out.insert(out.end(), units.units[u].instances.begin(), units.units[u].instances.end());
      std::sort(out.begin(), out.end());
      return out;
    };
    EXPECT_EQ(costOf(units, every), ownedMemory(scene, instancesOf(every)).total());
    EXPECT_EQ(costOf(units, some), ownedMemory(scene, instancesOf(some)).total());
    // Shared content is counted once: the parts' sum exceeds the whole.
    std::vector<uint32_t> rest;
    for (uint32_t u : every)
      if (u % 3 != 1) rest.push_back(u);
    EXPECT_GT(costOf(units, some) + costOf(units, rest), costOf(units, every));
  }
}

TEST(Partitioners, WholeModeMakesOneUnitOfAllNonInstancedContent) {
  const Scene& scene = builtinScene(kIsland);
  UnitSet broken = extractUnits(scene, {UnitGrouping::Objects, false});
  UnitSet whole = extractUnits(scene, {UnitGrouping::Objects, true});
  size_t nonInstanced = 0;
  for (const Unit& u : broken.units) nonInstanced += u.nonInstanced;
  ASSERT_GT(nonInstanced, 3u);
  EXPECT_EQ(whole.units.size(), broken.units.size() - nonInstanced + 1);
}

TEST(Partitioners, ReplicationStaysWithinItsBudget) {
  for (const char* spec : {kIsland, kLandscape}) {
    for (double budget : {0.0, 0.01, 0.05, 0.2}) {
      for (int ranks : {2, 8}) {
        SCOPED_TRACE(fmt::format("{} budget {} ranks {}", spec, budget, ranks));
        PartitionerOptions o = named("best");
        o.replicationBudget = budget;
        Scene scene = builtinScene(spec);
        PartitionStats with;
        partitionScene(scene, ranks, o, &with);
        EXPECT_LE(double(with.replicatedBytes), budget * double(with.inputBytes));
        // The copies' bytes are exactly what the ranks hold beyond the same
        // partition without them.
        o.replicationBudget = 0;
        Scene again = builtinScene(spec);
        PartitionStats without;
        partitionScene(again, ranks, o, &without);
        uint64_t sumWith = 0, sumWithout = 0;
        for (uint64_t b : with.rankBytes) sumWith += b;
        for (uint64_t b : without.rankBytes) sumWithout += b;
        EXPECT_EQ(sumWith - sumWithout, with.replicatedBytes);
        // At 8 ranks the parts are near best's cap (1.25 x an even share),
        // which leaves no room for copies there.
        if (budget >= 0.05 && spec == std::string(kIsland) && ranks == 2) {
          EXPECT_GT(with.replicatedUnits, 0u) << "the ocean is large and cheap";
        }
      }
    }
  }
}

TEST(Partitioners, AreDeterministic) {
  for (const std::string& name : partitionerNames()) {
    Scene a = builtinScene(kIsland), b = builtinScene(kIsland);
    Partition pa = partitionScene(a, 5, named(name)), pb = partitionScene(b, 5, named(name));
    EXPECT_EQ(pa.instanceOwners, pb.instanceOwners) << name;
    ASSERT_EQ(pa.proxies.size(), pb.proxies.size()) << name;
    for (size_t k = 0; k < pa.proxies.size(); ++k) {
      EXPECT_EQ(pa.proxies[k].owners, pb.proxies[k].owners);
      EXPECT_TRUE(pa.proxies[k].bounds.lower == pb.proxies[k].bounds.lower);
      EXPECT_TRUE(pa.proxies[k].bounds.upper == pb.proxies[k].bounds.upper);
    }
  }
}

TEST(Partitioners, ProxyStylesDifferAsDescribed) {
  auto run = [](const std::string& name, int ranks, PartitionStats& s, Scene& scene) {
    scene = builtinScene(kIsland);
    return partitionScene(scene, ranks, named(name), &s);
  };
  PartitionStats s;
  Scene scene;
  Partition spatial = run("spatial-sah", 6, s, scene);
  EXPECT_EQ(spatial.proxies.size(), size_t(s.parts));  // one domain per part
  Partition naive = run("object-naive", 6, s, scene);
  EXPECT_EQ(naive.proxies.size(), s.units);  // one box per object
  Partition braided = run("object-proxies", 6, s, scene);
  Scene scene2;
  Partition bvh = run("bvh-style", 6, s, scene2);
  EXPECT_EQ(naive.instanceOwners, braided.instanceOwners);  // the same parts
  EXPECT_GT(braided.proxies.size(), bvh.proxies.size());    // 64 boxes per non-instanced mesh
  // Object partitioners never split an object over ranks.
  std::map<int32_t, RankSet> ownerOfObject;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    auto [it, fresh] = ownerOfObject.emplace(scene.instances[i].object, naive.instanceOwners[i]);
    if (!fresh) {
      EXPECT_EQ(it->second, naive.instanceOwners[i]);
    }
  }
}

TEST(Partitioners, BraidedInstancesKeepThePartsAndCoverTheContent) {
  // --instance-proxies: the same parts, instanced proxies instead of boxes,
  // still covering every instance's geometry (checkCovers; tighter:
  // proxies_test.cpp).
  // ray-guided too: it weighs its splits with one box per instance whatever
  // the proxies.
  for (const std::string name : {"object-proxies", "best", "ray-guided"}) {
    SCOPED_TRACE(name);
    PartitionerOptions one = named(name), four = named(name);
    one.maxProxies = four.maxProxies = 0;
    one.instanceProxies = 1;
    four.instanceProxies = 4;
    Scene a = builtinScene(kIsland), b = builtinScene(kIsland);
    const Partition pa = partitionScene(a, 5, one);
    const Partition pb = partitionScene(b, 5, four);
    EXPECT_EQ(pa.instanceOwners, pb.instanceOwners);
    // One instanced proxy per instance, whose shape has 4 boxes per mesh
    // (held once per object), where one box per instance was.
    EXPECT_EQ(pb.proxies.size(), pa.proxies.size());
    EXPECT_TRUE(pa.proxyShapes.empty());
    size_t instanced = 0, shapeBoxes = 0;
    for (const Proxy& p : pb.proxies) instanced += p.shape >= 0;
    for (const ProxyShape& s : pb.proxyShapes) shapeBoxes += s.boxes.size();
    EXPECT_GT(instanced, 1000u);
    EXPECT_GT(shapeBoxes, 2 * pb.proxyShapes.size());
    EXPECT_NO_THROW(pb.checkCovers(b));
  }
}

TEST(Partitioners, BestAndRayGuidedBraidTheirInstancesByDefault) {
  EXPECT_EQ(instanceProxiesFor(named("best")), kShapeBoxesBySize);
  EXPECT_EQ(instanceProxiesFor(named("ray-guided")), kShapeBoxesBySize);
  EXPECT_EQ(instanceProxiesFor(named("object-proxies")), 1);  // the paper's: one box per instance
  PartitionerOptions two = named("object-proxies");
  two.instanceProxies = 2;
  EXPECT_EQ(instanceProxiesFor(two), 2);
}

TEST(Partitioners, FineShapesThatWouldBecomeWorldBoxesAreAnErrorNamingTheSettings) {
  // Instanced proxies hold their boxes once per object; when the instances
  // alone reach --max-proxies they become world boxes, k per mesh of every
  // instance, which above kMaxWorldInstanceBoxes is refused, not made.
  Scene scene = builtinScene(kIsland);
  PartitionerOptions o = named("best");
  o.instanceProxies = kMaxWorldInstanceBoxes + 1;
  o.maxProxies = 100;
  try {
    partitionScene(scene, 3, o);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("instance-proxies 65"), std::string::npos) << message;
    EXPECT_NE(message.find("max-proxies 100"), std::string::npos) << message;
  }
  // Up to kMaxWorldInstanceBoxes the fallback is made, as before; so is
  // the default's (the object's box per instance, then merged).
  for (int instanceProxies : {2, 0}) {
    SCOPED_TRACE(instanceProxies);
    Scene again = builtinScene(kIsland);
    o.instanceProxies = instanceProxies;
    const Partition p = partitionScene(again, 3, o);
    EXPECT_TRUE(p.proxyShapes.empty());
    EXPECT_LE(p.proxies.size(), 100u);
    EXPECT_NO_THROW(p.checkCovers(again));
  }
}

TEST(Partitioners, CheckCoversCatchesAGap) {
  // Each partitioner's proxies are needed: take one away (or shrink one) and
  // some content is no longer covered.
  for (const std::string& name : paperPartitionerNames()) {
    SCOPED_TRACE(name);
    Scene scene = builtinScene(kIsland);
    Partition p = partitionScene(scene, 4, named(name));
    ASSERT_NO_THROW(p.checkCovers(scene));
    // The proxy with the largest volume surely matters.
    size_t largest = 0;
    auto volume = [](const Box3f& b) {
      Vec3f s = b.size();
      return double(s.x) * s.y * s.z + s.x + s.y + s.z;
    };
    for (size_t k = 1; k < p.proxies.size(); ++k)
      if (volume(p.proxies[k].bounds) > volume(p.proxies[largest].bounds)) largest = k;
    Partition shrunk = p;
    Box3f& b = shrunk.proxies[largest].bounds;
    b.upper = b.lower + b.size() * 0.5f;
    EXPECT_THROW(shrunk.checkCovers(scene), InternalError);
    Partition dropped = p;
    dropped.proxies.erase(dropped.proxies.begin() + long(largest));
    EXPECT_THROW(dropped.checkCovers(scene), InternalError);
  }
}

// An instanced proxy covers its instance only through its shape, placed as
// the instance is and owned by its owners: spoil any of the three and the
// check finds the gap.
TEST(Partitioners, CheckCoversCatchesAGapInAnInstancedProxy) {
  Scene scene = builtinScene(kIsland);
  const Partition p = partitionScene(scene, 4, named("best"));
  ASSERT_NO_THROW(p.checkCovers(scene));
  size_t k = 0;
  while (k < p.proxies.size() && (p.proxies[k].shape < 0 || p.proxies[k].owners.count() != 1)) ++k;
  ASSERT_LT(k, p.proxies.size());
  const Proxy& proxy = p.proxies[k];
  Partition shrunk = p;
  for (Box3f& b : shrunk.proxyShapes[size_t(proxy.shape)].boxes)
    b.upper = b.lower + b.size() * 0.5f;
  EXPECT_THROW(shrunk.checkCovers(scene), InternalError);
  Partition moved = p;
  Affine3f& placed = moved.proxyPlacements[size_t(proxy.placement)];
  placed.t = placed.t + Vec3f(0.01f, 0, 0);
  EXPECT_THROW(moved.checkCovers(scene), InternalError);
  Partition elsewhere = p;
  elsewhere.proxies[k].owners = RankSet::single((proxy.owners.lowest() + 1) % 4);
  EXPECT_THROW(elsewhere.checkCovers(scene), InternalError);
}

TEST(Partitioners, MaxPartCurvesStartAtTheWholeAndNeverGrowWithoutReplication) {
  for (const std::string& name : paperPartitionerNames()) {
    SCOPED_TRACE(name);
    Scene scene = builtinScene(kIsland);
    std::vector<uint64_t> curve = maxPartBytesCurve(scene, named(name), 24);
    ASSERT_EQ(curve.size(), 24u);
    UnitSet units = extractUnits(scene, {UnitGrouping::Instances, false});
    std::vector<uint32_t> every(units.units.size());
    for (uint32_t u = 0; u < every.size(); ++u) every[u] = u;
    EXPECT_EQ(curve[0], costOf(units, every));
    if (name != "best") {
      for (size_t n = 1; n < curve.size(); ++n) EXPECT_LE(curve[n], curve[n - 1]) << "n " << n + 1;
    }
    // The curve agrees with partitioning for that many ranks.
    for (int ranks : {3, 8}) {
      Scene again = builtinScene(kIsland);
      PartitionStats s;
      partitionScene(again, ranks, named(name), &s);
      EXPECT_EQ(curve[ranks - 1], s.maxRankBytes()) << "ranks " << ranks;
    }
  }
}

// The ray-guided partitioner's balance (the largest part at most
// 1.3 x total / N at 8 ranks), on both built-in scenes at the scale the goal
// is stated for (at scale 0.05 single units are too coarse to balance: the
// island's largest part is 1.32 x there).
TEST(Partitioners, RayGuidedKeepsTheLargestPartWithin130PercentOfAnEvenShare) {
  for (const char* spec : {"builtin:island", "builtin:landscape"}) {
    Scene scene = builtinScene(spec);
    PartitionStats s;
    partitionScene(scene, 8, named("ray-guided"), &s);
    EXPECT_LE(double(s.maxRankBytes()), 1.3 * double(s.inputBytes) / 8) << spec;
    EXPECT_GT(s.sampledRays, 0u);
    EXPECT_GT(s.separatedRays, 0u);
  }
}

// --max-part trades memory for forwarding: with parts up to 2.7 x an even
// share, the ray sample's estimate of the forwards falls (at full scale 2.0
// to 2.6 times fewer predicted on the landscape's views, docs/partitioning.md),
// and the largest part stays within what was asked.
TEST(Partitioners, RayGuidedMaxPartTradesMemoryForForwards) {
  Scene scene = builtinScene(kLandscape);
  PartitionStats tight, loose;
  partitionScene(scene, 8, named("ray-guided"), &tight);
  PartitionerOptions o = named("ray-guided");
  o.maxPart = 2.7;
  partitionScene(scene, 8, o, &loose);
  const double share = double(loose.inputBytes) / 8;
  EXPECT_LE(double(loose.maxRankBytes()), (2.7 + kRayGuidedReplicationMargin) * share);
  EXPECT_GT(loose.maxRankBytes(), tight.maxRankBytes());
  EXPECT_LT(double(loose.separatedRays), 0.8 * double(tight.separatedRays));
}

TEST(Partitioners, ObjectAndHybridPartitionsShrinkTheLargestPart) {
  // Not a fixed number: the largest part at 8 ranks is well below the whole
  // for the partitioners that can separate content.
  for (std::string name : {"object-naive", "bvh-style", "best"}) {
    Scene scene = builtinScene(kLandscape);
    PartitionStats s;
    partitionScene(scene, 8, named(name), &s);
    EXPECT_LT(double(s.maxRankBytes()), 0.6 * double(s.inputBytes)) << name;
  }
}

TEST(Partitioners, UnknownNamesAndRankCountsAreInputErrors) {
  Scene scene = builtinScene(kCornell);
  EXPECT_THROW(named("kd-tree"), InputError);
  EXPECT_THROW(partitionScene(scene, 0, named("best")), InputError);
  EXPECT_THROW(partitionScene(scene, kMaxRanks + 1, named("best")), InputError);
  EXPECT_THROW(partitionerNamed("spatial"), InputError);
}

TEST(Partitioners, TheRegistryFindsEveryPartitionerByItsName) {
  for (const Partitioner* p : partitioners()) EXPECT_EQ(&partitionerNamed(p->name()), p);
  EXPECT_EQ(partitionerNames().size(), partitioners().size());
  EXPECT_EQ(paperPartitionerNames().size(), 6u);
  EXPECT_EQ(&defaultPartitioner(2), &bestPartitioner());
  EXPECT_EQ(defaultPartitioner(1).name(), "round-robin");
  EXPECT_EQ(PartitionerOptions{}.chosen().name(), "best");
  try {
    partitionerNamed("Best");
    FAIL() << "a name differing in case was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "unknown partitioner 'Best' (partitioners: spatial-simple, spatial-sah, "
              "object-naive, object-proxies, bvh-style, best, ray-guided, round-robin, random)");
  }
  EXPECT_THROW(partitionerNamed(""), InputError);
}

TEST(Partitioners, EverySettingAPartitionerReadsExistsAndIsChecked) {
  for (const Partitioner* p : partitioners())
    for (std::string_view name : p->settings()) {
      bool found = false;
      for (const PartitionerSetting& s : partitionerSettings()) found |= s.name == name;
      EXPECT_TRUE(found) << p->name() << " reads an unknown setting " << name;
    }
  PartitionerOptions o;
  o.meshProxies = 0;
  try {
    checkPartitionerOptions(o);
    FAIL() << "mesh-proxies 0 was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "partitioner setting mesh-proxies = 0: expected 1 to 4096");
  }
  Scene scene = builtinScene(kCornell);
  EXPECT_THROW(partitionScene(scene, 2, o), InputError);
}

// Above 64 ranks owner sets grow past one word: the spare ranks (the Cornell
// box has 8 instances) hold copies, including ranks 64 and above.
TEST(Partitioners, MoreThan64RanksGetCopiesBeyondRank63) {
  for (const char* name : {"best", "ray-guided", "spatial-sah", "round-robin", "random"}) {
    SCOPED_TRACE(name);
    Scene scene = builtinScene(kCornell);
    Partition p = partitionScene(scene, 70, named(name));
    p.checkCovers(scene);
    bool beyond = false;
    for (const RankSet& owners : p.instanceOwners) beyond = beyond || owners.highest() >= 64;
    for (const Proxy& proxy : p.proxies) beyond = beyond || proxy.owners.highest() >= 64;
    if (std::string(name) != "round-robin") {
      EXPECT_TRUE(beyond);
    }
  }
}

TEST(SplitLoop, SpareRanksGetCopiesOfTheCostliestParts) {
  Scene scene = builtinScene(kCornell);  // 8 instances: 13 ranks need copies
  PartitionStats s;
  Partition p = partitionScene(scene, 13, named("bvh-style"), &s);
  EXPECT_LT(s.parts, 13);
  int replicated = 0;
  for (const RankSet& m : p.instanceOwners) replicated += m.count() > 1;
  EXPECT_GT(replicated, 0);
  p.checkCovers(scene);
}

}  // namespace ferry
