// A partition of a scene over ranks: which ranks own each instance, and the
// proxies, boxes with a set of owner ranks saying "these ranks have content here".
//
// The one invariant the forwarding operator relies on: every point of every
// instance's geometry lies in some proxy whose owners all hold the instance
// (a ray that would hit it there enters that proxy first, and whichever of
// its owners it is sent to finds the hit). Extra proxies (overlapping,
// conservative) only cost forwarding, never correctness.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"
#include "partition/rank_set.h"

namespace ferry {

struct Scene;

// Rank ids travel in 16 bits in the replay path layout (0xffff: none).
constexpr int kMaxRanks = 65535;

struct Proxy {
  Box3f bounds;
  RankSet owners;
  // An instanced proxy (shape >= 0) stands for an instance of an instanced
  // object: it is entered where the ray enters one of its shape's boxes,
  // which are in the object's space and placed by the instance's transform
  // (Partition::proxyPlacements[placement]), as Embree places an instance's
  // geometry. Its `bounds` are those boxes' world box. The shape is held
  // once however many instances use it, so a tight shape costs a transform
  // per instance, not a box per shape box (docs/partitioning.md,
  // "Instanced proxies").
  int32_t shape = -1;      // Partition::proxyShapes index; -1: the box `bounds` itself
  int32_t placement = -1;  // Partition::proxyPlacements index, with a shape
};

// The boxes, in an object's space, that an instanced proxy is made of.
struct ProxyShape {
  std::vector<Box3f> boxes;
};

struct Partition {
  int ranks = 1;
  std::vector<RankSet> instanceOwners;  // per Scene::instances entry
  std::vector<Proxy> proxies;
  std::vector<ProxyShape> proxyShapes;    // what instanced proxies refer to
  std::vector<Affine3f> proxyPlacements;  // where they stand (object to world)

  std::vector<int32_t> instancesOf(int rank) const;
  // Throws InternalError if an instance has no owner, or its geometry is not
  // covered by the union of proxies owned only by its owners (see the
  // invariant above). Checked on the instance's box first, then, for proxies
  // that follow the content (spatial domains, braided mesh boxes), on each
  // mesh's box and finally on each triangle's box.
  void checkCovers(const Scene& scene) const;
};

// Instances dealt round-robin, one proxy per instance: the simplest partition,
// for testing the distributed layer before the real partitioners.
Partition roundRobinPartition(const Scene& scene, int ranks);
// Random owners (1 to 3 ranks each: replication), proxies inflated at random,
// plus random large single-owner proxies that overlap everything: a hostile
// partition for testing that the image does not depend on it.
Partition randomPartition(const Scene& scene, int ranks, uint32_t seed);

}  // namespace ferry
