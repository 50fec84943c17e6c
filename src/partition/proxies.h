// Proxies that follow the content rather than a domain: for every mesh of a
// non-instanced object either its box or (braiding, paper Section 3.2)
// several tight boxes made by BVH build steps on its triangles, so rays can
// pass through the gaps of a large mesh without being sent to its owner; and
// for an instance of an instanced object either the box of its object or,
// braided the same way, the object-space boxes of its meshes' clusters, each
// transformed (a palm's trunk and crown apart: rays low over the ground pass
// beside the trunk instead of through the crown's box).
#pragma once

#include <vector>

#include "partition/partition.h"
#include "partition/units.h"

namespace ferry {

struct Scene;

// The boxes those proxies have, each with the unit it stands for, in the
// order the proxies come in.
struct UnitBox {
  uint32_t unit;
  Box3f box;
};
std::vector<UnitBox> unitProxyBoxes(const Scene& scene, const UnitSet& units, int meshBoxes,
                                    int instanceBoxes = 1);

// `meshBoxes`: boxes per non-instanced mesh (1: the mesh's own box);
// `instanceBoxes`: boxes per mesh of an instanced object, for each of its
// instances (1: one box per instance, the object's). Each proxy is owned by
// the owners of the unit holding the instance.
std::vector<Proxy> instanceProxies(const Scene& scene, const UnitSet& units,
                                   const std::vector<RankSet>& owners, int meshBoxes,
                                   int instanceBoxes = 1);

}  // namespace ferry
