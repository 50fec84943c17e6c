#include "partition/proxies.h"

#include "partition/triangle_clusters.h"
#include "scene/scene.h"

namespace ferry {

std::vector<Proxy> instanceProxies(const Scene& scene, const UnitSet& units,
                                   const std::vector<RankSet>& owners, int meshBoxes) {
  const std::vector<uint32_t> placements = scene.instanceCountPerObject();
  std::vector<Box3f> objectBounds(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o)
    if (placements[o] > 1) objectBounds[o] = scene.objectBounds(int32_t(o));
  std::vector<Proxy> proxies;
  for (size_t u = 0; u < units.units.size(); ++u) {
    const RankSet& mask = owners[u];
    for (int32_t i : units.units[u].instances) {
      const Instance& inst = scene.instances[i];
      if (placements[inst.object] > 1) {
        Box3f b = inst.transform.transformBox(objectBounds[inst.object]);
        if (!b.empty()) proxies.push_back({b, mask});
        continue;
      }
      for (int32_t m : scene.objects[inst.object].meshes) {
        const Mesh& mesh = scene.meshes[m];
        if (mesh.indices.empty()) continue;
        if (meshBoxes <= 1) {
          proxies.push_back({inst.transform.transformBox(mesh.bounds()), mask});
          continue;
        }
        for (const auto& cluster : clusterTriangles(mesh, inst.transform, meshBoxes))
          proxies.push_back({trianglesBounds(mesh, inst.transform, cluster), mask});
      }
    }
  }
  return proxies;
}

}  // namespace ferry
