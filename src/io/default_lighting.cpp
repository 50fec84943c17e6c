#include "io/default_lighting.h"

#include <algorithm>
#include <cmath>

namespace ferry {

void addDefaultView(Scene& scene) {
  scene.views.push_back(framingView(scene.worldBounds()));
}

CameraView framingView(const Box3f& bounds) {
  CameraView view;
  view.name = "default";
  view.fovY = 45.0f;
  view.at = bounds.empty() ? Vec3f(0) : bounds.center();
  float radius = bounds.empty() ? 1.0f : 0.5f * length(bounds.size());
  if (!(radius > 0) || !std::isfinite(radius)) radius = 1;
  // The bounding sphere fits the vertical field of view.
  float distance = radius / std::sin(0.5f * view.fovY * kPi / 180.0f);
  view.from = view.at + Vec3f(0, 0, distance);
  view.up = {0, 1, 0};
  return view;
}

void addDefaultViewAndLights(Scene& scene) {
  addDefaultView(scene);
  bool emissive = std::any_of(scene.materials.begin(), scene.materials.end(),
                              [](const Material& m) { return m.isEmissive(); });
  if (!emissive) {
    SunLight sun;
    sun.direction = normalize(Vec3f(0.4f, 1.0f, 0.6f));
    scene.suns.push_back(sun);
    scene.environment.color = Vec3f(0.5f);
  }
}

}  // namespace ferry
