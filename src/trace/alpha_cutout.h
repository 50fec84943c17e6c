// Alpha cut-outs (leaf cards, fences): a hit on a texel whose alpha is below
// the material's cutoff is no hit, for closest-hit and occlusion queries
// alike, so shadows see the same holes as camera rays. Every backend asks
// this one test, so they cut the same holes.
#pragma once

#include <cstdint>

#include "scene/scene.h"

namespace ferry {

struct AlphaCutout {
  const Mesh* mesh = nullptr;
  const Texture* texture = nullptr;
  float cutoff = 0.5f;

  // The cut-out of `mesh` drawn with `material`, or none (texture null).
  static AlphaCutout of(const Scene& scene, const Mesh& mesh) {
    const Material& material = scene.materials[mesh.material];
    if (material.alphaTexture == kNoTexture) return {};
    return {&mesh, &scene.textures[material.alphaTexture], material.alphaCutoff};
  }
  bool active() const { return texture != nullptr; }

  // Whether the hit at barycentrics (u, v) of triangle `primitive` falls in a hole.
  bool isHole(uint32_t primitive, float u, float v) const {
    const Vec3i& tri = mesh->indices[primitive];
    Vec2f uv{u, v};
    if (!mesh->uvs.empty())
      uv = mesh->uvs[tri.x] * (1 - u - v) + mesh->uvs[tri.y] * u + mesh->uvs[tri.z] * v;
    return texture->sampleAlpha(uv) < cutoff;
  }
};

}  // namespace ferry
