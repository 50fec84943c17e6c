// Wavefront OBJ with MTL materials and textures, through tinyobjloader.
#pragma once

#include <string>

#include "scene/scene.h"

namespace ferry {

// Loads an OBJ file as single-instance meshes (one per shape and material)
// with the MTL materials and textures the faces use, a view framing the
// bounds, and a sun and sky unless some material emits. Two streaming passes
// (the file is never held in memory): every line checked, then built through
// tinyobjloader. Throws InputError naming the file and line for malformed
// input: bad or out-of-range indices, NaN or infinite numbers, a truncated
// file, an unknown material, a missing texture. What is read and checked,
// exactly: docs/formats.md, "OBJ".
Scene loadObj(const std::string& path);

}  // namespace ferry
