// Shading one path vertex, in named steps (the wavefront renderer's shade
// stage runs shadePath for every path that traversal left on this rank):
//
//   escaped        a path that hit nothing: the light from infinity
//   surface        the hit's surface rebuilt (the path carries no hit data)
//   emission       the light the surface emits back along the path
//   shading frame  the BSDF, both normals turned to the side the path came
//                  from, the local frame, the vertex's random numbers
//   BSDF sample    the continuation, after Russian roulette
//   light sample   next-event estimation: one light, one shadow ray, its tmax
//
// Emitters are weighed by MIS over the BSDF and light samples, and with light
// paths (connections to the camera) over all three; the densities travel on
// the path (PathCore::bsdfDensity, lightRatio). docs/path-tracer.md,
// "Multiple importance sampling" and "Light paths".
#pragma once

#include <algorithm>
#include <cstdint>

#include <memory>
#include "core/math.h"
#include "core/random.h"

#include <tbb/enumerable_thread_specific.h>

#include "material/bsdf.h"
#include "media/tracking.h"
#include "path/path.h"
#include "render/camera.h"
#include "render/frame_buffer.h"
#include "render/lights.h"
#include "render/media_along_rays.h"
#include "render/surface.h"
#include "trace/trace_backend.h"

namespace ferry {

struct Scene;
struct SubsurfaceModel;

// A light path's shadow ray to the camera stops this fraction of the way to
// the camera's lens point (so that it never finds the lens as a surface).
constexpr float kCameraConnectionShortening = 1 - 1e-4f;

// A path at a surface (the surface step): what it brings and where it is.
struct PathVertex {
  uint32_t pixel;
  uint32_t bounce;
  Vec3f throughput;     // of the path arriving here
  Vec3f wo;             // unit, back towards where the path came from
  bool afterSpecular;   // the previous vertex was the camera or a delta lobe
  Vec3f from;           // the ray's origin: the previous vertex
  float bsdfPdf;        // the previous vertex's BSDF density for wo (as stored)
  uint16_t lightRatio;  // as the path stores it (see "Light paths")
  SurfacePoint surface;
};

// How the vertex scatters light (the shading-frame step).
struct VertexScattering {
  Bsdf bsdf;
  Vec3f ng;             // geometric normal, on wo's side unless the BSDF transmits
  Frame frame;          // about the shading normal, turned with ng
  Vec3f woLocal;        // wo in `frame`
  RandomStream random;  // this vertex's numbers: (pixel, sample, bounce, seed)
  Vec3f originAbove;    // where rays leaving on ng's side start (offsetRayOrigin)
  float originOffset;   // SurfacePoint::originOffset
  // Where a ray leaving in direction `d` starts: off the surface on d's side of ng.
  Vec3f originTowards(Vec3f position, Vec3f d) const {
    return dot(d, ng) > 0 ? originAbove : offsetRayOrigin(position - ng * originOffset, -ng);
  }
};

// Makes `p` a new ray (no traversal history); returns its direction as stored
// (quantized), without reading it back. `bsdfPdf`: see PathCore::bsdfDensity.
template <typename Path>
[[gnu::always_inline]] inline Vec3f makeRay(Path& p, Vec3f origin, Vec3f direction, float tmax,
                                            Vec3f weight, uint32_t pixel, uint32_t flags,
                                            float bsdfPdf = 0, float lightRatio = 0) {
  p.origin = origin;
  p.bsdfDensity = packDensity(bsdfPdf);
  p.lightRatio = packDensity(lightRatio);
  Vec3f stored = p.setDirAndWeight(direction, weight);
  p.tmax = tmax;
  p.setPixelAndFlags(pixel, flags);
  p.clearHistory();
  return stored;
}

// Where a shadow ray from `origin` along `storedDir` (its direction as
// stored) to the sampled point of a finite light stops: short of the sampled
// point and of the emitter's plane along the ray as stored, so the emitter
// does not shadow itself (docs/path-tracer.md, "Light sampling").
[[gnu::always_inline]] inline float shadowRayTmax(Vec3f position, Vec3f origin, Vec3f storedDir,
                                                  const LightSample& light) {
  const Vec3f toLight = position + light.direction * light.distance - origin;
  float t = length(toLight) / length(storedDir);
  const float along = dot(storedDir, light.normal);
  if (along != 0) {
    const float tPlane = dot(toLight, light.normal) / along;
    if (tPlane > 0) t = std::min(t, tPlane);
  }
  return t * (1 - 1e-4f);
}

// Which samples find emitters and the sky. Mis: both (the default).
// LightSamples: light samples alone (emission counts only after delta
// vertices; the paper's). BsdfSamples: BSDF samples
// alone, no shadow rays (for tests: all three must agree on the mean).
enum class LightStrategy { Mis, LightSamples, BsdfSamples };
// "mis", "light", "bsdf" (the stats JSON and checkpoint identities).
inline const char* lightStrategyName(LightStrategy s) {
  return s == LightStrategy::Mis ? "mis" : s == LightStrategy::LightSamples ? "light" : "bsdf";
}

// How light that enters a subsurface material finds where it leaves
// (--subsurface; material/models/subsurface.h): pbrt's BSSRDF sampled by
// probe rays (the default: it needs the probe path layout, PathProbe), or a
// random walk through the medium inside.
enum class SubsurfaceMethod { Probes, Walks };
inline const char* subsurfaceMethodName(SubsurfaceMethod m) {
  return m == SubsurfaceMethod::Probes ? "probe" : "walk";
}
// Whether rendering `scene` by `method` takes probe paths (a subsurface
// material with its medium, and probes asked for).
bool sceneTakesProbes(const Scene& scene, SubsurfaceMethod method);

// How MIS weighs strategies (--mis-heuristic): Veach's power heuristic
// (beta = 2, the default, pbrt's path integrator's) or the balance heuristic
// (beta = 1, pbrt's bdpt's). Either is unbiased; they differ only in noise,
// and where pbrt-v3's mirrored emitters make one strategy see no light.
enum class MisHeuristic { Power, Balance };
inline const char* misHeuristicName(MisHeuristic h) {
  return h == MisHeuristic::Power ? "power" : "balance";
}

template <typename Path>
class PathShading {
 public:
  // `maxDepth`: scattering events (1 = direct lighting only); `seed`: the
  // render's random seed; `strategy`: which samples find emitters and the sky.
  // `lightPathCamera`: light paths connect to it (null: no light paths; they
  // need MIS and an emissive triangle, else there are none either).
  // `window`: the part of the film the image is (a crop); random numbers
  // are keyed by the film's pixel (null: the image is the film).
  // `transmittance`: how shadow rays through media estimate it. A scene with
  // participating media takes no light paths (its camera paths carry their
  // medium where light paths keep a ratio: path/path.h, pathMedium).
  // `sampler`: how a vertex's random numbers are drawn (core/random.h).
  // `subsurface`: probes need the probe layout (Path::kProbes); with
  // another layout subsurface materials are walked.
  PathShading(const Scene& scene, const LightSampler& lights, uint32_t maxDepth, uint32_t seed,
              LightStrategy strategy = LightStrategy::Mis, const Camera* lightPathCamera = nullptr,
              const FilmWindow* window = nullptr,
              TransmittanceEstimator transmittance = TransmittanceEstimator::Ratio,
              MisHeuristic heuristic = MisHeuristic::Power,
              SamplerKind sampler = SamplerKind::Sobol,
              SubsurfaceMethod subsurface = SubsurfaceMethod::Probes);

