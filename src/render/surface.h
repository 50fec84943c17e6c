// Everything shading needs about a hit, rebuilt from the re-traced ray (the
// path itself carries no hit data).
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <vector>

#include "core/math.h"
#include "scene/scene.h"
#include "trace/trace_backend.h"

namespace ferry {

struct SurfacePoint {
  Vec3f position;
  Vec3f geometricNormal;  // world space, unit, from the triangle's winding
  Vec3f shadingNormal;    // world space, unit, interpolated (or geometric)
  Vec2f uv;
  const Material* material = nullptr;
  Vec3f baseColor;  // material colour times its texture
  // For a mix (Material::mixedWith) on a mesh with uvs: the shading normal
  // before any bump or normal map, and the triangle's world-space dp/du and
  // dp/dv, so that the material the mix picks bends the normal by its own
  // map (bentNormal); hasDerivatives false otherwise.
  bool hasDerivatives = false;
  // On a fibre (a curve): dpdu holds its tangent, and shading turns its
  // frame about the normal to follow it (hair models read it).
  bool hasTangent = false;
  // How far beyond offsetRayOrigin's few ulps rays leaving here start, along
  // the normal (ShapeSurface::originOffset, world units); 0 on triangles.
  float originOffset = 0;
  Vec3f smoothNormal, dpdu, dpdv;
};

// `inverses` (from instanceInverses, one per instance) saves inverting the
// instance transform for every hit; the result is the same, bit for bit.
// (Inline, as offsetRayOrigin: both run at every path vertex, and inlined
// the compiler interleaves their loads and square roots with the shading
// around them.)
// `direction`: the world-space direction of the ray that hit (a shape that
// faces the ray reads it; zero: none known).
SurfacePoint reconstructSurface(const Scene& scene, const TraceHit& hit,
                                const std::vector<Affine3f>* inverses = nullptr,
                                Vec3f direction = Vec3f(0));
std::vector<Affine3f> instanceInverses(const Scene& scene);

// What reconstructSurface reads for a hit, gathered once per render (the
// renderer's): per instance its inverse transform and where its object's
// meshes start in `meshes`; per (object, mesh slot) the mesh's arrays and
// material. A hit then reaches its triangle's vertices in three dependent
// loads instead of six (instance, object, mesh list, mesh, indices,
// positions). Same result, bit for bit.
struct SurfaceTable {
  struct MeshArrays {
    const Vec3i* indices;
    const Vec3f* positions;
    const Vec3f* normals;  // null: none
    const Vec2f* uvs;      // null: none
    const Material* material;
    const Shape* shape = nullptr;  // set: a geometry of another kind (the arrays are null)
  };
  std::vector<Affine3f> inverses;        // per instance
  std::vector<uint32_t> instanceMeshes;  // per instance: its object's slot 0 in `meshes`
  std::vector<MeshArrays> meshes;
  explicit SurfaceTable(const Scene& scene);
};
SurfacePoint reconstructSurface(const Scene& scene, const SurfaceTable& table, const TraceHit& hit,
                                Vec3f direction = Vec3f(0));

// A material's base colour at a shading point: its colour times its
// texture there (an image at uv, a solid texture at p).
inline Vec3f materialBaseColor(const Scene& scene, const Material& material, Vec2f uv, Vec3f p) {
  if (material.baseColorTexture == kNoTexture) return material.baseColor;
  return material.baseColor *
         scene.textures[size_t(material.baseColorTexture)].evaluate(uv, p).xyz();
}

// Whether `material` bends shading normals (a bump map or a normal map).
inline bool hasNormalPerturbation(const Material& material) {
  return material.bumpTexture != kNoTexture || material.normalTexture != kNoTexture;
}

// Bends `s`'s shading normal by its material's bump map or normal map (in
// the triangle's uv parametrization, or without uvs its barycentric one), and for a mix
// keeps what bentNormal needs for the other materials. Out of line: few
// materials have either.
void perturbShadingNormal(const Scene& scene, const Affine3f& transform,
                          const SurfaceTable::MeshArrays& mesh, const Vec3i& tri, SurfacePoint& s);

// `n` bent by `material`'s bump or normal map at `s` (its uv and position),
// with the triangle's world-space dp/du and dp/dv; `n` itself where the
// material has no map or the bent normal would be unusable or below the
// geometric surface.
Vec3f bentNormal(const Scene& scene, const Material& material, const SurfacePoint& s, Vec3f n,
                 Vec3f dpdu, Vec3f dpdv);

// The surface where `hit` meets a geometry of another kind (scene/shape.h),
// whose material has no bump or normal map (Scene::validate). Out of line:
// triangles are the common case.
SurfacePoint shapeSurfaceAt(const Scene& scene, const Affine3f& transform, const Affine3f& inv,
                            const Shape& shape, const Material& material, const TraceHit& hit,
                            Vec3f direction);

// The hit triangle's corners in world space, each as Affine3f::transformPoint
// places it (what the light sampler keys emitters by: LightSampler::emitterIndex).
std::array<Vec3f, 3> worldCorners(const Scene& scene, const SurfaceTable& table,
                                  const TraceHit& hit);

// Moves a ray origin off a surface by a few ulps along the normal (Wächter and
// Binder, Ray Tracing Gems ch. 6), robust at any distance from the origin.
Vec3f offsetRayOrigin(Vec3f p, Vec3f n);

// ------------------------------------------------------------------ inline definitions

// Affine3f::transformNormal with the inverse given.
inline Vec3f transformNormalByInverse(const Affine3f& inv, Vec3f n) {
  return {inv.l[0][0] * n.x + inv.l[1][0] * n.y + inv.l[2][0] * n.z,
          inv.l[0][1] * n.x + inv.l[1][1] * n.y + inv.l[2][1] * n.z,
          inv.l[0][2] * n.x + inv.l[1][2] * n.y + inv.l[2][2] * n.z};
}

// The one computation behind both reconstructSurface overloads.
inline SurfacePoint surfaceAt(const Scene& scene, const Affine3f& transform, const Affine3f& inv,
                              const SurfaceTable::MeshArrays& mesh, const TraceHit& hit,
                              Vec3f direction) {
  // Every return returns `s`, so it is built in the caller's slot, not copied.
  SurfacePoint s;
  if (mesh.shape) [[unlikely]] {
    s = shapeSurfaceAt(scene, transform, inv, *mesh.shape, *mesh.material, hit, direction);
    return s;
  }
  const Vec3i& tri = mesh.indices[hit.primitive];
  float w = 1 - hit.u - hit.v;
  Vec3f p0 = mesh.positions[tri.x], p1 = mesh.positions[tri.y], p2 = mesh.positions[tri.z];
  // The object-space barycentric point is more precise than origin + t * dir
  // far from the camera.
  s.position = transform.transformPoint(p0 * w + p1 * hit.u + p2 * hit.v);
  // Both normals are set from registers (copying one member to the other read
  // back a value still in the store buffer, which the CPU cannot forward).
  const Vec3f ng = normalize(transformNormalByInverse(inv, cross(p1 - p0, p2 - p0)));
  s.geometricNormal = ng;
  if (mesh.normals) {
    Vec3f n = mesh.normals[tri.x] * w + mesh.normals[tri.y] * hit.u + mesh.normals[tri.z] * hit.v;
    n = transformNormalByInverse(inv, n);
    float len = length(n);
    Vec3f ns = len > 0 && std::isfinite(len) ? n * (1 / len) : ng;
    // Keep the shading normal on the geometric side so it cannot flip the surface.
    s.shadingNormal = dot(ns, ng) < 0 ? -ns : ns;
  } else {
    s.shadingNormal = ng;
  }
  s.uv = !mesh.uvs ? Vec2f{hit.u, hit.v}
                   : mesh.uvs[tri.x] * w + mesh.uvs[tri.y] * hit.u + mesh.uvs[tri.z] * hit.v;
  s.material = mesh.material;
  if (hasNormalPerturbation(*s.material) || s.material->mixedWith >= 0)
    perturbShadingNormal(scene, transform, mesh, tri, s);
  s.baseColor = materialBaseColor(scene, *s.material, s.uv, s.position);
  return s;
}

inline SurfaceTable::MeshArrays meshArrays(const Scene& scene, const Mesh& mesh) {
  return {mesh.indices.data(), mesh.positions.data(),
          mesh.normals.empty() ? nullptr : mesh.normals.data(),
          mesh.uvs.empty() ? nullptr : mesh.uvs.data(), &scene.materials[mesh.material]};
}

inline SurfaceTable::MeshArrays geometryArrays(const Scene& scene, const Geometry& geometry) {
  return {nullptr,
          nullptr,
          nullptr,
          nullptr,
          &scene.materials[geometry.material],
          geometry.shape.get()};
}

inline SurfacePoint reconstructSurface(const Scene& scene, const TraceHit& hit,
                                       const std::vector<Affine3f>* inverses, Vec3f direction) {
  const Instance& inst = scene.instances[hit.instance];
  const Affine3f transform = inst.transformAt(hit.time);
  const Affine3f inv = inverses && !inst.motion ? (*inverses)[hit.instance] : transform.inverse();
  const Object& object = scene.objects[inst.object];
  const size_t slot = size_t(hit.slot);
  const SurfaceTable::MeshArrays arrays =
      slot < object.meshes.size()
          ? meshArrays(scene, scene.meshes[object.meshes[slot]])
          : geometryArrays(scene, scene.geometries[object.geometries[slot - object.meshes.size()]]);
  return surfaceAt(scene, transform, inv, arrays, hit, direction);
}

inline SurfacePoint reconstructSurface(const Scene& scene, const SurfaceTable& table,
                                       const TraceHit& hit, Vec3f direction) {
  const Instance& inst = scene.instances[hit.instance];
  const SurfaceTable::MeshArrays& arrays =
      table.meshes[table.instanceMeshes[hit.instance] + uint32_t(hit.slot)];
  if (!inst.motion)
    return surfaceAt(scene, inst.transform, table.inverses[hit.instance], arrays, hit, direction);
  const Affine3f transform = inst.motion->at(hit.time);  // where it was when the ray met it
  return surfaceAt(scene, transform, transform.inverse(), arrays, hit, direction);
}

inline std::array<Vec3f, 3> worldCorners(const Scene& scene, const SurfaceTable& table,
                                         const TraceHit& hit) {
  const Affine3f& transform = scene.instances[hit.instance].transform;
  const SurfaceTable::MeshArrays& mesh =
      table.meshes[table.instanceMeshes[hit.instance] + uint32_t(hit.slot)];
  const Vec3i& tri = mesh.indices[hit.primitive];
  return {transform.transformPoint(mesh.positions[tri.x]),
          transform.transformPoint(mesh.positions[tri.y]),
          transform.transformPoint(mesh.positions[tri.z])};
}

inline Vec3f offsetRayOrigin(Vec3f p, Vec3f n) {
  constexpr float kOrigin = 1.0f / 32.0f;
  constexpr float kFloatScale = 1.0f / 65536.0f;
  constexpr float kIntScale = 256.0f;
  Vec3f out;
  for (int k = 0; k < 3; ++k) {
    int offset = static_cast<int>(kIntScale * n[k]);
    int bits = std::bit_cast<int>(p[k]);
    float moved = std::bit_cast<float>(bits + (p[k] < 0 ? -offset : offset));
    out[k] = std::abs(p[k]) < kOrigin ? p[k] + kFloatScale * n[k] : moved;
  }
  return out;
}

}  // namespace ferry
