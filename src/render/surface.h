// Everything shading needs about a hit, rebuilt from the re-traced ray (the
// path itself carries no hit data).
#pragma once

#include <vector>

#include "core/math.h"
#include "trace/local_geometry.h"

namespace ferry {

struct Scene;
struct Material;

struct SurfacePoint {
  Vec3f position;
  Vec3f geometricNormal;  // world space, unit, from the triangle's winding
  Vec3f shadingNormal;    // world space, unit, interpolated (or geometric)
  Vec2f uv;
  const Material* material = nullptr;
  Vec3f baseColor;        // material colour times its texture
};

// `inverses` (from instanceInverses, one per instance) saves inverting the
// instance transform for every hit; the result is the same, bit for bit.
SurfacePoint reconstructSurface(const Scene& scene, const TraceHit& hit,
                                const std::vector<Affine3f>* inverses = nullptr);
std::vector<Affine3f> instanceInverses(const Scene& scene);

// Moves a ray origin off a surface by a few ulps along the normal (Wächter and
// Binder, Ray Tracing Gems ch. 6), robust at any distance from the origin.
Vec3f offsetRayOrigin(Vec3f p, Vec3f n);

}  // namespace ferry
