// One entry point from a scene name on the command line to a Scene: built-ins
// ("builtin:island?scale=2") and files, chosen by extension: .obj, .ply,
// .pbrt, .gltf, .glb.
#pragma once

#include <string>

#include "io/load_options.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {

Scene loadScene(const std::string& spec, const LoadOptions& options = {});
// Counts and memory estimate; for built-ins computed without making geometry.
SceneSummary describeScene(const std::string& spec, const LoadOptions& options = {});

}  // namespace ferry