  // The pixel index random numbers of image pixel `pixel` are keyed by:
  // its index in the whole film.
  uint32_t randomPixel(uint32_t pixel) const { return cropped_ ? window_.filmPixel(pixel) : pixel; }

  // The medium camera rays start in (kNoMedium: none, or no media).
  int32_t cameraMedium() const { return cameraMedium_; }
  // What tracking through media did since the last call (summed over threads).
  MediumCounts takeMediumCounts() const;

  // Whether pixel samples start light paths.
  bool lightPaths() const { return camera_ != nullptr; }
  // Light path `index` (one per pixel, the pixel's index) of sample
  // `sampleIndex`: its first ray, from an emitter. False if none.
  bool makeLightPath(uint32_t index, uint32_t sampleIndex, Path& out) const;
  // The pixel an unoccluded shadow ray adds its light to: its pixel, or for
  // a light path's ray to the camera where its origin projects.
  bool shadowRayPixel(const Path& shadowRay, uint32_t& pixel) const {
    if (!shadowRay.has(kPathLight)) {
      pixel = shadowRay.pixel();
      return true;
    }
    if (!camera_) return false;
    if (!camera_->hasLens()) return camera_->pixelOf(shadowRay.origin, pixel);
    // The lens point the connection chose: the ray's end (shadeLightPath).
    const Vec3f lens =
        shadowRay.origin + shadowRay.dir() * (shadowRay.tmax / kCameraConnectionShortening);
    return camera_->pixelOf(shadowRay.origin, lens, pixel);
  }

