#include "render/surface.h"

#include "scene/scene.h"

namespace ferry {

void perturbShadingNormal(const Scene& scene, const Affine3f& transform,
                          const SurfaceTable::MeshArrays& mesh, const Vec3i& tri, SurfacePoint& s) {
  // The triangle's dp/du and dp/dv (pbrt's, from its three uvs; without uvs
  // the barycentric ones SurfacePoint::uv then holds), in world space; a
  // triangle whose uvs are degenerate keeps its normal.
  const Vec2f uv0 = mesh.uvs ? mesh.uvs[tri.x] : Vec2f{0, 0};
  const Vec2f uv1 = mesh.uvs ? mesh.uvs[tri.y] : Vec2f{1, 0};
  const Vec2f uv2 = mesh.uvs ? mesh.uvs[tri.z] : Vec2f{0, 1};
  const Vec2f d02 = uv0 - uv2, d12 = uv1 - uv2;
  const Vec3f p02 = mesh.positions[tri.x] - mesh.positions[tri.z],
              p12 = mesh.positions[tri.y] - mesh.positions[tri.z];
  const float det = d02.x * d12.y - d02.y * d12.x;
  if (!(std::abs(det) > 1e-12f)) return;
  const float inv = 1 / det;
  const Vec3f dpdu = transform.transformVector((p02 * d12.y - p12 * d02.y) * inv);
  const Vec3f dpdv = transform.transformVector((p12 * d02.x - p02 * d12.x) * inv);
  if (!isFinite(dpdu) || !isFinite(dpdv)) return;
  if (s.material->mixedWith >= 0) {
    s.hasDerivatives = true;
    s.smoothNormal = s.shadingNormal;
    s.dpdu = dpdu;
    s.dpdv = dpdv;
  }
  s.shadingNormal = bentNormal(scene, *s.material, s, s.shadingNormal, dpdu, dpdv);
}

Vec3f bentNormal(const Scene& scene, const Material& material, const SurfacePoint& s, Vec3f n,
                 Vec3f dpdu, Vec3f dpdv) {
  Vec3f bent = n;
  if (material.bumpTexture != kNoTexture) {
    // pbrt's Bump(): the surface displaced by d(u, v) along the shading
    // normal; its partial derivatives by finite differences over half a
    // texel (the slope of the bilinear lookup; pbrt steps by the ray
    // differentials' footprint, which Ferry's paths do not carry).
    const Texture& bump = scene.textures[material.bumpTexture];
    float ddu = 0, ddv = 0;
    if (bump.isSolid()) {
      // Evaluated at the point (a solid texture, or a combination with
      // one): displaced at (u + du, p + du dp/du) and (v + dv, p + dv dp/dv)
      // (pbrt's step without ray differentials, 0.0005), its raw value (fBm
      // is negative half the time).
      constexpr float kStep = 0.0005f;
      auto displacement = [&](Vec2f uv, Vec3f p) {
        return material.bumpScale * bump.value(uv, p).x;
      };
      const float d = displacement(s.uv, s.position);
      ddu = (displacement(s.uv + Vec2f{kStep, 0}, s.position + dpdu * kStep) - d) / kStep;
      ddv = (displacement(s.uv + Vec2f{0, kStep}, s.position + dpdv * kStep) - d) / kStep;
    } else {
      const float du = bump.width > 0 ? 0.5f / float(bump.width) : 0.0005f;
      const float dv = bump.height > 0 ? 0.5f / float(bump.height) : 0.0005f;
      auto displacement = [&](Vec2f uv) {
        return material.bumpScale * bump.evaluate(uv, s.position).x;
      };
      const float d = displacement(s.uv);
      ddu = (displacement(s.uv + Vec2f{du, 0}) - d) / du;
      ddv = (displacement(s.uv + Vec2f{0, dv}) - d) / dv;
    }
    bent = cross(dpdu + n * ddu, dpdv + n * ddv);
    // The parametrization may be mirrored: keep the side of the normal.
    if (dot(bent, n) < 0) bent = -bent;
  } else if (material.normalTexture != kNoTexture) {
    // A tangent-space normal map (glTF): x along dp/du, y along dp/dv,
    // both made orthogonal to the shading normal, the bitangent's sign
    // following the uvs' handedness.
    const Vec4f texel = scene.textures[material.normalTexture].sample(s.uv);
    const Vec3f m{(2 * texel.x - 1) * material.normalScale,
                  (2 * texel.y - 1) * material.normalScale, 2 * texel.z - 1};
    const Vec3f t = dpdu - n * dot(n, dpdu);
    if (!(length(t) > 0)) return n;
    const Vec3f tangent = normalize(t);
    Vec3f bitangent = cross(n, tangent);
    if (dot(bitangent, dpdv) < 0) bitangent = -bitangent;
    bent = tangent * m.x + bitangent * m.y + n * m.z;
  } else {
    return n;
  }
  const float len = length(bent);
  if (!(len > 0) || !std::isfinite(len)) return n;
  bent = bent * (1 / len);
  // On the geometric normal's side, as every shading normal (the shading
  // frame then keeps the viewer in front of it: path_shading.cpp).
  if (dot(bent, s.geometricNormal) < 0) return n;
  return bent;
}

SurfacePoint shapeSurfaceAt(const Scene& scene, const Affine3f& transform, const Affine3f& inv,
                            const Shape& shape, const Material& material, const TraceHit& hit,
                            Vec3f direction) {
  const ShapeSurface local =
      shape.surface(hit.primitive, {hit.u, hit.v}, inv.transformVector(direction));
  SurfacePoint s;
  s.position = transform.transformPoint(local.position);
  const Vec3f ng = normalize(transformNormalByInverse(inv, local.geometricNormal));
  const Vec3f n = transformNormalByInverse(inv, local.shadingNormal);
  const float len = length(n);
  const Vec3f ns = len > 0 && std::isfinite(len) ? n * (1 / len) : ng;
  s.geometricNormal = ng;
  s.shadingNormal = dot(ns, ng) < 0 ? -ns : ns;
  s.uv = local.uv;
  s.material = &material;
  s.baseColor = materialBaseColor(scene, material, s.uv, s.position);
  if (local.tangent.x != 0 || local.tangent.y != 0 || local.tangent.z != 0) {
    s.hasTangent = true;
    s.dpdu = transform.transformVector(local.tangent);
  }
  if (local.originOffset > 0)
    s.originOffset = local.originOffset * length(transform.transformVector(local.geometricNormal));
  return s;
}

std::vector<Affine3f> instanceInverses(const Scene& scene) {
  std::vector<Affine3f> out;
  out.reserve(scene.instances.size());
  for (const Instance& inst : scene.instances) out.push_back(inst.transform.inverse());
  return out;
}

SurfaceTable::SurfaceTable(const Scene& scene) : inverses(instanceInverses(scene)) {
  std::vector<uint32_t> objectMeshes(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    objectMeshes[o] = uint32_t(meshes.size());
    for (int32_t m : scene.objects[o].meshes) meshes.push_back(meshArrays(scene, scene.meshes[m]));
    for (int32_t g : scene.objects[o].geometries)
      meshes.push_back(geometryArrays(scene, scene.geometries[g]));
  }
  instanceMeshes.reserve(scene.instances.size());
  for (const Instance& inst : scene.instances) instanceMeshes.push_back(objectMeshes[inst.object]);
}

}  // namespace ferry
