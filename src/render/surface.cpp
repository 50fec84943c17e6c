#include "render/surface.h"

#include "scene/scene.h"

namespace ferry {

std::vector<Affine3f> instanceInverses(const Scene& scene) {
  std::vector<Affine3f> out;
  out.reserve(scene.instances.size());
  for (const Instance& inst : scene.instances) out.push_back(inst.transform.inverse());
  return out;
}

}  // namespace ferry
