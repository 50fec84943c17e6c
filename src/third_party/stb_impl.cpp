// The single translation unit that holds the stb, tinyobjloader and tinygltf
// implementations.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>

// tinygltf reuses the stb compiled above and the system's nlohmann/json, and
// decodes no image itself: Ferry's glTF loader decodes only the images its
// materials use (see io/gltf/gltf_config.h, which every includer goes through).
#include <nlohmann/json.hpp>
#define TINYGLTF_IMPLEMENTATION
#include "io/gltf/gltf_config.h"
