// tinygltf as Ferry builds it: no stb inside (no decoding at parse time, no
// writing), no loading of external images at parse time (they are read only
// if a material uses them), the system's nlohmann/json. Include this instead
// of <tiny_gltf.h> so every translation unit sees the same configuration.
#pragma once

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_INCLUDE_JSON
// The JSON library must come first.
// clang-format off
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>
// clang-format on
