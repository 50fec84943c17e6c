#include "render/path_shading.h"

#include <algorithm>
#include <cmath>

#include "scene/scene.h"

namespace ferry {
namespace {

// Paths whose bounce reaches this start playing Russian roulette.
constexpr uint32_t kRouletteStartBounce = 3;

// The least cosine between the viewer and a shading normal (shadingFrame).
constexpr float kMinShadingCosine = 0.02f;

// Contributions that cannot be represented are dropped rather than poisoning the image.
[[gnu::always_inline]] inline bool usable(Vec3f c) {
  return isFinite(c) && maxComponent(c) > 0;
}

}  // namespace

template <typename Path>
PathShading<Path>::PathShading(const Scene& scene, const LightSampler& lights, uint32_t maxDepth,
                               uint32_t seed, LightStrategy strategy)
    : scene_(scene),
      lights_(lights),
      surfaces_(scene),
      maxDepth_(maxDepth),
      seed_(seed),
      strategy_(strategy) {}

template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::shadePath(
    const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
    FrameBuffer& frameBuffer, Path& continuation, Path& shadowRay) const {
  if (!path.hasHit()) {
    addEscapedLight(path, frameBuffer);
    return {};
  }
  const PathVertex vertex = surfaceVertex(path, hit, bounce);
  addEmission(vertex, hit, frameBuffer);
  if (bounce >= maxDepth_) return {};
  const VertexScattering scattering = shadingFrame(vertex, sampleIndex);
  Spawned spawned;
  spawned.continuation = sampleContinuation(vertex, scattering, continuation);
  // (A delta vertex takes no light sample: its emission on the next vertex
  // counts in full instead.)
  if (!scattering.bsdf.isDelta() && strategy_ != LightStrategy::BsdfSamples)
    spawned.shadowRay = sampleLight(vertex, scattering, shadowRay);
  return spawned;
}

// Escaped: light from infinity counts in full after a delta vertex (no light
// sample covered it); otherwise only an environment map's, MIS-weighted.
template <typename Path>
[[gnu::always_inline]] inline void PathShading<Path>::addEscapedLight(
    const Path& path, FrameBuffer& frameBuffer) const {
  Vec3f l;
  if (path.has(kPathAfterSpecular) || strategy_ == LightStrategy::BsdfSamples) {
    l = path.weight() * lights_.background(normalize(path.dir()));
  } else if (strategy_ == LightStrategy::Mis && lights_.environmentTakesPartInMis()) {
    const Vec3f d = path.dir();
    const float weight = powerHeuristic(path.bsdfPdf(), lights_.environmentPdf(path.origin, d));
    l = path.weight() * lights_.environmentAlong(d) * weight;
  } else {
    return;
  }
  if (usable(l)) frameBuffer.add(path.pixel(), l);
}

template <typename Path>
[[gnu::always_inline]] inline PathVertex PathShading<Path>::surfaceVertex(const Path& path,
                                                                          const TraceHit& hit,
                                                                          uint32_t bounce) const {
  return PathVertex{path.pixel(),
                    bounce,
                    path.weight(),
                    normalize(-path.dir()),
                    path.has(kPathAfterSpecular),
                    path.origin,
                    path.bsdfPdf(),
                    reconstructSurface(scene_, surfaces_, hit)};
}

// Emission counts in full after a delta vertex, and MIS-weighted against the
// light sample the previous vertex took otherwise.
template <typename Path>
[[gnu::always_inline]] inline void PathShading<Path>::addEmission(const PathVertex& vertex,
                                                                  const TraceHit& hit,
                                                                  FrameBuffer& frameBuffer) const {
  const Material& material = *vertex.surface.material;
  const bool full = vertex.afterSpecular || strategy_ == LightStrategy::BsdfSamples;
  if (!material.isEmissive() || (!full && strategy_ != LightStrategy::Mis)) return;
  // A one-sided emitter lights only the side its winding normal faces.
  if (!material.emitsBackSide && !(dot(vertex.surface.geometricNormal, vertex.wo) > 0)) return;
  float weight = 1;
  if (!full) {
    const uint32_t emitter = lights_.emitterIndex(worldCorners(scene_, surfaces_, hit));
    if (emitter != LightSampler::kNotAnEmitter)
      weight = powerHeuristic(vertex.bsdfPdf,
                              lights_.emitterPdf(vertex.from, emitter, vertex.surface.position));
  }
  const Vec3f l = vertex.throughput * material.emission * weight;
  if (usable(l)) frameBuffer.add(vertex.pixel, l);
}

// A mix (Material::mixedWith): one material of the chain, chosen with `u`
// (each link taken with its mixAmount, u stretched back to [0, 1) for the
// next link), its base colour evaluated where the surface is.
template <typename Path>
Bsdf PathShading<Path>::mixedBsdf(const SurfacePoint& surface, float u,
                                  const Material*& chosen) const {
  const Material* material = surface.material;
  for (size_t n = 0; material->mixedWith >= 0 && n < scene_.materials.size(); ++n) {
    const float amount = material->mixAmount;
    if (!(u < amount)) break;  // this one
    u = u / amount;
    material = &scene_.materials[size_t(material->mixedWith)];
  }
  const Vec3f color = material == surface.material
                          ? surface.baseColor
                          : materialBaseColor(scene_, *material, surface.uv, surface.position);
  chosen = material;
  return Bsdf::fromMaterial(*material, color, scene_.bsdfTableOf(*material));
}

template <typename Path>
[[gnu::always_inline]] inline VertexScattering PathShading<Path>::shadingFrame(
    const PathVertex& vertex, uint32_t sampleIndex) const {
  const RandomStream random(RandomKey{vertex.pixel, sampleIndex, vertex.bounce, seed_});
  const SurfacePoint& surface = vertex.surface;
  const Material* chosen = surface.material;
  const Bsdf bsdf =
      chosen->mixedWith < 0
          ? Bsdf::fromMaterial(*chosen, surface.baseColor, scene_.bsdfTableOf(*chosen))
          : mixedBsdf(surface, random(RandomDim::MaterialSelect), chosen);
  Vec3f ng = surface.geometricNormal, ns = surface.shadingNormal;
  // The mix picked another material: the normal is bent by its map (or by
  // none), not by the first material's.
  if (chosen != surface.material && surface.hasDerivatives)
    ns = bentNormal(scene_, *chosen, surface, surface.smoothNormal, surface.dpdu, surface.dpdv);
  if (!bsdf.transmits()) {
    if (dot(ng, vertex.wo) < 0) {
      // Opaque surfaces are two-sided: shade the side the ray arrived on.
      ng = -ng;
      ns = -ns;
    }
    // A shading normal (interpolated, bumped, normal-mapped) that turns
    // away from the viewer would make the surface black there: bend it
    // towards the geometric normal until the viewer sees its front (as Iray
    // does, Keller et al. 2017). Light still cannot leak: continuations and
    // light samples below the geometric surface are dropped.
    const float facing = dot(ns, vertex.wo);
    if (facing < kMinShadingCosine) {
      const float geometric = std::max(dot(ng, vertex.wo), 1e-4f);
      ns = normalize(ns + ng * ((kMinShadingCosine - facing) / geometric));
    }
  }
  const Frame frame(ns);
  return VertexScattering{bsdf, ng, frame, frame.toLocal(vertex.wo), random};
}

// The continuation is written in place (no copy of a half-written path
// through the stack). It and the light sample draw different random
// dimensions, so the order of computing them is free.
template <typename Path>
[[gnu::always_inline]] inline bool PathShading<Path>::sampleContinuation(
    const PathVertex& vertex, const VertexScattering& scattering, Path& continuation) const {
  const RandomStream& random = scattering.random;
  BsdfSample bs;
  const Vec2f u{random(RandomDim::BsdfU), random(RandomDim::BsdfV)};
  if (!scattering.bsdf.sample(scattering.woLocal, random(RandomDim::BsdfLobe), u, bs)) return false;
  const Vec3f wi = scattering.frame.toWorld(bs.wi);
  const Vec3f ng = scattering.ng;
  // The shading normal sent it below the surface.
  if (!scattering.bsdf.transmits() && dot(wi, ng) <= 0) return false;
  Vec3f weight = vertex.throughput * bs.weight;
  if (!survivesRoulette(vertex, scattering, weight) || !usable(weight)) return false;
  const Vec3f origin = offsetRayOrigin(vertex.surface.position, dot(wi, ng) > 0 ? ng : -ng);
  makeRay(continuation, origin, wi, kInfinity, weight, vertex.pixel,
          bs.delta ? uint32_t(kPathAfterSpecular) : 0u, bs.delta ? 0.0f : bs.pdf);
  return true;
}

// Russian roulette from kRouletteStartBounce on: a path survives with
// probability min(1, its largest weight), and its weight is divided by that.
template <typename Path>
[[gnu::always_inline]] inline bool PathShading<Path>::survivesRoulette(
    const PathVertex& vertex, const VertexScattering& scattering, Vec3f& weight) const {
  if (vertex.bounce + 1 < kRouletteStartBounce) return true;
  const float q = std::min(1.0f, maxComponent(weight));
  if (scattering.random(RandomDim::Roulette) >= q) return false;
  weight = weight * (1 / q);
  return true;
}

// Next-event estimation: exactly one light sample, and its shadow ray
// carrying the contribution the light makes if nothing is in the way.
template <typename Path>
[[gnu::always_inline]] inline bool PathShading<Path>::sampleLight(
    const PathVertex& vertex, const VertexScattering& scattering, Path& shadowRay) const {
  const RandomStream& random = scattering.random;
  const Bsdf& bsdf = scattering.bsdf;
  const Vec3f position = vertex.surface.position;
  LightSample ls;
  const Vec2f u{random(RandomDim::LightSampleU), random(RandomDim::LightSampleV)};
  if (!lights_.sample(position, scattering.frame, bsdf.transmits(), random(RandomDim::LightSelect),
                      u, ls))
    return false;
  const Vec3f wiLocal = scattering.frame.toLocal(ls.direction);
  const Vec3f f = bsdf.eval(scattering.woLocal, wiLocal);
  // Weighed against the BSDF sample that could find the same light, with
  // the BSDF density as a continuation would store it.
  const float weight =
      strategy_ == LightStrategy::Mis && ls.mis
          ? powerHeuristic(ls.pdf,
                           unpackDensity(packDensity(bsdf.pdf(scattering.woLocal, wiLocal))))
          : 1.0f;
  const Vec3f contribution = vertex.throughput * f * ls.radiance * (weight / ls.pdf);
  // Only light arriving on the geometric side it is evaluated for.
  const Vec3f ng = scattering.ng;
  const bool sameSide = bsdf.transmits() || dot(ls.direction, ng) > 0;
  if (!sameSide || !usable(contribution)) return false;
  const Vec3f origin = offsetRayOrigin(position, dot(ls.direction, ng) > 0 ? ng : -ng);
  const Vec3f stored =
      makeRay(shadowRay, origin, ls.direction, kInfinity, contribution, vertex.pixel, kPathShadow);
  if (std::isfinite(ls.distance)) shadowRay.tmax = shadowRayTmax(position, origin, stored, ls);
  return true;
}

template class PathShading<Path8>;
template class PathShading<Path64>;
template class PathShading<PathReplay>;

}  // namespace ferry
