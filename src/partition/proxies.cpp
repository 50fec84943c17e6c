#include "partition/proxies.h"

#include <algorithm>

#include "partition/triangle_clusters.h"
#include "scene/scene.h"

namespace ferry {

int shapeBoxesForMesh(int instanceBoxes, uint32_t triangles) {
  if (instanceBoxes != kShapeBoxesBySize) return instanceBoxes;
  const uint32_t boxes = (triangles + kTrianglesPerShapeBox - 1) / kTrianglesPerShapeBox;
  return int(std::clamp<uint32_t>(boxes, 1, kMaxShapeBoxesPerMesh));
}

std::vector<std::vector<Box3f>> instancedObjectBoxes(const Scene& scene, int instanceBoxes) {
  const std::vector<uint32_t> placements = scene.instanceCountPerObject();
  std::vector<std::vector<Box3f>> objectBoxes(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    if (placements[o] <= 1) continue;
    if (instanceBoxes == 1) {
      objectBoxes[o].push_back(scene.objectBounds(int32_t(o)));
      continue;
    }
    for (int32_t m : scene.objects[o].meshes) {
      if (scene.meshes[m].triangleCount() == 0) continue;
      Mesh scratch;
      const Mesh& mesh = scene.geometry(m, scratch);
      const int clusters = shapeBoxesForMesh(instanceBoxes, mesh.triangleCount());
      for (const auto& cluster : clusterTriangles(mesh, Affine3f::identity(), clusters))
        objectBoxes[o].push_back(trianglesBounds(mesh, Affine3f::identity(), cluster));
    }
    for (int32_t g : scene.objects[o].geometries)  // one box a geometry of another kind
      if (const Shape* shape = scene.geometries[g].shape.get(); shape && !shape->bounds().empty())
        objectBoxes[o].push_back(shape->bounds());
  }
  return objectBoxes;
}

uint64_t instancedInstanceCount(const Scene& scene, const UnitSet& units) {
  const std::vector<uint32_t> placements = scene.instanceCountPerObject();
  uint64_t count = 0;
  for (const Unit& unit : units.units)
    for (int32_t i : unit.instances)
      count += placements[size_t(scene.instances[i].object)] > 1 && !scene.instances[i].motion;
  return count;
}

void addInstancedProxies(const Scene& scene, const UnitSet& units,
                         const std::vector<RankSet>& owners, int instanceBoxes,
                         Partition& partition) {
  std::vector<std::vector<Box3f>> objectBoxes = instancedObjectBoxes(scene, instanceBoxes);
  std::vector<int32_t> shapeOf(scene.objects.size(), -1);
  // An instance's world box is that of its shape's boxes, transformed. A
  // shape may have thousands, so each run of kBoundsRun consecutive boxes
  // (clusters of one mesh, in the braiding's order, so close together) is
  // transformed as its union: a box a little wider than the exact one, at a
  // kBoundsRun-th of the cost per instance. Only the proxy tree's culling
  // sees the difference; where a ray enters a proxy comes from its boxes.
  constexpr size_t kBoundsRun = 8;
  std::vector<std::vector<Box3f>> runsOf(scene.objects.size());
  for (uint32_t u = 0; u < units.units.size(); ++u)
    for (int32_t i : units.units[u].instances) {
      const Instance& inst = scene.instances[i];
      std::vector<Box3f>& boxes = objectBoxes[size_t(inst.object)];
      if (boxes.empty()) continue;  // placed once (a box proxy), or no triangles
      if (inst.motion) continue;    // swept boxes in the world (unitProxyBoxes)
      int32_t& shape = shapeOf[size_t(inst.object)];
      if (shape < 0) {
        Box3f all;
        for (const Box3f& b : boxes) all.extend(b);
        const float margin = kInstancedShapeMargin * length(all.size());
        for (Box3f& b : boxes) b = Box3f{b.lower - Vec3f(margin), b.upper + Vec3f(margin)};
        shape = int32_t(partition.proxyShapes.size());
        partition.proxyShapes.push_back({boxes});
        std::vector<Box3f>& runs = runsOf[size_t(inst.object)];
        for (size_t k = 0; k < boxes.size(); k += kBoundsRun) {
          Box3f run;
          for (size_t j = k; j < std::min(boxes.size(), k + kBoundsRun); ++j) run.extend(boxes[j]);
          runs.push_back(run);
        }
      }
      Proxy p;
      p.owners = owners[u];
      p.shape = shape;
      p.placement = int32_t(partition.proxyPlacements.size());
      partition.proxyPlacements.push_back(inst.transform);
      for (const Box3f& run : runsOf[size_t(inst.object)])
        p.bounds.extend(inst.transform.transformBox(run));
      partition.proxies.push_back(std::move(p));
    }
}

std::vector<UnitBox> unitProxyBoxes(const Scene& scene, const UnitSet& units, int meshBoxes,
                                    int instanceBoxes, bool instancedToo) {
  const std::vector<uint32_t> placements = scene.instanceCountPerObject();
  // An instanced object's boxes, in object space, made once: its own box, or
  // braided, its meshes' clusters; an instance's proxies are those, transformed.
  const std::vector<std::vector<Box3f>> objectBoxes =
      instancedToo ? instancedObjectBoxes(scene, instanceBoxes)
                   : std::vector<std::vector<Box3f>>(scene.objects.size());
  // Reserved exactly (clusterTriangles makes min(triangles, clusters)):
  // braided, these are several times the proxies kept after merging.
  size_t count = 0;
  for (const Unit& unit : units.units)
    for (int32_t i : unit.instances) {
      const int32_t o = scene.instances[i].object;
      if (placements[o] > 1 && !scene.instances[i].motion) {
        count += objectBoxes[o].size();  // none when !instancedToo
        continue;
      }
      for (int32_t m : scene.objects[o].meshes)
        count += std::min<size_t>(scene.meshes[m].triangleCount(), size_t(std::max(meshBoxes, 1)));
      count += scene.objects[o].geometries.size();
    }
  std::vector<UnitBox> boxes;
  boxes.reserve(count);
  for (uint32_t u = 0; u < units.units.size(); ++u) {
    for (int32_t i : units.units[u].instances) {
      const Instance& inst = scene.instances[i];
      if (inst.motion) {  // a moving instance: each mesh's and geometry's swept box
        for (int32_t m : scene.objects[inst.object].meshes)
          if (scene.meshes[m].triangleCount() > 0)
            boxes.push_back({u, inst.placeBox(scene.meshes[m].bounds())});
        for (int32_t g : scene.objects[inst.object].geometries)
          if (const Shape* shape = scene.geometries[g].shape.get();
              shape && !shape->bounds().empty())
            boxes.push_back({u, inst.placeBox(shape->bounds())});
        continue;
      }
      if (placements[inst.object] > 1) {
        for (const Box3f& objectBox : objectBoxes[inst.object]) {
          Box3f b = inst.transform.transformBox(objectBox);
          if (!b.empty()) boxes.push_back({u, b});
        }
        continue;
      }
      for (int32_t m : scene.objects[inst.object].meshes) {
        if (scene.meshes[m].triangleCount() == 0) continue;
        if (meshBoxes <= 1) {
          boxes.push_back({u, inst.transform.transformBox(scene.meshes[m].bounds())});
          continue;
        }
        Mesh scratch;
        const Mesh& mesh = scene.geometry(m, scratch);
        for (const auto& cluster : clusterTriangles(mesh, inst.transform, meshBoxes))
          boxes.push_back({u, trianglesBounds(mesh, inst.transform, cluster)});
      }
      for (int32_t g : scene.objects[inst.object].geometries)  // one box a geometry
        if (const Shape* shape = scene.geometries[g].shape.get(); shape && !shape->bounds().empty())
          boxes.push_back({u, inst.transform.transformBox(shape->bounds())});
    }
  }
  return boxes;
}

std::vector<Proxy> instanceProxies(const Scene& scene, const UnitSet& units,
                                   const std::vector<RankSet>& owners, int meshBoxes,
                                   int instanceBoxes) {
  std::vector<Proxy> proxies;
  for (const UnitBox& b : unitProxyBoxes(scene, units, meshBoxes, instanceBoxes))
    proxies.push_back({b.box, owners[b.unit]});
  return proxies;
}

}  // namespace ferry
