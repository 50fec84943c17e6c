#include "render/wavefront_renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "core/random.h"
#include "render/bsdf.h"
#include "render/path.h"
#include "render/surface.h"
#include "scene/scene.h"

namespace ferry {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Paths whose bounce reaches this start playing Russian roulette.
constexpr uint32_t kRouletteStartBounce = 3;

template <typename Path>
Path makeRay(Vec3f origin, Vec3f direction, float tmax, Vec3f weight, uint32_t pixel, uint32_t flags) {
  Path p{};
  p.origin = origin;
  p.setDir(direction);
  p.tmax = tmax;
  p.setWeight(weight);
  p.setPixelAndFlags(pixel, flags);
  p.clearHistory();
  return p;
}

// Contributions that cannot be represented are dropped rather than poisoning the image.
bool usable(Vec3f c) { return isFinite(c) && maxComponent(c) > 0; }

}  // namespace

template <typename Path>
WavefrontRenderer<Path>::WavefrontRenderer(const Scene& scene, const LocalGeometry& geometry,
                                           const LightSampler& lights, RayTraversal<Path>& traversal,
                                           const RenderSettings& settings)
    : scene_(scene),
      geometry_(geometry),
      lights_(lights),
      traversal_(traversal),
      settings_(settings),
      camera_(scene.view(settings.view), settings.width, settings.height) {
  if (uint64_t(settings.width) * uint64_t(settings.height) > kMaxPixels)
    throw InputError(fmt::format("image of {}x{} has more than {} pixels", settings.width,
                                 settings.height, kMaxPixels));
}

template <typename Path>
FrameStats WavefrontRenderer<Path>::renderFrame(int frame, FrameBuffer& frameBuffer,
                                                const ProgressCallback& progress) {
  FrameStats stats;
  stats.frame = frame;
  auto frameStart = Clock::now();
  std::vector<Path> rays;
  for (int s = 0; s < settings_.samplesPerPixel; ++s) {
    const uint32_t sampleIndex = uint32_t(frame * settings_.samplesPerPixel + s);
    generateCameraRays(sampleIndex, rays, stats);
    for (uint32_t bounce = 0; traversal_.anyRaysLeft(rays.size()); ++bounce) {
      if (stats.perBounce.size() <= bounce) stats.perBounce.resize(bounce + 1);
      traversal_.traverse(rays, stats.perBounce[bounce], stats);
      accumulateShadowRays(rays, frameBuffer, stats);
      rays = shade(rays, sampleIndex, bounce, frameBuffer, stats);
    }
    if (progress) progress(s + 1, settings_.samplesPerPixel);
  }
  stats.seconds = secondsSince(frameStart);
  return stats;
}

template <typename Path>
void WavefrontRenderer<Path>::generateCameraRays(uint32_t sampleIndex, std::vector<Path>& rays,
                                                 FrameStats& stats) {
  auto start = Clock::now();
  const uint32_t pixels = uint32_t(settings_.width) * uint32_t(settings_.height);
  std::vector<Path> all(pixels);
  std::vector<uint8_t> kept(pixels);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, pixels, 1024), [&](const auto& range) {
    FrameStats local;
    for (uint32_t pixel = range.begin(); pixel != range.end(); ++pixel) {
      RandomKey key{pixel, sampleIndex, 0, settings_.seed};
      float x = float(pixel % settings_.width) + random01(key, RandomDim::PixelJitterX);
      float y = float(pixel / settings_.width) + random01(key, RandomDim::PixelJitterY);
      all[pixel] = makeRay<Path>(camera_.origin(), camera_.direction(x, y), kInfinity, Vec3f(1), pixel,
                                 kPathAfterSpecular);
      TraceRay ray{all[pixel].origin, all[pixel].dir(), 0, kInfinity};
      kept[pixel] = traversal_.keepsPrimary(pixel, ray, local);
    }
  });
  rays.clear();
  for (uint32_t pixel = 0; pixel < pixels; ++pixel)
    if (kept[pixel]) rays.push_back(all[pixel]);
  stats.cameraPaths += rays.size();
  stats.times.generate += secondsSince(start);
}

