// The lights of a scene as a small scene of their own, for ranks that hold
// only part of the geometry: light sampling needs every emitter, wherever it
// lives. Holds the suns, the environment, and every emissive mesh placed in
// world space (one identity-placed mesh per instance of an emissive mesh, in
// the order of instances and then of the object's meshes), each with its own
// material and no textures. Built from the scene as given, before any
// partitioning rewrite.
//
// LightSampler(lightScene(s)) samples exactly as LightSampler(s) does: the
// same triangles in the same order, with the same float values (positions
// are transformed here by the same transformPoint, and placing them by the
// identity transform again is exact).
#pragma once

#include "scene/scene.h"

namespace ferry {

Scene lightScene(const Scene& scene);

}  // namespace ferry
