#include "io/light_emitters.h"

#include <algorithm>
#include <cmath>

#include "io/shape_tessellation.h"

namespace ferry {
namespace {

int32_t addPlaced(Scene& scene, Mesh mesh, const Affine3f& place) {
  scene.meshes.push_back(std::move(mesh));
  Object o;
  o.name = scene.meshes.back().name;
  o.meshes.push_back(int32_t(scene.meshes.size() - 1));
  scene.objects.push_back(std::move(o));
  scene.instances.push_back({int32_t(scene.objects.size() - 1), place});
  return int32_t(scene.objects.size() - 1);
}

void addToObject(Scene& scene, int32_t object, Mesh mesh) {
  scene.meshes.push_back(std::move(mesh));
  scene.objects[size_t(object)].meshes.push_back(int32_t(scene.meshes.size() - 1));
}

}  // namespace

float pointLightRadius(const Box3f& bounds) {
  float diagonal = bounds.empty() ? 1.0f : length(bounds.size());
  if (!(diagonal > 0) || !std::isfinite(diagonal)) diagonal = 1;
  return 1e-3f * diagonal;
}

void addPointLightEmitter(Scene& scene, Vec3f position, Vec3f intensity, float radius,
                          const std::string& name) {
  Mesh sphere = tessellateSphere(radius, -radius, radius, 360, 12);
  // A convex body's mean projected area is a quarter of its surface.
  float projected = meshArea(sphere) / 4;
  Material lamp;
  lamp.name = name;
  lamp.baseColor = Vec3f(0);
  lamp.emission = max(intensity, Vec3f(0)) / projected;
  sphere.name = name;
  sphere.material = scene.addMaterial(lamp);
  addPlaced(scene, std::move(sphere), Affine3f::translate(position));
}

void addSpotLightEmitter(Scene& scene, Vec3f position, Vec3f direction, Vec3f intensity,
                         float coneDegrees, float radius, const std::string& name) {
  Vec3f z = normalize(direction);
  Vec3f x = std::abs(z.x) < 0.9f ? Vec3f(1, 0, 0) : Vec3f(0, 1, 0);
  Vec3f y = normalize(cross(z, x));
  x = cross(y, z);
  Affine3f place = Affine3f::translate(position);
  for (int r = 0; r < 3; ++r) {
    place.l[r][0] = x[r];
    place.l[r][1] = y[r];
    place.l[r][2] = z[r];
  }
  Mesh disk = tessellateDisk(0, radius, 0, 360, 16);
  Material lamp;
  lamp.name = name;
  lamp.baseColor = Vec3f(0);
  lamp.emission = max(intensity, Vec3f(0)) / meshArea(disk);
  disk.name = name;
  disk.material = scene.addMaterial(lamp);
  int32_t object = addPlaced(scene, std::move(disk), place);

  Material black;
  black.name = name + " housing";
  black.baseColor = Vec3f(0);
  int32_t housing = scene.addMaterial(black);
  // Behind the disk: its back side emits into the housing.
  Mesh back = tessellateDisk(-0.05f * radius, radius * 1.05f, 0, 360, 16);
  back.name = name + " housing";
  back.material = housing;
  addToObject(scene, object, std::move(back));
  float cone = std::clamp(coneDegrees, 0.5f, 90.0f);
  if (cone < 89) {
    float h = 2 * radius / std::tan(cone * kPi / 180);
    Mesh tube = tessellateCylinder(radius * 1.05f, -0.05f * radius, h, 360, 16);
    tube.name = name + " housing";
    tube.material = housing;
    addToObject(scene, object, std::move(tube));
  }
}

}  // namespace ferry
