#include "partition/partition.h"

#include <fmt/format.h>

#include <bit>

#include "core/error.h"
#include "core/random.h"
#include "scene/scene.h"

namespace ferry {
namespace {

std::vector<Box3f> instanceWorldBounds(const Scene& scene) {
  std::vector<Box3f> objectBounds(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o) objectBounds[o] = scene.objectBounds(int32_t(o));
  std::vector<Box3f> bounds(scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i)
    bounds[i] = scene.instances[i].transform.transformBox(objectBounds[scene.instances[i].object]);
  return bounds;
}

}  // namespace

std::vector<int32_t> Partition::instancesOf(int rank) const {
  std::vector<int32_t> out;
  for (size_t i = 0; i < instanceOwners.size(); ++i)
    if (instanceOwners[i] & (RankMask(1) << rank)) out.push_back(int32_t(i));
  return out;
}

void Partition::checkCovers(const Scene& scene) const {
  FERRY_CHECK(instanceOwners.size() == scene.instances.size());
  std::vector<Box3f> bounds = instanceWorldBounds(scene);
  for (size_t i = 0; i < bounds.size(); ++i) {
    if (instanceOwners[i] == 0) throw InternalError(fmt::format("instance {} has no owner", i));
    if (bounds[i].empty()) continue;
    bool covered = false;
    for (const Proxy& p : proxies)
      if ((p.owners & ~instanceOwners[i]) == 0 && p.bounds.contains(bounds[i])) covered = true;
    if (!covered) throw InternalError(fmt::format("instance {} is not covered by a proxy of its owners", i));
  }
}

Partition roundRobinPartition(const Scene& scene, int ranks) {
  Partition p;
  p.ranks = ranks;
  std::vector<Box3f> bounds = instanceWorldBounds(scene);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    RankMask owner = RankMask(1) << (i % ranks);
    p.instanceOwners.push_back(owner);
    if (!bounds[i].empty()) p.proxies.push_back({bounds[i], owner});
  }
  return p;
}

Partition randomPartition(const Scene& scene, int ranks, uint32_t seed) {
  Partition p;
  p.ranks = ranks;
  std::vector<Box3f> bounds = instanceWorldBounds(scene);
  Box3f world;
  for (const Box3f& b : bounds) world.extend(b);
  auto uniform = [&](uint32_t a, uint32_t b) {
    return random01(RandomKey{a, b, 0, seed}, RandomDim::OwnerPick);
  };
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    int copies = 1 + int(uniform(uint32_t(i), 0) * std::min(3, ranks));
    RankMask owners = 0;
    for (int c = 0; owners == 0 || std::popcount(owners) < copies; ++c)
      owners |= RankMask(1) << int(uniform(uint32_t(i), 1 + c) * ranks);
    p.instanceOwners.push_back(owners);
    if (bounds[i].empty()) continue;
    // Inflated by up to half its size: conservative, overlapping neighbours.
    Vec3f grow = bounds[i].size() * (0.5f * uniform(uint32_t(i), 100));
    p.proxies.push_back({{bounds[i].lower - grow, bounds[i].upper + grow}, owners});
  }
  // Random single-owner boxes anywhere in the world.
  for (int k = 0; k < 2 * ranks; ++k) {
    Vec3f a = world.lower + world.size() * Vec3f(uniform(1000000 + k, 1), uniform(1000000 + k, 2),
                                                 uniform(1000000 + k, 3));
    Vec3f b = world.lower + world.size() * Vec3f(uniform(1000000 + k, 4), uniform(1000000 + k, 5),
                                                 uniform(1000000 + k, 6));
    Box3f box;
    box.extend(a);
    box.extend(b);
    p.proxies.push_back({box, RankMask(1) << int(uniform(1000000 + k, 7) * ranks)});
  }
  return p;
}

}  // namespace ferry
