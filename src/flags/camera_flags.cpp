#include "flags/camera_flags.h"

#include <cmath>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "core/error.h"
#include "core/number_list.h"

namespace ferry {

void addCameraFlags(CLI::App* command, CameraFlags& f) {
  command
      ->add_option("--look-from", f.lookFrom,
                   "A camera given outright, instead of a named view: its position x,y,z")
      ->type_name("X,Y,Z");
  command->add_option("--look-at", f.lookAt, "The point it looks at, x,y,z")->type_name("X,Y,Z");
  command->add_option("--up", f.up, "Its up direction (default 0,1,0)")->type_name("X,Y,Z");
  command->add_option("--fov", f.fov, "Its vertical field of view in degrees (default 45)");
  command->add_option("--lens-radius", f.lensRadius,
                      "A thin lens of this radius (world units) for the camera rendered, given or\n"
                      "named (pbrt's lensradius; 0: a pinhole; default: the view's own)");
  command->add_option("--focal-distance", f.focalDistance,
                      "The distance of the plane in focus along the view axis (pbrt's\n"
                      "focaldistance; default: the view's own, else 1e6)");
}

void lensFromFlags(const CameraFlags& f, std::optional<float>& lensRadius,
                   std::optional<float>& focalDistance) {
  // (NaN: not given; CLI11 reads "nan" too, which is refused like any non-number.)
  auto given = [](float v) { return !std::isnan(v); };
  lensRadius.reset();
  focalDistance.reset();
  if (given(f.lensRadius)) {
    if (!(f.lensRadius >= 0 && std::isfinite(f.lensRadius)))
      throw InputError(fmt::format("--lens-radius {}: expected 0 or more", f.lensRadius));
    lensRadius = f.lensRadius;
  }
  if (given(f.focalDistance)) {
    if (!(f.focalDistance > 0 && std::isfinite(f.focalDistance)))
      throw InputError(
          fmt::format("--focal-distance {}: expected a positive distance", f.focalDistance));
    focalDistance = f.focalDistance;
  }
}

Vec3f parseVectorFlag(const std::string& flag, const std::string& text) {
  float v[3];
  if (!parseNumberList(text, v))
    throw InputError(fmt::format("{} '{}': expected three numbers x,y,z", flag, text));
  return {v[0], v[1], v[2]};
}

std::optional<CameraView> cameraFromFlags(const CameraFlags& f) {
  if (!f.given()) {
    if (!f.up.empty() || f.fov != 0)
      throw InputError("--up and --fov go with --look-from and --look-at");
    return std::nullopt;
  }
  if (f.lookFrom.empty() || f.lookAt.empty())
    throw InputError("--look-from and --look-at go together");
  CameraView c;
  c.name = "command line";
  c.from = parseVectorFlag("--look-from", f.lookFrom);
  c.at = parseVectorFlag("--look-at", f.lookAt);
  if (!f.up.empty()) c.up = parseVectorFlag("--up", f.up);
  if (f.fov != 0) c.fovY = f.fov;
  if (!(length(c.at - c.from) > 0))
    throw InputError("--look-from and --look-at must be different points");
  if (!(length(cross(normalize(c.at - c.from), c.up)) > 1e-4f))
    throw InputError("--up must not be parallel to the view direction");
  if (!(c.fovY > 0.01f && c.fovY < 179))
    throw InputError(fmt::format("--fov {}: expected 0.01 to 179 degrees", f.fov));
  return c;
}

}  // namespace ferry
