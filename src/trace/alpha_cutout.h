// Alpha cut-outs (leaf cards, fences): a hit where the material's alpha test
// finds a hole is no hit, for the rays the material names (paths, shadow
// rays or both; scene/scene.h's AlphaTest and AlphaRays). Alpha is the
// texel's alpha over uv, or, for a solid texture (pbrt's fbm, wrinkled,
// windy, or a combination using one), the mean of its value at the hit's
// world point. Stochastic tests decide by a hash of the world ray and the
// triangle's corners, so every backend, rank and partition decides alike. Every backend asks this
// one test, so they cut the same holes.
#pragma once

#include <bit>
#include <cstdint>

#include "core/random.h"
#include "scene/scene.h"
#include "trace/alpha_cutout_coverage.h"

namespace ferry {

// The hash of a ray that stochastic cut-outs decide by: a function of its
// world origin and direction alone.
inline uint32_t alphaRayHash(Vec3f o, Vec3f d) {
  uint32_t h = hashMix(std::bit_cast<uint32_t>(o.x));
  for (float f : {o.y, o.z, d.x, d.y, d.z}) h = hashCombine(h, std::bit_cast<uint32_t>(f));
  return h;
}

struct AlphaCutout {
  const Mesh* mesh = nullptr;
  const Texture* texture = nullptr;
  float cutoff = 0.5f;
  AlphaTest test = AlphaTest::Below;
  AlphaRays rays = AlphaRays::All;
  // The texture's coverage for this test (alpha_cutout_coverage.h): most tests skip
  // the texels. Optional (null: every test reads them); same answers.
  const AlphaCoverage* coverage = nullptr;

  // The cut-out of `mesh` drawn with `material`, or none (texture null).
  static AlphaCutout of(const Scene& scene, const Mesh& mesh) {
    const Material& material = scene.materials[mesh.material];
    if (material.alphaTexture == kNoTexture) return {};
    return {&mesh, &scene.textures[material.alphaTexture], material.alphaCutoff, material.alphaTest,
            material.alphaRays};
  }
  bool active() const { return texture != nullptr; }
  bool cutsPaths() const { return active() && rays != AlphaRays::ShadowRaysOnly; }
  bool cutsShadowRays() const { return active() && rays != AlphaRays::NotShadowRays; }

  // Whether the hit at barycentrics (u, v) of triangle `primitive`, of the
  // mesh placed by `toWorld` (null: the identity), falls in a hole for the
  // ray whose alphaRayHash is `rayHash`.
  bool isHole(uint32_t primitive, float u, float v, const Affine3f* toWorld,
              uint32_t rayHash) const {
    const Vec3i& tri = mesh->indices[primitive];
    Vec2f uv{u, v};
    if (!mesh->uvs.empty())
      uv = mesh->uvs[tri.x] * (1 - u - v) + mesh->uvs[tri.y] * u + mesh->uvs[tri.z] * v;
    float alpha = 1;  // a texture without texels
    if (!texture->isSolid()) {
      if (texture->hasTexels()) {
        const Texture::Taps taps = texture->taps(uv);
        if (coverage) {
          switch (coverage->at(taps.x0, taps.y0)) {
            case AlphaCoverage::Cell::Hole:
              return true;
            case AlphaCoverage::Cell::Solid:
              return false;
            case AlphaCoverage::Cell::Mixed:
              break;
          }
        }
        alpha = texture->alphaAt(taps);
      }
    } else {
      Vec3f p = mesh->positions[tri.x] * (1 - u - v) + mesh->positions[tri.y] * u +
                mesh->positions[tri.z] * v;
      if (toWorld) p = toWorld->transformPoint(p);
      const Vec3f value = texture->value(uv, p);
      alpha = (value.x + value.y + value.z) / 3;
    }
    switch (test) {
      case AlphaTest::Below:
        return alpha < cutoff;
      case AlphaTest::Zero:
        return alpha == 0;
      case AlphaTest::Stochastic: {
        if (alpha >= 1) return false;
        // One number per ray and triangle, so surfaces along a ray decide
        // independently. The triangle is named by its corners in any order:
        // partitioning renumbers triangles and vertices, not positions.
        uint32_t corners = 0;
        for (int k = 0; k < 3; ++k) {
          const Vec3f& c = mesh->positions[tri[k]];
          corners += hashCombine(
              hashCombine(hashMix(std::bit_cast<uint32_t>(c.x)), std::bit_cast<uint32_t>(c.y)),
              std::bit_cast<uint32_t>(c.z));
        }
        return random01FromBits(hashCombine(rayHash, corners)) >= alpha;
      }
    }
    return false;
  }
};

}  // namespace ferry
