// Where a glTF material looks a texture up: the texture, the TEXCOORD_<n>
// set and the KHR_texture_transform applied to it. Ferry's meshes carry one
// uv set, so the loader bakes the transform of the textures read at render
// time (base colour, normal map) into the mesh's uvs, and bakes emission
// with the emissive texture's own (gltf_loader.h).
#pragma once

#include <cmath>

#include "core/math.h"

namespace ferry {

// KHR_texture_transform: uv' = offset + R(rotation) (scale * uv), in glTF's
// uv space (v down the image). R turns (u, v) to (cos u + sin v, -sin u +
// cos v), as the Khronos sample viewer and three.js do and as the
// extension's own example needs (its GLSL, read column-major, would turn
// the other way).
struct GltfUvTransform {
  Vec2f offset{0, 0};
  float rotation = 0;  // radians
  Vec2f scale{1, 1};

  bool isIdentity() const { return *this == GltfUvTransform(); }
  bool operator==(const GltfUvTransform& o) const {
    return offset.x == o.offset.x && offset.y == o.offset.y && rotation == o.rotation &&
           scale.x == o.scale.x && scale.y == o.scale.y;
  }
  bool operator!=(const GltfUvTransform& o) const { return !(*this == o); }

  Vec2f apply(Vec2f uv) const {
    if (isIdentity()) return uv;
    const float c = std::cos(rotation), s = std::sin(rotation);
    const Vec2f scaled{uv.x * scale.x, uv.y * scale.y};
    return {offset.x + c * scaled.x + s * scaled.y, offset.y - s * scaled.x + c * scaled.y};
  }
};

struct GltfTextureRef {
  int index = -1;  // into the glTF's textures; -1: none
  int texCoord = 0;
  GltfUvTransform transform;

  bool present() const { return index >= 0; }
  // Whether two textures read the same uvs (same set, same transform).
  bool sameUvsAs(const GltfTextureRef& o) const {
    return texCoord == o.texCoord && transform == o.transform;
  }
};

}  // namespace ferry
