// --look-from/--look-at/--up/--fov: a camera given outright on the command
// line, for `render`, `view` and `partition` (its --predict-forwards), so any
// view can be rendered or evaluated, not only a scene's named ones.
#pragma once

#include <cmath>
#include <optional>
#include <string>

#include "scene/scene.h"

namespace CLI {
class App;
}

namespace ferry {

struct CameraFlags {
  std::string lookFrom, lookAt, up;  // "x,y,z"; empty: not given
  float fov = 0;                     // vertical, degrees; 0: the default
  // The thin lens of whichever camera renders (given or named); NaN: the view's own.
  float lensRadius = std::nanf(""), focalDistance = std::nanf("");
  bool given() const { return !lookFrom.empty() || !lookAt.empty(); }
};

void addCameraFlags(CLI::App* command, CameraFlags& flags);

// The camera the flags give (named "command line"), or none if neither
// --look-from nor --look-at is given; throws InputError naming the flag for
// one without the other, a bad vector, coincident points, an up parallel to
// the view direction or a field of view outside 0.01..179 degrees.
std::optional<CameraView> cameraFromFlags(const CameraFlags& flags);
// --lens-radius and --focal-distance, checked (InputError naming the flag).
void lensFromFlags(const CameraFlags& flags, std::optional<float>& lensRadius,
                   std::optional<float>& focalDistance);

// "x,y,z" -> a vector; throws InputError naming the flag.
Vec3f parseVectorFlag(const std::string& flag, const std::string& text);

}  // namespace ferry
