// Proxies that follow the content rather than a domain: one box per instance
// of an instanced object, and for every mesh of a non-instanced object either
// its box or (braiding, paper Section 3.2) several tight boxes made by BVH
// build steps on its triangles, so rays can pass through the gaps of a large
// mesh without being sent to its owner.
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
std::vector<UnitBox> unitProxyBoxes(const Scene& scene, const UnitSet& units, int meshBoxes);

// `meshBoxes`: boxes per non-instanced mesh (1: the mesh's own box). Each
// proxy is owned by the owners of the unit holding the instance.
std::vector<Proxy> instanceProxies(const Scene& scene, const UnitSet& units,
                                   const std::vector<RankSet>& owners, int meshBoxes);

}  // namespace ferry