  // What shading one path made: each is written only when made.
  struct Spawned {
    bool continuation = false;
    bool shadowRay = false;
  };
  // Shades one path, given its hit when it has one (path.hasHit(); the hit
  // must then be valid): adds the light it finds to the frame buffer, and
  // writes its continuation to `continuation` and its shadow ray to `shadowRay`.
  Spawned shadePath(const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
                    FrameBuffer& frameBuffer, Path& continuation, Path& shadowRay) const;

 private:
  // The steps, in shadePath's order (defined in path_shading.cpp and inlined
  // into shadePath: this is the hot loop of a frame).
  inline void addEscapedLight(const Path& path, FrameBuffer& frameBuffer) const;
  inline PathVertex surfaceVertex(const Path& path, const TraceHit& hit, uint32_t bounce) const;
  inline void addEmission(const PathVertex& vertex, const TraceHit& hit,
                          FrameBuffer& frameBuffer) const;
  // A camera path's first surface: its AOVs to the frame buffer (which has some).
  void addFirstSurfaceAovs(const PathVertex& vertex, const VertexScattering& scattering,
                           FrameBuffer& frameBuffer) const;
  // `keyBounce`: the random key's bounce (a light path's are offset).
  inline VertexScattering shadingFrame(const PathVertex& vertex, uint32_t sampleIndex,
                                       uint32_t keyBounce) const;
  // `chosen`: the material of the chain the mix picked.
  Bsdf mixedBsdf(const SurfacePoint& surface, float u, const Material*& chosen) const;
  // `lightBase`: with light paths, the camera path's ratio up to this
  // vertex but for its reverse density (0: none).
  inline bool sampleContinuation(const PathVertex& vertex, const VertexScattering& scattering,
                                 float lightBase, Path& continuation) const;
  inline bool survivesRoulette(const PathVertex& vertex, const VertexScattering& scattering,
                               Vec3f& weight) const;
  // Whether a vertex's light sample draws a constant sky uniformly over the
  // sphere, weighed by MIS against its BSDF sample: where light arrives from
  // both sides, and (under MIS) wherever the BSDF is not diffuse, whose
  // glossy lobe a sky sample about the normal would find only by chance.
  // A diffuse surface's sky sample is cosine-weighted and needs no MIS.
  inline bool skyOverSphere(const Bsdf& bsdf) const;
  inline bool sampleLight(const PathVertex& vertex, const VertexScattering& scattering,
                          float lightBase, Path& shadowRay) const;
  // Light paths: the camera path's ratio at its vertex (see lightRatio).
  inline float cameraLightBase(const PathVertex& vertex, const VertexScattering& scattering) const;
  // A light path at a surface: its connection to the camera and its continuation.
  Spawned shadeLightPath(const Path& path, const TraceHit& hit, uint32_t sampleIndex,
                         uint32_t bounce, Path& continuation, Path& shadowRay) const;
  bool emission(uint32_t index, uint32_t sampleIndex, EmissionSample& out) const;

