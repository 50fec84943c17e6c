#include "render/surface.h"

#include "scene/scene.h"

namespace ferry {

std::vector<Affine3f> instanceInverses(const Scene& scene) {
  std::vector<Affine3f> out;
  out.reserve(scene.instances.size());
  for (const Instance& inst : scene.instances) out.push_back(inst.transform.inverse());
  return out;
}

SurfaceTable::SurfaceTable(const Scene& scene) : inverses(instanceInverses(scene)) {
  std::vector<uint32_t> objectMeshes(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    objectMeshes[o] = uint32_t(meshes.size());
    for (int32_t m : scene.objects[o].meshes) meshes.push_back(meshArrays(scene, scene.meshes[m]));
  }
  instanceMeshes.reserve(scene.instances.size());
  for (const Instance& inst : scene.instances) instanceMeshes.push_back(objectMeshes[inst.object]);
}

}  // namespace ferry
