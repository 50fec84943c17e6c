// The camera and light a scene file without its own gets (OBJ, PLY), so that
// any mesh renders framed and lit.
#pragma once

#include "scene/scene.h"

namespace ferry {

// Adds a view "default" that frames the world bounds, looking along -z from
// in front (+z), fovY 45. If no material is emissive, adds a sun (from above,
// front right) and a constant environment of 0.5; a scene with emissive
// materials is taken to be lit as authored (a Cornell box) and gets neither.
void addDefaultViewAndLights(Scene& scene);

// Only the view (for formats that bring their own lights but no camera).
void addDefaultView(Scene& scene);

// That view for `bounds`: the bounding sphere fits the vertical field of view.
CameraView framingView(const Box3f& bounds);

}  // namespace ferry
