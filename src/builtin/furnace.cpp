#include "builtin/furnace.h"

#include <cmath>

namespace ferry::builtin {

ScenePlan planFurnace(double scale, uint32_t /*seed: nothing random*/) {
  ScenePlan plan;
  plan.name = "furnace";
  const double refine = std::sqrt(scale);
  // Even latitudes and longitudes divisible by 4 put vertices exactly on the
  // poles and on the +-x, +-z points of the equator: the bounds are exact.
  const int latitudes = 2 * int(std::clamp(std::round(32 * refine), 4.0, 8192.0));
  const int longitudes = 4 * int(std::clamp(std::round(32 * refine), 2.0, 8192.0));

  Material white;
  white.name = "white-diffuse";
  white.baseColor = Vec3f(kFurnaceAlbedo);
  const int32_t material = plan.addMaterial(white);

  MeshRecipe sphere;
  sphere.name = "sphere";
  sphere.material = material;
  sphere.counts = uvSphereCounts(latitudes, longitudes);
  sphere.build = [latitudes, longitudes] {
    MeshBuilder b(true, true, uvSphereCounts(latitudes, longitudes));
    addUvSphere(b, latitudes, longitudes, {0, 0, 0}, 1);
    return b.finish();
  };
  plan.addSingleInstanceMesh(std::move(sphere));

  plan.environmentColor = {1, 1, 1};
  CameraView view;
  view.name = "default";
  view.from = {0, 0, 4};
  view.at = {0, 0, 0};
  view.fovY = 40;
  plan.views.push_back(view);
  plan.bounds.extend(Vec3f(-1, -1, -1));
  plan.bounds.extend(Vec3f(1, 1, 1));
  return plan;
}

}  // namespace ferry::builtin
