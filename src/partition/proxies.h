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
// With `instancedToo` false, instances of instanced objects are left out
// (they become instanced proxies: addInstancedProxies).
std::vector<UnitBox> unitProxyBoxes(const Scene& scene, const UnitSet& units, int meshBoxes,
                                    int instanceBoxes = 1, bool instancedToo = true);

// `instanceBoxes`, the boxes per mesh of an instanced object's shape: 1
// (the object's box), N > 1 (N cluster boxes per mesh), or
// kShapeBoxesBySize: one box per kTrianglesPerShapeBox triangles of each
// mesh, at most kMaxShapeBoxesPerMesh, so a large mesh gets a tight shape
// and a small one is not cut finer than it is. The boxes `instanceBoxes`
// gives a mesh of `triangles` triangles:
constexpr int kShapeBoxesBySize = 0;
constexpr uint32_t kTrianglesPerShapeBox = 4;
constexpr int kMaxShapeBoxesPerMesh = 1024;
int shapeBoxesForMesh(int instanceBoxes, uint32_t triangles);

// An instanced object's boxes in its own space: its box (`instanceBoxes`
// 1), or braided, shapeBoxesForMesh cluster boxes per mesh; empty for
// objects placed once. Instanced proxies' shapes are these, grown by
// kInstancedShapeMargin of the object's box diagonal, so that a ray that
// Embree finds hitting a triangle on a box's face enters the box too, though
// the proxy query takes the ray into object space with other floats.
std::vector<std::vector<Box3f>> instancedObjectBoxes(const Scene& scene, int instanceBoxes);
constexpr float kInstancedShapeMargin = 1e-3f;

// The instances of instanced objects (placed more than once) in `units`: at
// most the instanced proxies addInstancedProxies makes.
uint64_t instancedInstanceCount(const Scene& scene, const UnitSet& units);

// One instanced proxy (Proxy::shape) per instance of an instanced object in
// `units`, owned by its unit's owners; its shape, the object's
// instancedObjectBoxes, is added to partition.proxyShapes once per object.
void addInstancedProxies(const Scene& scene, const UnitSet& units,
                         const std::vector<RankSet>& owners, int instanceBoxes,
                         Partition& partition);

// `meshBoxes`: boxes per non-instanced mesh (1: the mesh's own box);
// `instanceBoxes`: boxes per mesh of an instanced object, for each of its
// instances (1: one box per instance, the object's). Each proxy is owned by
// the owners of the unit holding the instance.
std::vector<Proxy> instanceProxies(const Scene& scene, const UnitSet& units,
                                   const std::vector<RankSet>& owners, int meshBoxes,
                                   int instanceBoxes = 1);

}  // namespace ferry
