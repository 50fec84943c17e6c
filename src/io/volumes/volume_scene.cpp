#include <cmath>

#include "io/default_lighting.h"
#include "io/volumes/volume_files.h"

namespace ferry {

Scene volumeScene(const std::string& name, Medium medium, const Box3f& box) {
  Scene scene = framedVolumeScene(name, box);
  scene.media.push_back(std::move(medium));
  scene.mediumBoundaries.push_back({boxMesh(box, name + " box"), {0, kNoMedium}});
  return scene;
}

Scene framedVolumeScene(const std::string& name, const Box3f& box) {
  Scene scene;
  scene.name = name;
  // Framed as a lone mesh is (io/default_lighting.h), lit by a sun and a sky.
  CameraView view;
  view.name = "default";
  view.fovY = 45;
  view.at = box.center();
  const float radius = 0.5f * length(box.size());
  view.from = view.at + Vec3f(0, 0, radius / std::sin(0.5f * view.fovY * kPi / 180));
  scene.views.push_back(view);
  SunLight sun;
  sun.direction = normalize(Vec3f(0.4f, 1.0f, 0.6f));
  scene.suns.push_back(sun);
  scene.environment.color = Vec3f(0.5f);
  return scene;
}

}  // namespace ferry