template <typename Path>
void WavefrontRenderer<Path>::accumulateShadowRays(const std::vector<Path>& rays, FrameBuffer& frameBuffer,
                                                   FrameStats& stats) {
  auto start = Clock::now();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 4096), [&](const auto& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const Path& p = rays[i];
      if (p.isShadow() && !p.has(kPathOccluded)) frameBuffer.add(p.pixel(), p.weight());
    }
  });
  stats.times.accumulate += secondsSince(start);
}

template <typename Path>
std::vector<Path> WavefrontRenderer<Path>::shade(const std::vector<Path>& rays, uint32_t sampleIndex,
                                                 uint32_t bounce, FrameBuffer& frameBuffer,
                                                 FrameStats& stats) {
  auto start = Clock::now();
  const uint32_t maxDepth = uint32_t(std::max(settings_.maxDepth, 0));
  // Slot 2i: the continuation of ray i, slot 2i+1: its shadow ray. Compacted
  // in order afterwards, so the next wavefront's order is deterministic.
  std::vector<Path> spawned(rays.size() * 2);
  std::vector<uint8_t> live(rays.size() * 2, 0);
  std::atomic<uint64_t> retraceMisses{0};

  // Re-trace every path that hit something, to recover the full hit, as one
  // batched query (the same kind of query that found it, so the same hit is
  // found). Embree accepts a hit only somewhat inside tfar, with an error that
  // scales with the coordinates, not with t (measured: tfar = t, t + 1e-6
  // relative, or t * 1.001 at t = 0.016 in a 555-unit box can all miss it), so
  // search past tmax by a margin of both kinds; nothing closer than the
  // recorded hit exists, so the closest hit found is the same one.
  std::vector<TraceRay> retrace(rays.size());
  std::vector<TraceHit> hits(rays.size());
  std::vector<uint32_t> retraced;
  for (uint32_t i = 0; i < rays.size(); ++i)
    if (!rays[i].isShadow() && rays[i].hasHit()) {
      const Vec3f o = rays[i].origin;
      const float scale = std::max({std::abs(o.x), std::abs(o.y), std::abs(o.z), 1.0f});
      retrace[retraced.size()] = {o, rays[i].dir(), 0, rays[i].tmax * 1.001f + 1e-4f * scale};
      retraced.push_back(i);
    }
  {
    std::vector<TraceHit> found(retraced.size());
    geometry_.intersect(std::span(retrace.data(), retraced.size()), found);
    for (size_t k = 0; k < retraced.size(); ++k) hits[retraced[k]] = found[k];
  }

  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 256), [&](const auto& range) {
    uint64_t localMisses = 0;
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const Path& path = rays[i];
      if (path.isShadow()) continue;
      const uint32_t pixel = path.pixel();
      const Vec3f throughput = path.weight();
      const Vec3f dir = path.dir();
      const bool afterSpecular = path.has(kPathAfterSpecular);

      if (!path.hasHit()) {
        // Escaped: light from infinity counts only where no light sample covered it.
        if (afterSpecular) {
          Vec3f l = throughput * lights_.background(normalize(dir));
          if (usable(l)) frameBuffer.add(pixel, l);
        }
        continue;
      }

      const TraceHit& hit = hits[i];
      if (!hit.valid()) {
        ++localMisses;
        continue;
      }
      SurfacePoint surface = reconstructSurface(scene_, hit);
      const Material& material = *surface.material;
      const Vec3f wo = normalize(-dir);

      if (afterSpecular && material.isEmissive()) {
        Vec3f l = throughput * material.emission;
        if (usable(l)) frameBuffer.add(pixel, l);
      }
      if (bounce >= maxDepth) continue;

      Bsdf bsdf = Bsdf::fromMaterial(material, surface.baseColor);
      Vec3f ng = surface.geometricNormal, ns = surface.shadingNormal;
      if (!bsdf.transmits() && dot(ng, wo) < 0) {
        // Opaque surfaces are two-sided: shade the side the ray arrived on.
        ng = -ng;
        ns = -ns;
      }
      Frame frame(ns);
      const Vec3f woLocal = frame.toLocal(wo);
      RandomKey key{pixel, sampleIndex, bounce, settings_.seed};

      // Next-event estimation: exactly one light sample.
      if (!bsdf.isDelta()) {
        LightSample ls;
        Vec2f u{random01(key, RandomDim::LightSampleU), random01(key, RandomDim::LightSampleV)};
        if (lights_.sample(surface.position, ns, bsdf.transmits(), random01(key, RandomDim::LightSelect), u, ls)) {
          Vec3f f = bsdf.eval(woLocal, frame.toLocal(ls.direction));
          Vec3f contribution = throughput * f * ls.radiance * (1 / ls.pdf);
          // Only light arriving on the geometric side it is evaluated for.
          bool sameSide = bsdf.transmits() || dot(ls.direction, ng) > 0;
          if (sameSide && usable(contribution)) {
            Vec3f origin = offsetRayOrigin(surface.position, dot(ls.direction, ng) > 0 ? ng : -ng);
            Path shadow = makeRay<Path>(origin, ls.direction, kInfinity, contribution, pixel, kPathShadow);
            if (std::isfinite(ls.distance)) {
              // Stop short of the emitter along the ray as stored: its half-precision
              // direction is off by up to ~3e-4 rad, so it meets the emitter's plane up
              // to 3e-4 / cos(theta_light) (relative) before or after the sampled point,
              // more than the 1e-4 margin; the emitter then shadowed itself (6% too
              // dark under a square light, 11% inside a closed emitter).
              Vec3f d = shadow.dir();
              Vec3f toLight = surface.position + ls.direction * ls.distance - origin;
              float t = length(toLight) / length(d);
              float along = dot(d, ls.normal);
              if (along != 0) {
                float tPlane = dot(toLight, ls.normal) / along;
                if (tPlane > 0) t = std::min(t, tPlane);
              }
              shadow.tmax = t * (1 - 1e-4f);
            }
            spawned[2 * i + 1] = shadow;
            live[2 * i + 1] = 1;
          }
        }
      }

      // Continuation.
      BsdfSample bs;
      Vec2f u{random01(key, RandomDim::BsdfU), random01(key, RandomDim::BsdfV)};
      if (!bsdf.sample(woLocal, random01(key, RandomDim::BsdfLobe), u, bs)) continue;
      Vec3f wi = frame.toWorld(bs.wi);
      if (!bsdf.transmits() && dot(wi, ng) <= 0) continue;  // shading normal sent it below the surface
      Vec3f next = throughput * bs.weight;
      if (bounce + 1 >= kRouletteStartBounce) {
        float q = std::min(1.0f, maxComponent(next));
        if (random01(key, RandomDim::Roulette) >= q) continue;
        next = next * (1 / q);
      }
      if (!usable(next)) continue;
      Vec3f origin = offsetRayOrigin(surface.position, dot(wi, ng) > 0 ? ng : -ng);
      spawned[2 * i] = makeRay<Path>(origin, wi, kInfinity, next, pixel, bs.delta ? uint32_t(kPathAfterSpecular) : 0u);
      live[2 * i] = 1;
    }
    retraceMisses += localMisses;
  });

  std::vector<Path> next;
  next.reserve(rays.size());
  for (size_t k = 0; k < spawned.size(); ++k) {
    if (!live[k]) continue;
    next.push_back(spawned[k]);
    if (k & 1)
      ++stats.shadowRays;
    else
      ++stats.continuationRays;
  }
  stats.retraces += retraced.size();
  stats.retraceMisses += retraceMisses;
  stats.times.shade += secondsSince(start);
  return next;
}

template class WavefrontRenderer<Path8>;
template class WavefrontRenderer<Path64>;
template class WavefrontRenderer<PathReplay>;

}  // namespace ferry
