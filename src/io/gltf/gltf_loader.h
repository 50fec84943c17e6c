// glTF 2.0 scenes (.gltf with .bin and image files, or .glb) through tinygltf.
// Each glTF mesh used by a node becomes one Ferry object (a Ferry mesh per
// triangle primitive), and every node using it, and every entry of its
// EXT_mesh_gpu_instancing, one instance. Materials are metallic-roughness with
// glTF's dielectric specular layer as Ferry's coat (gltf_specular_layers.h);
// lights come from KHR_lights_punctual, views from the nodes' cameras.
// Malformed input or a wrong extension value is an InputError naming the file
// (and the material); what is approximated or ignored is warned about.
// What is read, exactly: docs/formats.md, "glTF".
#pragma once

#include <string>

#include "io/load_options.h"
#include "scene/scene.h"

namespace ferry {

Scene loadGltf(const std::string& path, const LoadOptions& options = {});

}  // namespace ferry
