// Point and spot lights as small emitting shapes. Ferry's lights are suns,
// an environment and emissive triangles (sampled by area); a point light is
// none of these, so the loaders that meet one (pbrt, glTF) make a tiny
// emitter with the same intensity instead.
#pragma once

#include "scene/scene.h"

namespace ferry {

// The emitter size for a scene: 1/1000 of its bounds' diagonal (small
// enough not to be seen as an object, large enough for float precision).
float pointLightRadius(const Box3f& sceneBounds);

// A sphere of `radius` at `position` whose radiance gives `intensity`
// (W/sr, per channel) in every direction: L = I / (mean projected area).
void addPointLightEmitter(Scene& scene, Vec3f position, Vec3f intensity, float radius,
                          const std::string& name);

// A spot light: a disk of `radius` facing `direction`, emitting L = I / area
// (the intensity along the axis), at the bottom of a black tube whose opening
// lets light out up to `coneDegrees` off the axis, fading towards the edge as
// the tube hides the disk. Cones of 89 degrees or more get no tube.
void addSpotLightEmitter(Scene& scene, Vec3f position, Vec3f direction, Vec3f intensity,
                         float coneDegrees, float radius, const std::string& name);

}  // namespace ferry