  // Participating media (path_shading.cpp, "Media"): the path's way to its
  // hit through the media, then the surface, or a vertex in a medium.
  Spawned shadeInMedia(const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
                       FrameBuffer& frameBuffer, Path& continuation, Path& shadowRay) const;
  // A vertex scattering by a Henyey-Greenstein phase function of asymmetry
  // `g`, in `medium` (the path's medium after it; kNoMedium without media).
  // `depth`: the scattering events the path has made (its bounce, but for
  // subsurface walks); `bounce` keys its random numbers.
  Spawned shadeMediumVertex(const Path& path, Vec3f position, float g, int32_t medium,
                            uint32_t sampleIndex, uint32_t bounce, uint32_t depth,
                            Path& continuation, Path& shadowRay) const;
  // A path scattering inside a subsurface material's medium (`flight`
  // ended there): on by the phase function, with no light sample (the
  // surface around it is in the way) and no bounce counted.
  Spawned walkVertex(const Path& path, Vec3f position, const MediaFlight& flight,
                     uint32_t sampleIndex, uint32_t bounce, Path& continuation) const;
  // Subsurface probes (path_shading.cpp, "Subsurface probes"). The model
  // whose BSSRDF light entering `surface` samples, or null.
  const SubsurfaceModel* probeModel(const SurfacePoint& surface) const;
  // Turns `continuation`, which a BSDF sample sent into the probe material
  // at `vertex`, into a probe ray; false if the probe draws no segment.
  bool startProbe(const PathVertex& vertex, const SubsurfaceModel& model, uint32_t sampleIndex,
                  uint32_t depth, Path& continuation) const;
  // A probe ray's trace: counts the material's surfaces, or returns to the
  // chosen one and leaves there.
  Spawned shadeProbe(const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
                     Path& continuation, Path& shadowRay) const;
  // Light leaving the probe material at its chosen surface.
  Spawned leaveProbe(const Path& path, const TraceHit& hit, const SurfacePoint& surface,
                     const SubsurfaceModel& model, uint32_t sampleIndex, uint32_t bounce,
                     Path& continuation, Path& shadowRay) const;
  // The volume (scene/shape.h: isVolume) the hit is a collision in, or null.
  const Shape* volumeOf(const TraceHit& hit) const;
  // A path that collided in a volume (a brick: shapes/volume_brick.h): it
  // scatters there, weighed by the volume's albedo.
  Spawned shadeVolumeCollision(const Path& path, const TraceHit& hit, const Shape& volume,
                               int32_t medium, uint32_t sampleIndex, uint32_t bounce,
                               uint32_t depth, Path& continuation, Path& shadowRay) const;
  // Multiplies a shadow ray leaving into `medium` by its transmittance to the
  // light; false if none is left.
  bool throughMedia(Path& shadowRay, int32_t medium, uint32_t keyHash) const;
  const MediumInterface& surfaceMedia(const TraceHit& hit) const;
  // The medium a ray leaving a surface of media `sides` (geometric normal
  // `ng`) along `direction` enters; `current` where the surface is no
  // transition. Under probes the inside of a subsurface material is empty,
  // as in pbrt (its medium is the walks').
  int32_t mediumLeaving(const MediumInterface& sides, Vec3f ng, Vec3f direction,
                        int32_t current) const {
    const int32_t m = sides.isTransition() ? sides.along(direction, ng) : current;
    return probes_ && m != kNoMedium && media_->medium(m).subsurface ? kNoMedium : m;
  }
  // In a scene with subsurface walks the path's 16 medium bits hold its
  // medium + 1 in the low 8 and its depth in the high 8 (a walk's steps are
  // wavefront bounces that do not count); otherwise the depth is the bounce.
  // So do scenes with probes (a probe's rays are not bounces either).
  int32_t mediumOf(const Path& path) const {
    return depthOnPath_ ? int32_t(path.lightRatio & 0xffu) - 1 : pathMedium(path);
  }
  uint32_t depthOf(const Path& path, uint32_t bounce) const {
    return depthOnPath_ ? uint32_t(path.lightRatio >> 8) : bounce;
  }
  void setMediumAndDepth(Path& path, int32_t medium, uint32_t depth) const {
    if (depthOnPath_)
      path.lightRatio = uint16_t(uint32_t(medium + 1) | (std::min(depth, 255u) << 8));
    else
      setPathMedium(path, medium);
  }

  const Scene& scene_;
  const LightSampler& lights_;
  SurfaceTable surfaces_;  // for reconstructSurface
  uint32_t maxDepth_;
  uint32_t seed_;
  SamplerKind sampler_;
  LightStrategy strategy_;
  MisHeuristic heuristic_;
  // A density ratio raised to the heuristic's beta (the weights below sum these).
  float misPow(float ratio) const {
    return heuristic_ == MisHeuristic::Power ? ratio * ratio : ratio;
  }
  // The weight of a sample drawn with density `own` against another
  // strategy's `other`: own^beta / (own^beta + other^beta), written as a
  // ratio so that large densities do not overflow.
  float misWeight(float own, float other) const {
    if (!(other > 0)) return 1;
    if (!(own > 0)) return 0;
    return 1 / (1 + misPow(other / own));
  }
  const Camera* camera_ = nullptr;  // light paths connect to it (null: none)
  float lightPathScale_ = 1;        // light path throughputs are stored divided by it
  FilmWindow window_;
  bool cropped_ = false;
  std::shared_ptr<const MediaAlongRays> media_;  // null: no media
  TransmittanceEstimator transmittance_ = TransmittanceEstimator::Ratio;
  int32_t cameraMedium_ = kNoMedium;
  bool walks_ = false;  // the scene has a subsurface medium (Medium::subsurface)
  // Per material: the subsurface model probes sample (null: none, or no probes).
  std::vector<const SubsurfaceModel*> probeModels_;
  bool probes_ = false;       // some material is probed
  bool depthOnPath_ = false;  // walks_ || probes_
  mutable tbb::enumerable_thread_specific<MediumCounts> mediumCounts_;
};

}  // namespace ferry
