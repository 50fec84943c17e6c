#include "render/path_shading.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "material/models/diffuse.h"
#include "material/models/subsurface.h"
#include "media/phase.h"
#include "scene/scene.h"

namespace ferry {
namespace {

// Paths whose bounce reaches this start playing Russian roulette: the
// continuation from a path's second vertex on (pbrt-v4's rule).
constexpr uint32_t kRouletteStartBounce = 2;

// A scene with subsurface walks keeps a path's medium in 8 bits (mediumOf).
constexpr size_t kMaxWalkSceneMedia = 254;

// The least cosine between the viewer and a shading normal (shadingFrame).
constexpr float kMinShadingCosine = 0.02f;

// Contributions that cannot be represented are dropped rather than poisoning the image.
[[gnu::always_inline]] inline bool usable(Vec3f c) {
  return isFinite(c) && maxComponent(c) > 0;
}

// A light path's random keys: its bounces offset by this (camera paths use
// the bounce itself), its emission at the offset alone.
constexpr uint32_t kLightPathKey = 0x40000000u;

inline float square(float x) {
  return x * x;
}
// A density as a path stores it (both sides of an MIS weight read the same).
inline float stored(float pdf) {
  return unpackDensity(packDensity(pdf));
}
// A light path's emission direction density over the emitted cosine: 1 / pi,
// or 1 / (2 pi) for a two-sided emitter.
inline float emissionDensityOverCosine(bool bothSides) {
  return bothSides ? 0.5f / kPi : 1 / kPi;
}

}  // namespace

template <typename Path>
PathShading<Path>::PathShading(const Scene& scene, const LightSampler& lights, uint32_t maxDepth,
                               uint32_t seed, LightStrategy strategy, const Camera* lightPathCamera,
                               const FilmWindow* window, TransmittanceEstimator transmittance,
                               MisHeuristic heuristic, SamplerKind sampler,
                               SubsurfaceMethod subsurface)
    : scene_(scene),
      lights_(lights),
      surfaces_(scene),
      maxDepth_(maxDepth),
      seed_(seed),
      sampler_(sampler),
      strategy_(strategy),
      heuristic_(heuristic),
      transmittance_(transmittance) {
  if (Path::kProbes && subsurface == SubsurfaceMethod::Probes) {
    probes_ = true;
    probeModels_.resize(scene.materials.size());
    for (size_t i = 0; i < scene.materials.size(); ++i) {
      const auto* model = dynamic_cast<const SubsurfaceModel*>(scene.materials[i].model.get());
      if (model && model->hasMedium) probeModels_[i] = model;
    }
    lightPathCamera = nullptr;
  }
  if (scene.hasMedia()) {
    media_ = std::make_shared<MediaAlongRays>(scene);
    cameraMedium_ = scene.cameraMedium;
    lightPathCamera = nullptr;
    for (const Medium& m : scene.media) walks_ = walks_ || m.subsurface;
  }
  depthOnPath_ = walks_ || probes_;
  if (depthOnPath_) {
    if (scene.media.size() > kMaxWalkSceneMedia)
      throw InputError(
          fmt::format("a scene with subsurface materials may hold at most {} media; "
                      "this one has {}",
                      kMaxWalkSceneMedia, scene.media.size()));
  }
  if (window && !window->whole()) {
    window_ = *window;
    cropped_ = true;
  }
  if (lightPathCamera && strategy == LightStrategy::Mis && lights.emissiveTriangleCount() > 0 &&
      lights.totalEmittedPower() > 0) {
    camera_ = lightPathCamera;
    lightPathScale_ = lights.totalEmittedPower();
  }
}

template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::shadePath(
    const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
    FrameBuffer& frameBuffer, Path& continuation, Path& shadowRay) const {
  if (path.has(kPathLight))
    return shadeLightPath(path, hit, sampleIndex, bounce, continuation, shadowRay);
  if constexpr (Path::kProbes)
    if (path.probing()) return shadeProbe(path, hit, sampleIndex, bounce, continuation, shadowRay);
  if (media_ || probes_)
    return shadeInMedia(path, hit, sampleIndex, bounce, frameBuffer, continuation, shadowRay);
  if (!path.hasHit()) {
    addEscapedLight(path, frameBuffer);
    return {};
  }
  if (const Shape* volume = volumeOf(hit))
    return shadeVolumeCollision(path, hit, *volume, kNoMedium, sampleIndex, bounce, bounce,
                                continuation, shadowRay);
  const PathVertex vertex = surfaceVertex(path, hit, bounce);
  addEmission(vertex, hit, frameBuffer);
  const bool aovs = bounce == 0 && frameBuffer.hasAovs();
  if (bounce >= maxDepth_) {
    if (aovs) addFirstSurfaceAovs(vertex, shadingFrame(vertex, sampleIndex, bounce), frameBuffer);
    return {};
  }
  const VertexScattering scattering = shadingFrame(vertex, sampleIndex, bounce);
  if (aovs) addFirstSurfaceAovs(vertex, scattering, frameBuffer);
  const float lightBase = camera_ ? cameraLightBase(vertex, scattering) : 0.0f;
  Spawned spawned;
  spawned.continuation = sampleContinuation(vertex, scattering, lightBase, continuation);
  // (A delta vertex takes no light sample: its emission on the next vertex
  // counts in full instead.)
  if (!scattering.bsdf.isDelta() && strategy_ != LightStrategy::BsdfSamples)
    spawned.shadowRay = sampleLight(vertex, scattering, lightBase, shadowRay);
  return spawned;
}

// The camera path's light-path ratio at vertex i, all but its reverse
// density rev_i: at the first hit the inverse of the camera's density of it
// over the whole image (area measure; 0 at a delta vertex, which a light
// path cannot connect to the camera), after that the ratio the path brought
// over this vertex's cosine.
template <typename Path>
[[gnu::always_inline]] inline float PathShading<Path>::cameraLightBase(
    const PathVertex& vertex, const VertexScattering& scattering) const {
  const float cosIn = std::abs(dot(vertex.surface.geometricNormal, vertex.wo));
  if (!(cosIn > 0)) return 0;
  if (vertex.bounce > 0) return unpackDensity(vertex.lightRatio) / cosIn;
  if (scattering.bsdf.isDelta()) return 0;
  const Vec3f toPoint = vertex.surface.position - vertex.from;
  const float dist2 = dot(toPoint, toPoint);
  const float cosAxis = camera_->cosToAxis(toPoint * (1 / std::sqrt(dist2)));
  if (!(cosAxis > 0)) return 0;
  return camera_->planeArea() * cosAxis * cosAxis * cosAxis * dist2 / cosIn;
}

template <typename Path>
bool PathShading<Path>::emission(uint32_t index, uint32_t sampleIndex, EmissionSample& out) const {
  const RandomStream random(RandomKey{randomPixel(index), sampleIndex, kLightPathKey, seed_},
                            sampler_);
  return lights_.sampleEmission(random(RandomDim::LightSelect),
                                {random(RandomDim::LightSampleU), random(RandomDim::LightSampleV)},
                                {random(RandomDim::BsdfU), random(RandomDim::BsdfV)}, out);
}

template <typename Path>
bool PathShading<Path>::makeLightPath(uint32_t index, uint32_t sampleIndex, Path& out) const {
  if (!camera_) return false;
  EmissionSample e;
  if (!emission(index, sampleIndex, e)) return false;
  const float cosine = dot(e.direction, e.normal);
  if (!(cosine > 0)) return false;
  // Throughput Le cos / (p_position p_direction), stored over the total power.
  const float q = cosine / (e.pdfPosition * e.pdfDirection);
  const Vec3f weight = e.radiance * (q / lightPathScale_);
  if (!usable(weight) || !std::isfinite(q)) return false;
  // The other strategies' density over the light path's, so far: 1 / p_position
  // and cos / p_direction (the rest comes at the next vertices), to the heuristic's beta.
  makeRay(out, offsetRayOrigin(e.position, e.normal), e.direction, kInfinity, weight, index,
          kPathLight, 0, misPow(q));
  return true;
}

// A light path at vertex y_j: connect to the camera (the t = 1 strategy,
// pbrt-v3's ConnectBDPT), then scatter on, with the adjoint's shading-normal
// correction (Veach 1997, 5.3; pbrt's CorrectShadingNormal). The path's wo
// points back to the light.
template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::shadeLightPath(
    const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
    Path& continuation, Path& shadowRay) const {
  // A light path connects at scattering vertices 1..maxDepth (a camera path
  // of as many scattering events), and scatters on while the next can.
  if (!path.hasHit() || !camera_ || bounce >= maxDepth_) return {};
  const PathVertex vertex = surfaceVertex(path, hit, bounce);
  const VertexScattering scattering = shadingFrame(vertex, sampleIndex, kLightPathKey + 1 + bounce);
  const Bsdf& bsdf = scattering.bsdf;
  const Vec3f ng = scattering.ng;
  const Vec3f position = vertex.surface.position;
  const float cosIn = std::abs(dot(vertex.surface.geometricNormal, vertex.wo));
  if (!(cosIn > 0)) return {};
  const float ratio = unpackDensity(path.lightRatio);
  // At the first vertex the light sample could have found the emitter too:
  // its density from here, for the factor (1 + (p_light / p_bsdf)^beta).
  float lightSamplePdf = 0;
  if (bounce == 0 && !bsdf.isDelta()) {
    EmissionSample e;
    if (emission(vertex.pixel, sampleIndex, e))
      lightSamplePdf = lights_.emitterPdf(position, e.emitter, e.position);
  }
  auto withLightSample = [&](float bsdfPdf) {
    return lightSamplePdf > 0 && bsdfPdf > 0 ? 1 + misPow(lightSamplePdf / bsdfPdf) : 1.0f;
  };
  Spawned spawned;

  // The connection to the camera.
  if (!bsdf.isDelta()) {
    // A point on the lens (the eye for a pinhole): the lens density and the
    // camera's importance per lens area cancel, as in pbrt's Sample_Wi.
    const Vec3f lens = camera_->hasLens()
                           ? camera_->lensPoint({scattering.random(RandomDim::LensU),
                                                 scattering.random(RandomDim::LensV)})
                           : camera_->origin();
    const Vec3f toCamera = lens - position;
    const bool front = dot(toCamera, ng) > 0;
    const Vec3f origin = scattering.originTowards(position, toCamera);
    uint32_t pixel;
    if ((bsdf.transmits() || front) && camera_->pixelOf(origin, lens, pixel)) {
      const float dist2 = dot(toCamera, toCamera);
      const Vec3f wc = toCamera * (1 / std::sqrt(dist2));
      const float cosAxis = camera_->cosToAxis(-wc);
      const Vec3f wcLocal = scattering.frame.toLocal(wc);
      const float cosCamera = std::abs(dot(vertex.surface.geometricNormal, wc));
      if (cosAxis > 0 && cosCamera > 0) {
        const float area = camera_->planeArea();
        // f(camera, light) |cos_s light| |cos_g camera| / |cos_g light|, times
        // the importance 1 / (area cos^4) and cos_axis / d^2.
        const float importance = 1 / (area * square(square(cosAxis)));
        float forwardPdf;
        const Vec3f f = bsdf.evalPdf(wcLocal, scattering.woLocal, &forwardPdf);
        // The camera path's density of this vertex (the image, in area
        // measure) and of the next one towards the light, over the light
        // path's; to the heuristic's beta and summed with the light sample's.
        const float cameraPdf = cosCamera / (area * cosAxis * cosAxis * cosAxis * dist2);
        const float forward = stored(forwardPdf);
        const float others =
            ratio * misPow(forward / cosIn) * misPow(cameraPdf) * withLightSample(forward);
        const float weight = 1 / (1 + others);
        const Vec3f contribution =
            vertex.throughput * f *
            (lightPathScale_ * cosCamera / cosIn * importance * cosAxis / dist2 * weight);
        if (usable(contribution) && std::isfinite(others)) {
          makeRay(shadowRay, origin, wc, kInfinity, contribution, vertex.pixel,
                  kPathShadow | kPathLight);
          shadowRay.tmax =
              length(lens - origin) / length(shadowRay.dir()) * kCameraConnectionShortening;
          spawned.shadowRay = true;
        }
      }
    }
  }

  // The continuation, while a longer path can still connect.
  if (bounce + 1 >= maxDepth_) return spawned;
  const RandomStream& random = scattering.random;
  BsdfSample bs;
  const Vec2f u{random(RandomDim::BsdfU), random(RandomDim::BsdfV)};
  if (!bsdf.sample(scattering.woLocal, random(RandomDim::BsdfLobe), u, bs)) return spawned;
  const Vec3f wi = scattering.frame.toWorld(bs.wi);
  if (!bsdf.transmits() && dot(wi, ng) <= 0) return spawned;
  const float cosOut = std::abs(dot(vertex.surface.geometricNormal, wi));
  const float shadingOut = std::abs(bs.wi.z), shadingIn = std::abs(scattering.woLocal.z);
  if (!(cosOut > 0) || !(shadingOut > 0)) return spawned;
  // The adjoint: the light arriving along wo leaves along wi as a camera
  // path would see it, f(wi, wo) (not the f(wo, wi) sample() weighs with:
  // a rough dielectric's is not symmetric). Delta lobes are (Ferry's
  // dielectrics drop 1 / eta^2).
  float forwardPdf = 1;
  const Vec3f adjoint = bs.delta ? bs.weight
                                 : bsdf.evalPdf(bs.wi, scattering.woLocal, &forwardPdf) *
                                       (shadingOut / (shadingIn * bs.pdf));
  Vec3f weight = vertex.throughput * adjoint * (shadingIn * cosOut / (cosIn * shadingOut));
  if (!survivesRoulette(vertex, scattering, weight) || !usable(weight)) return spawned;
  // The camera path's density at this vertex towards the light, over the
  // light path's cosine here; then this direction's cosine over the light
  // path's density of it (delta lobes: density 1 both ways).
  const float forward = bs.delta ? 1.0f : stored(forwardPdf);
  const float reverse = bs.delta ? 1.0f : stored(bs.pdf);
  float next = ratio * misPow(forward / cosIn) * misPow(cosOut / reverse);
  if (!bs.delta) next *= withLightSample(forward);
  if (!std::isfinite(next)) return spawned;
  const Vec3f origin = scattering.originTowards(position, wi);
  makeRay(continuation, origin, wi, kInfinity, weight, vertex.pixel, kPathLight, 0, next);
  spawned.continuation = true;
  return spawned;
}

// Escaped: light from infinity counts in full after a delta vertex (no light
// sample covered it); otherwise only an environment map's, MIS-weighted, or
// a constant one's after a vertex that sampled it over the sphere.
template <typename Path>
[[gnu::always_inline]] inline void PathShading<Path>::addEscapedLight(
    const Path& path, FrameBuffer& frameBuffer) const {
  Vec3f l;
  if (path.has(kPathAfterSpecular) || strategy_ == LightStrategy::BsdfSamples) {
    l = path.weight() * lights_.background(path.dir());
  } else if (strategy_ == LightStrategy::Mis &&
             (lights_.environmentTakesPartInMis() || path.skyByMis())) {
    const Vec3f d = path.dir();
    const float lightPdf = lights_.environmentTakesPartInMis()
                               ? lights_.environmentPdf(path.origin, d)
                               : lights_.constantEnvironmentPdf(path.origin);
    l = path.weight() * lights_.environmentAlong(d) * misWeight(path.bsdfPdf(), lightPdf);
  } else {
    return;
  }
  if (usable(l)) frameBuffer.add(path.pixel(), l);
}

template <typename Path>
[[gnu::always_inline]] inline PathVertex PathShading<Path>::surfaceVertex(const Path& path,
                                                                          const TraceHit& hit,
                                                                          uint32_t bounce) const {
  const Vec3f direction = path.dir();  // decoded once: unit
  return PathVertex{path.pixel(),
                    bounce,
                    path.weight(),
                    -direction,
                    path.has(kPathAfterSpecular),
                    path.origin,
                    path.bsdfPdf(),
                    path.lightRatio,
                    reconstructSurface(scene_, surfaces_, hit, direction)};
}

// The AOVs of a camera path's first surface (render/aov.h). The albedo is
// the weight of one BSDF sample drawn with the vertex's own numbers (f cos /
// pdf: an unbiased estimate of the directional albedo, exact for diffuse and
// smooth surfaces), clamped to [0, 1]; a sample that fails gives 0. Out of
// line: only renders with AOVs come here.
template <typename Path>
[[gnu::noinline]] void PathShading<Path>::addFirstSurfaceAovs(const PathVertex& vertex,
                                                              const VertexScattering& scattering,
                                                              FrameBuffer& frameBuffer) const {
  SurfaceAovs aovs;
  const RandomStream& random = scattering.random;
  BsdfSample bs;
  const Vec2f u{random(RandomDim::BsdfU), random(RandomDim::BsdfV)};
  if (scattering.bsdf.sample(scattering.woLocal, random(RandomDim::BsdfLobe), u, bs) &&
      isFinite(bs.weight))
    aovs.albedo = Vec3f(std::clamp(bs.weight.x, 0.0f, 1.0f), std::clamp(bs.weight.y, 0.0f, 1.0f),
                        std::clamp(bs.weight.z, 0.0f, 1.0f));
  aovs.shadingNormal = scattering.frame.n;
  aovs.geometricNormal = scattering.ng;
  aovs.depth = length(vertex.surface.position - vertex.from);
  aovs.position = vertex.surface.position;
  aovs.uv = vertex.surface.uv;
  frameBuffer.addAovs(vertex.pixel, aovs);
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
  // With light paths, every emitter hit after the camera ray is weighed
  // against the light sample (unless after a delta vertex) and the light
  // path that could have made the same path (its first vertex here).
  const bool againstLightPaths = camera_ && vertex.bounce > 0;
  float weight = 1;
  if (!full || againstLightPaths) {
    const uint32_t emitter = lights_.emitterIndex(worldCorners(scene_, surfaces_, hit));
    if (emitter != LightSampler::kNotAnEmitter) {
      const float lightSamplePdf =
          vertex.afterSpecular ? 0.0f
                               : lights_.emitterPdf(vertex.from, emitter, vertex.surface.position);
      if (againstLightPaths) {
        const float lightPath = unpackDensity(vertex.lightRatio) *
                                lights_.emissionPositionPdf(emitter) *
                                emissionDensityOverCosine(lights_.emitsBothSides(emitter));
        const float lightSample = vertex.afterSpecular ? 0.0f : lightSamplePdf / vertex.bsdfPdf;
        weight = 1 / (1 + misPow(lightSample) + misPow(lightPath));
        if (!std::isfinite(weight)) weight = 0;
      } else {
        weight = misWeight(vertex.bsdfPdf, lightSamplePdf);
      }
    }
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
  return material->model->bsdfAt(color, surface.uv, scene_.materialResources());
}

template <typename Path>
[[gnu::always_inline]] inline VertexScattering PathShading<Path>::shadingFrame(
    const PathVertex& vertex, uint32_t sampleIndex, uint32_t keyBounce) const {
  const RandomStream random(RandomKey{randomPixel(vertex.pixel), sampleIndex, keyBounce, seed_},
                            sampler_);
  const SurfacePoint& surface = vertex.surface;
  const Material* chosen = surface.material;
  const SubsurfaceModel* probed = probes_ ? probeModel(surface) : nullptr;
  const Bsdf bsdf =
      probed ? probed->probedBsdf(surface.baseColor)
      : chosen->mixedWith < 0
          ? chosen->model->bsdfAt(surface.baseColor, surface.uv, scene_.materialResources())
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
  const Frame frame = surface.hasTangent ? Frame(ns, surface.dpdu) : Frame(ns);
  return VertexScattering{bsdf,
                          ng,
                          frame,
                          frame.toLocal(vertex.wo),
                          random,
                          offsetRayOrigin(surface.position + ng * surface.originOffset, ng),
                          surface.originOffset};
}

// The continuation is written in place (no copy of a half-written path
// through the stack). It and the light sample draw different random
// dimensions, so the order of computing them is free.
template <typename Path>
[[gnu::always_inline]] inline bool PathShading<Path>::sampleContinuation(
    const PathVertex& vertex, const VertexScattering& scattering, float lightBase,
    Path& continuation) const {
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
  const Vec3f origin = scattering.originTowards(vertex.surface.position, wi);
  // With light paths: the ratio times this vertex's reverse density (none at
  // the first: the camera is not sampled), its cosine towards the next
  // vertex, over the density stored for it (delta lobes: 1 both ways).
  float lightRatio = 0;
  if (lightBase > 0) {
    const float reverse = vertex.bounce == 0 || bs.delta
                              ? 1.0f
                              : stored(scattering.bsdf.pdf(bs.wi, scattering.woLocal));
    lightRatio = lightBase * reverse * std::abs(dot(vertex.surface.geometricNormal, wi)) /
                 (bs.delta ? 1.0f : stored(bs.pdf));
    if (!std::isfinite(lightRatio)) lightRatio = 0;
  }
  makeRay(continuation, origin, wi, kInfinity, weight, vertex.pixel,
          bs.delta ? uint32_t(kPathAfterSpecular) : 0u, bs.delta ? 0.0f : bs.pdf, lightRatio);
  if (!bs.delta && skyOverSphere(scattering.bsdf))
    continuation.setSkyByMis();  // its light sample drew a constant sky over the sphere
  return true;
}

template <typename Path>
[[gnu::always_inline]] inline bool PathShading<Path>::skyOverSphere(const Bsdf& bsdf) const {
  return bsdf.transmits() ||
         (strategy_ == LightStrategy::Mis && !bsdf.isDelta() && !bsdf.as<DiffuseLobe>());
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
    const PathVertex& vertex, const VertexScattering& scattering, float lightBase,
    Path& shadowRay) const {
  const RandomStream& random = scattering.random;
  const Bsdf& bsdf = scattering.bsdf;
  const Vec3f position = vertex.surface.position;
  LightSample ls;
  const Vec2f u{random(RandomDim::LightSampleU), random(RandomDim::LightSampleV)};
  const bool overSphere = skyOverSphere(bsdf);
  if (!lights_.sample(position, scattering.frame, overSphere, random(RandomDim::LightSelect), u, ls,
                      overSphere ? Vec3f(0) : scattering.ng))
    return false;
  const Vec3f wiLocal = scattering.frame.toLocal(ls.direction);
  // Weighed against the BSDF sample that could find the same light, with
  // the BSDF density as a continuation would store it.
  const bool weighed = strategy_ == LightStrategy::Mis && ls.mis;
  float pdf = 0;
  const Vec3f f = bsdf.evalPdf(scattering.woLocal, wiLocal, weighed ? &pdf : nullptr);
  const float bsdfPdf = weighed ? stored(pdf) : 0.0f;
  float weight = weighed ? misWeight(ls.pdf, bsdfPdf) : 1.0f;
  if (lightBase > 0 && ls.emitter != LightSampler::kNotAnEmitter) {
    // And against the light path that could have made it: the camera
    // path's ratio with this vertex's reverse density towards the light,
    // the emitter's densities, over the light sample's.
    const float reverse = vertex.bounce == 0 ? 1.0f : stored(bsdf.pdf(wiLocal, scattering.woLocal));
    const float lightPath = lightBase * reverse *
                            std::abs(dot(vertex.surface.geometricNormal, ls.direction)) *
                            lights_.emissionPositionPdf(ls.emitter) *
                            emissionDensityOverCosine(lights_.emitsBothSides(ls.emitter)) / ls.pdf;
    weight = 1 / (1 + misPow(bsdfPdf / ls.pdf) + misPow(lightPath));
    if (!std::isfinite(weight)) weight = 0;
  }
  const Vec3f contribution = vertex.throughput * f * ls.radiance * (weight / ls.pdf);
  // Only light arriving on the geometric side it is evaluated for.
  const Vec3f ng = scattering.ng;
  const bool sameSide = bsdf.transmits() || dot(ls.direction, ng) > 0;
  if (!sameSide || !usable(contribution)) return false;
  const Vec3f origin = scattering.originTowards(position, ls.direction);
  const Vec3f stored =
      makeRay(shadowRay, origin, ls.direction, kInfinity, contribution, vertex.pixel, kPathShadow);
  if (std::isfinite(ls.distance)) shadowRay.tmax = shadowRayTmax(position, origin, stored, ls);
  return true;
}

// ------------------------------------------------------------------ media
//
// A path in a scene with media first goes its way through them to its hit
// (or to infinity): it may scatter or be absorbed on the way (delta
// tracking), and the media's emission along it counts. If it arrives, the
// surface shades as without media, its continuation leaves into the medium
// on the side it goes to (the surface's MediumInterface, or the medium it
// arrived in), and its shadow ray carries the transmittance to the light
// (ratio tracking). A vertex in a medium scatters by the phase function,
// with a light sample weighed by MIS against phase sampling, as a surface
// does against its BSDF. pbrt's volpath counts depth the same way: each
// scattering event, in a medium or at a surface, is a bounce.

namespace {
// The random dimensions the media draw from a vertex's key: the flight to
// the vertex, and its shadow ray's transmittance (the surface's own
// decisions use the RandomDim values, all below).
constexpr uint32_t kFlightDimension = 64;
constexpr uint32_t kTransmittanceDimension = 1u << 30;
// A subsurface walk still going after this many wavefront bounces ends.
constexpr uint32_t kWalkBounceLimit = 1024;
}  // namespace

template <typename Path>
MediumCounts PathShading<Path>::takeMediumCounts() const {
  MediumCounts total;
  for (MediumCounts& c : mediumCounts_) {
    total.add(c);
    c = MediumCounts{};
  }
  return total;
}

template <typename Path>
const MediumInterface& PathShading<Path>::surfaceMedia(const TraceHit& hit) const {
  static const MediumInterface none;
  const Object& object = scene_.objects[size_t(scene_.instances[size_t(hit.instance)].object)];
  if (size_t(hit.slot) >= object.meshes.size()) return none;
  return scene_.meshes[size_t(object.meshes[size_t(hit.slot)])].media;
}

template <typename Path>
bool PathShading<Path>::throughMedia(Path& shadowRay, int32_t medium, uint32_t keyHash) const {
  const Vec3f stored = shadowRay.dir();
  const float scale = length(stored);
  const float tEnd = std::isfinite(shadowRay.tmax) ? shadowRay.tmax * scale : kInfinity;
  TrackingRandom random(keyHash, kTransmittanceDimension);
  const Vec3f tr = media_->transmittance(shadowRay.origin, stored * (1 / scale), tEnd, medium,
                                         transmittance_, random, mediumCounts_.local());
  if (!(maxComponent(tr) > 0)) return false;
  const Vec3f weight = shadowRay.weight() * tr;
  if (!usable(weight)) return false;
  shadowRay.setWeight(weight);
  return true;
}

template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::shadeInMedia(
    const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
    FrameBuffer& frameBuffer, Path& continuation, Path& shadowRay) const {
  const Vec3f stored = path.dir();
  const float scale = length(stored);
  const Vec3f d = stored * (1 / scale);
  const float tEnd = path.hasHit() ? path.tmax * scale : kInfinity;
  const uint32_t keyHash =
      randomKeyHash(RandomKey{randomPixel(path.pixel()), sampleIndex, bounce, seed_});
  TrackingRandom random(keyHash, kFlightDimension);
  MediaFlight f;
  if (media_)
    f = media_->flight(path.origin, d, tEnd, mediumOf(path), random, mediumCounts_.local());
  else
    f.medium = mediumOf(path);
  const uint32_t depth = depthOf(path, bounce);
  const Vec3f throughput = path.weight();
  if (const Vec3f e = throughput * f.emitted; usable(e)) frameBuffer.add(path.pixel(), e);
  if (f.event == FreeFlight::Event::Absorbed) return {};
  // The path with what the media took from it.
  Path arrived = path;
  arrived.setWeight(throughput * f.weight);
  if (f.event == FreeFlight::Event::Scattered) {
    if (walks_ && media_->medium(f.medium).subsurface)
      return walkVertex(arrived, path.origin + d * f.t, f, sampleIndex, bounce, continuation);
    return shadeMediumVertex(arrived, path.origin + d * f.t, media_->medium(f.medium).g, f.medium,
                             sampleIndex, bounce, depth, continuation, shadowRay);
  }
  if (!path.hasHit()) {
    addEscapedLight(arrived, frameBuffer);
    return {};
  }
  if (const Shape* volume = volumeOf(hit))
    return shadeVolumeCollision(arrived, hit, *volume, f.medium, sampleIndex, bounce, depth,
                                continuation, shadowRay);
  const PathVertex vertex = surfaceVertex(arrived, hit, depth);
  addEmission(vertex, hit, frameBuffer);
  const bool aovs = bounce == 0 && frameBuffer.hasAovs();
  const MediumInterface& sides = surfaceMedia(hit);
  // A walk back at its subsurface material's surface leaves or turns back
  // in within the bounce that entered (pbrt's BSSRDF: one bounce in and out).
  const SubsurfaceModel* probed = probes_ ? probeModel(vertex.surface) : nullptr;
  const bool walkEnds = walks_ && !probed && sides.inside != kNoMedium &&
                        media_->medium(sides.inside).subsurface &&
                        dot(vertex.wo, vertex.surface.geometricNormal) < 0;
  if (!walkEnds && depth >= maxDepth_) {
    if (aovs) addFirstSurfaceAovs(vertex, shadingFrame(vertex, sampleIndex, bounce), frameBuffer);
    return {};
  }
  const VertexScattering scattering = shadingFrame(vertex, sampleIndex, bounce);
  if (aovs) addFirstSurfaceAovs(vertex, scattering, frameBuffer);
  auto leaving = [&](Vec3f direction) {
    return mediumLeaving(sides, vertex.surface.geometricNormal, direction, f.medium);
  };
  Spawned spawned;
  spawned.continuation = sampleContinuation(vertex, scattering, 0, continuation);
  if (spawned.continuation) {
    const Vec3f n = vertex.surface.geometricNormal;
    if (probed && dot(continuation.dir(), n) * dot(vertex.wo, n) < 0) {
      // Through a probed material's surface (either way, as pbrt): the
      // BSSRDF finds where the light leaves.
      spawned.continuation = startProbe(vertex, *probed, sampleIndex, depth, continuation);
      if (spawned.continuation) setMediumAndDepth(continuation, f.medium, depth);
    } else {
      setMediumAndDepth(continuation, leaving(continuation.dir()), walkEnds ? depth : depth + 1);
    }
  }
  if (!scattering.bsdf.isDelta() && strategy_ != LightStrategy::BsdfSamples)
    spawned.shadowRay = sampleLight(vertex, scattering, 0, shadowRay) &&
                        (!media_ || throughMedia(shadowRay, leaving(shadowRay.dir()), keyHash));
  return spawned;
}

template <typename Path>
const Shape* PathShading<Path>::volumeOf(const TraceHit& hit) const {
  const Object& object = scene_.objects[size_t(scene_.instances[size_t(hit.instance)].object)];
  if (size_t(hit.slot) < object.meshes.size()) return nullptr;
  const Shape* shape =
      scene_.geometries[size_t(object.geometries[size_t(hit.slot) - object.meshes.size()])]
          .shape.get();
  return shape->isVolume() ? shape : nullptr;
}

template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::shadeVolumeCollision(
    const Path& path, const TraceHit& hit, const Shape& volume, int32_t medium,
    uint32_t sampleIndex, uint32_t bounce, uint32_t depth, Path& continuation,
    Path& shadowRay) const {
  // Where the trace found the collision, along the ray as it traced it.
  const Vec3f position = path.origin + path.dir() * hit.t;
  Path scattered = path;
  scattered.setWeight(path.weight() * volume.volumeAlbedo(hit.primitive, position));
  return shadeMediumVertex(scattered, position, volume.volumePhaseG(), medium, sampleIndex, bounce,
                           depth, continuation, shadowRay);
}

template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::shadeMediumVertex(
    const Path& path, Vec3f position, float g, int32_t medium, uint32_t sampleIndex,
    uint32_t bounce, uint32_t depth, Path& continuation, Path& shadowRay) const {
  if (depth >= maxDepth_) return {};
  const Vec3f wo = -path.dir();
  const RandomKey key{randomPixel(path.pixel()), sampleIndex, bounce, seed_};
  const RandomStream random(key, sampler_);
  const Vec3f throughput = path.weight();
  Spawned spawned;
  if (strategy_ != LightStrategy::BsdfSamples) {
    LightSample ls;
    const Vec2f u{random(RandomDim::LightSampleU), random(RandomDim::LightSampleV)};
    if (lights_.sample(position, Frame(wo), true, random(RandomDim::LightSelect), u, ls)) {
      const float phase = phaseValue(wo, ls.direction, g);
      const bool weighed = strategy_ == LightStrategy::Mis && ls.mis;
      const float weight = weighed ? misWeight(ls.pdf, stored(phase)) : 1.0f;
      const Vec3f contribution = throughput * ls.radiance * (phase * weight / ls.pdf);
      if (usable(contribution)) {
        const Vec3f storedDir = makeRay(shadowRay, position, ls.direction, kInfinity, contribution,
                                        path.pixel(), kPathShadow);
        if (std::isfinite(ls.distance))
          shadowRay.tmax = shadowRayTmax(position, position, storedDir, ls);
        spawned.shadowRay = !media_ || throughMedia(shadowRay, medium, randomKeyHash(key));
      }
    }
  }
  Vec3f wi;
  const float pdf = samplePhase(wo, g, {random(RandomDim::BsdfU), random(RandomDim::BsdfV)}, wi);
  Vec3f weight = throughput;  // the phase function over its own density
  if (depth + 1 >= kRouletteStartBounce) {
    const float q = std::min(1.0f, maxComponent(weight));
    if (random(RandomDim::Roulette) >= q) return spawned;
    weight = weight * (1 / q);
  }
  if (!usable(weight) || !(pdf > 0)) return spawned;
  makeRay(continuation, position, wi, kInfinity, weight, path.pixel(), 0, pdf);
  if (strategy_ != LightStrategy::BsdfSamples) continuation.setSkyByMis();  // (as a surface's)
  if (media_) setMediumAndDepth(continuation, medium, depth + 1);
  spawned.continuation = true;
  return spawned;
}

// Each step survives with the probability its flight's weight allows (the
// single-scattering albedo for a grey medium), so the throughput a walk
// carries stays near the one it entered with.
template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::walkVertex(const Path& path, Vec3f position,
                                                                  const MediaFlight& flight,
                                                                  uint32_t sampleIndex,
                                                                  uint32_t bounce,
                                                                  Path& continuation) const {
  if (bounce >= kWalkBounceLimit) return {};
  const RandomStream random(RandomKey{randomPixel(path.pixel()), sampleIndex, bounce, seed_},
                            sampler_);
  const float q = std::min(1.0f, maxComponent(flight.weight));
  if (!(random(RandomDim::Roulette) < q)) return {};
  const Vec3f weight = path.weight() * (1 / q);
  Vec3f wi;
  const float pdf = samplePhase(-path.dir(), media_->medium(flight.medium).g,
                                {random(RandomDim::BsdfU), random(RandomDim::BsdfV)}, wi);
  if (!usable(weight) || !(pdf > 0)) return {};
  makeRay(continuation, position, wi, kInfinity, weight, path.pixel(), 0, pdf);
  setMediumAndDepth(continuation, flight.medium, depthOf(path, bounce));
  Spawned spawned;
  spawned.continuation = true;
  return spawned;
}

// ------------------------------------------------------ subsurface probes
//
// pbrt's BSSRDF (material/models/subsurface.h). A BSDF sample that enters a
// probed material becomes a probe: rays along a segment drawn about the
// entry point, each an ordinary closest-hit ray (so forwarded to whichever
// ranks hold what it meets), that count the material's surfaces along the
// segment (kCounting). At the segment's end one of the n found is chosen
// uniformly, and the probe crosses the segment again, ray for ray the same,
// to that surface (kReturning). There the path's weight takes Sp / (pdf / n),
// and light leaves by the exit lobe Sw, with a light sample, as one bounce
// with the entry. The probe carries its segment and the material's probe
// id, so ranks that do not hold the material pass it on.

namespace {
// A probe's random key: the path's depth offset by this.
constexpr uint32_t kProbeKey = 0x20000000u;
}  // namespace

bool sceneTakesProbes(const Scene& scene, SubsurfaceMethod method) {
  if (method != SubsurfaceMethod::Probes) return false;
  for (const Material& m : scene.materials)
    if (const auto* model = dynamic_cast<const SubsurfaceModel*>(m.model.get());
        model && model->hasMedium)
      return true;
  return false;
}

template <typename Path>
const SubsurfaceModel* PathShading<Path>::probeModel(const SurfacePoint& surface) const {
  const size_t i = size_t(surface.material - scene_.materials.data());
  return i < probeModels_.size() ? probeModels_[i] : nullptr;
}

template <typename Path>
bool PathShading<Path>::startProbe(const PathVertex& vertex, const SubsurfaceModel& model,
                                   uint32_t sampleIndex, uint32_t depth, Path& continuation) const {
  if constexpr (!Path::kProbes) {
    return false;
  } else {
    const uint32_t normal = encodeOctahedral(vertex.surface.shadingNormal);
    const RandomStream random(
        RandomKey{randomPixel(vertex.pixel), sampleIndex, kProbeKey + depth, seed_}, sampler_);
    ProbeSegment segment;
    if (!sampleProbeSegment(model.profile(), vertex.surface.position,
                            Frame(normalize(decodeOctahedral(normal))), random(RandomDim::BsdfLobe),
                            {random(RandomDim::BsdfU), random(RandomDim::BsdfV)}, segment))
      return false;
    // pbrt scales radiance by eta^2 through the refraction out and again at
    // Sw; from outside the refraction in takes 1 / eta^2 and they cancel
    // (Ferry's dielectrics scale by neither), but light that the material
    // reflected back inside (or that left another surface inside it) and
    // now refracts out keeps both: eta^4.
    Vec3f weight = continuation.weight();
    if (dot(vertex.wo, vertex.surface.shadingNormal) < 0)
      weight = weight * square(square(model.ior));
    const Vec3f d = segment.end - segment.start;
    const Vec3f stored =
        makeRay(continuation, segment.start, normalize(d), 0, weight, vertex.pixel, 0);
    continuation.tmax = dot(d, stored) / dot(stored, stored);
    continuation.probeEntry = vertex.surface.position;
    continuation.probeNormal = normal;
    continuation.probeStart = segment.start;
    continuation.probeLength = continuation.tmax;
    continuation.probeMaterial = model.probeId;
    continuation.probePhase = PathProbe::kCounting;
    continuation.probeFound = 0;
    continuation.probeSkip = 0;
    return true;
  }
}

template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::shadeProbe(
    const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
    Path& continuation, Path& shadowRay) const {
  if constexpr (!Path::kProbes) {
    return {};
  } else {
    if (bounce >= kWalkBounceLimit) return {};
    const bool counting = path.probePhase == PathProbe::kCounting;
    uint32_t found = path.probeFound;
    Spawned spawned;
    // The next ray along the segment starts at `origin`.
    auto onwards = [&](Vec3f origin, float tmax) {
      continuation = path;
      continuation.origin = origin;
      continuation.tmax = tmax;
      continuation.setPixelAndFlags(path.pixel(), 0);
      continuation.PathReplay::clearHistory();
      spawned.continuation = true;
    };
    if (path.hasHit()) {
      const Vec3f d = path.dir();
      bool same = false;
      Vec3f next;
      if (volumeOf(hit)) {
        next = path.origin + d * hit.t;  // a collision in a volume: not a surface
      } else {
        const SurfacePoint surface = reconstructSurface(scene_, surfaces_, hit, d);
        const SubsurfaceModel* model = probeModel(surface);
        same = model && model->probeId == path.probeMaterial;
        if (same && !counting && path.probeSkip == 0)
          return leaveProbe(path, hit, surface, *model, sampleIndex, bounce, continuation,
                            shadowRay);
        const Vec3f n = dot(d, surface.geometricNormal) > 0 ? surface.geometricNormal
                                                            : -surface.geometricNormal;
        next = offsetRayOrigin(surface.position + n * surface.originOffset, n);
      }
      if (same && counting) found = std::min(found + 1, 255u);
      const Vec3f end = path.probeStart + d * path.probeLength;
      const float tmax = dot(end - next, d) / dot(d, d);
      if (tmax > 0) {
        onwards(next, tmax);
        continuation.probeFound = uint8_t(found);
        if (same && !counting) --continuation.probeSkip;
        return spawned;
      }
    }
    // The segment's end. (Returning, the chosen surface was not found again.)
    if (!counting || found == 0) return spawned;
    const RandomStream random(
        RandomKey{randomPixel(path.pixel()), sampleIndex, kProbeKey + depthOf(path, bounce), seed_},
        sampler_);
    const uint32_t chosen =
        std::min(uint32_t(random(RandomDim::MaterialSelect) * float(found)), found - 1);
    // Back to the start: the first ray again, bit for bit.
    onwards(path.probeStart, path.probeLength);
    continuation.probePhase = PathProbe::kReturning;
    continuation.probeFound = uint8_t(found);
    continuation.probeSkip = uint8_t(chosen);
    return spawned;
  }
}

// At the exit point p_i of a probe from p_o: the weight takes Sp(|p_i -
// p_o|) over the probe's density of p_i (over n, the surfaces it chose
// from); the vertex scatters by Sw about its shading normal (pbrt's wo is
// that normal), with a light sample, and the path's depth counts the entry
// and the exit as one bounce.
template <typename Path>
typename PathShading<Path>::Spawned PathShading<Path>::leaveProbe(
    const Path& path, const TraceHit& hit, const SurfacePoint& surface,
    const SubsurfaceModel& model, uint32_t sampleIndex, uint32_t bounce, Path& continuation,
    Path& shadowRay) const {
  if constexpr (!Path::kProbes) {
    return {};
  } else {
    const SubsurfaceProfile profile = model.profile();
    const Frame entryFrame(normalize(decodeOctahedral(path.probeNormal)));
    const float density = probeDensity(profile, path.probeEntry, entryFrame, surface.position,
                                       surface.geometricNormal) /
                          float(path.probeFound);
    if (!(density > 0)) return {};
    const Vec3f throughput =
        path.weight() * profile.sr(length(surface.position - path.probeEntry)) * (1 / density);
    if (!usable(throughput)) return {};
    const uint32_t depth = depthOf(path, bounce);
    const Vec3f ns = surface.shadingNormal;
    const Vec3f ng =
        dot(surface.geometricNormal, ns) < 0 ? -surface.geometricNormal : surface.geometricNormal;
    const PathVertex vertex{path.pixel(),    depth, throughput,      ns,     false,
                            path.probeEntry, 0.0f,  path.lightRatio, surface};
    const RandomKey key{randomPixel(path.pixel()), sampleIndex, bounce, seed_};
    const Frame frame(ns);
    const VertexScattering scattering{
        Bsdf(model.exitLobe(), false, false),
        ng,
        frame,
        frame.toLocal(ns),
        RandomStream(key, sampler_),
        offsetRayOrigin(surface.position + ng * surface.originOffset, ng),
        surface.originOffset};
    const MediumInterface& sides = surfaceMedia(hit);
    auto leaving = [&](Vec3f direction) {
      return mediumLeaving(sides, surface.geometricNormal, direction, mediumOf(path));
    };
    Spawned spawned;
    spawned.continuation = sampleContinuation(vertex, scattering, 0, continuation);
    if (spawned.continuation)
      setMediumAndDepth(continuation, leaving(continuation.dir()), depth + 1);
    if (strategy_ != LightStrategy::BsdfSamples)
      spawned.shadowRay =
          sampleLight(vertex, scattering, 0, shadowRay) &&
          (!media_ || throughMedia(shadowRay, leaving(shadowRay.dir()), randomKeyHash(key)));
    return spawned;
  }
}

template class PathShading<Path8>;
template class PathShading<Path64>;
template class PathShading<PathReplay>;
template class PathShading<PathProbe>;

}  // namespace ferry
