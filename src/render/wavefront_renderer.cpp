#include "render/wavefront_renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "core/clock.h"
#include "core/error.h"
#include "core/random.h"
#include "render/bsdf.h"
#include "render/surface.h"
#include "scene/scene.h"
#include "trace/path.h"

namespace ferry {
namespace {

// Paths whose bounce reaches this start playing Russian roulette.
constexpr uint32_t kRouletteStartBounce = 3;

// Returns the ray's direction as stored (quantized to halves).
template <typename Path>
Vec3f setRay(Path& p, Vec3f origin, Vec3f direction, float tmax, Vec3f weight, uint32_t pixel,
             uint32_t flags) {
  p.origin = origin;
  Vec3f stored = p.setDirAndWeight(direction, weight);
  p.tmax = tmax;
  p.setPixelAndFlags(pixel, flags);
  p.clearHistory();
  return stored;
}

// Contributions that cannot be represented are dropped rather than poisoning the image.
[[gnu::always_inline]] inline bool usable(Vec3f c) {
  return isFinite(c) && maxComponent(c) > 0;
}

}  // namespace

template <typename Path>
WavefrontRenderer<Path>::WavefrontRenderer(const Scene& scene, const TraceBackend& geometry,
                                           const LightSampler& lights,
                                           RayTraversal<Path>& traversal,
                                           const RenderSettings& settings)
    : scene_(scene),
      geometry_(geometry),
      lights_(lights),
      traversal_(traversal),
      settings_(settings),
      camera_(scene.view(settings.view), settings.width, settings.height),
      surfaces_(scene) {
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
  const uint32_t pixels = uint32_t(settings_.width) * uint32_t(settings_.height);
  for (int s = 0; s < settings_.samplesPerPixel; ++s) {
    const uint32_t sampleIndex = uint32_t(frame * settings_.samplesPerPixel + s);
    if (!chunked()) {
      // Many ranks: the whole image in one wavefront (each bounce is a
      // collective exchange), every stage parallel inside the rank.
      runWavefront(sampleIndex, 0, pixels, workspace_, frameBuffer, stats);
    } else {
      // One rank: chunks of pixels, each taken from camera ray to last bounce
      // by one thread, so that its queues (paths, kept hits, spawned rays:
      // ~130 bytes a pixel) stay in that core's cache from stage to stage and
      // no thread waits for another at the end of every stage (the whole
      // image per wavefront streamed ~17 MB through memory at each stage of a
      // 512x512 frame; docs/performance.md). Chunks are disjoint pixel ranges
      // and each pixel sample is the same computation, adding to the frame
      // buffer in the same order: the image does not depend on the chunks.
      // (Stage times are then summed over the threads.)
      const uint32_t chunk = std::max(1u, settings_.chunkPixels);
      const uint32_t chunks = (pixels + chunk - 1) / chunk;
      tbb::enumerable_thread_specific<FrameStats> chunkStats;
      tbb::parallel_for(tbb::blocked_range<uint32_t>(0, chunks, 1), [&](const auto& range) {
        for (uint32_t c = range.begin(); c != range.end(); ++c) {
          // Isolated: while its stages wait, this thread takes no other chunk,
          // which would reuse its workspace.
          tbb::this_task_arena::isolate([&] {
            runWavefront(sampleIndex, c * chunk, std::min(pixels, (c + 1) * chunk),
                         chunkWorkspaces_.local(), frameBuffer, chunkStats.local());
          });
        }
      });
      for (const FrameStats& local : chunkStats)
        stats.merge(local);  // counters and stage times summed
    }
    if (progress) progress(s + 1, settings_.samplesPerPixel);
  }
  stats.seconds = secondsSince(frameStart);
  return stats;
}

template <typename Path>
void WavefrontRenderer<Path>::runWavefront(uint32_t sampleIndex, uint32_t first, uint32_t last,
                                           Workspace& ws, FrameBuffer& frameBuffer,
                                           FrameStats& stats) {
  generateCameraRays(sampleIndex, first, last, ws, stats);
  for (uint32_t bounce = 0; traversal_.anyRaysLeft(ws.rays.size()); ++bounce) {
    if (stats.perBounce.size() <= bounce) stats.perBounce.resize(bounce + 1);
    traversal_.traverse(ws.rays, ws.hits, stats.perBounce[bounce], stats);
    shade(ws, sampleIndex, bounce, frameBuffer, stats);
    std::swap(ws.rays, ws.next);
  }
}

namespace {

// Deterministic parallel compaction: block b writes its survivors, in queue
// order, contiguously from staging[b * stride]; the blocks are then
// concatenated in block order, so the result does not depend on the threads.
constexpr size_t kBlock = 2048;

template <typename Path>
void concatenateBlocks(const PathQueue<Path>& staging, size_t stride,
                       const std::vector<uint32_t>& counts, PathQueue<Path>& out) {
  std::vector<size_t> offsets(counts.size() + 1, 0);
  for (size_t b = 0; b < counts.size(); ++b) offsets[b + 1] = offsets[b] + counts[b];
  out.resize(offsets.back());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, counts.size(), 4), [&](const auto& range) {
    for (size_t b = range.begin(); b != range.end(); ++b)
      std::copy_n(staging.begin() + ptrdiff_t(b * stride), counts[b],
                  out.begin() + ptrdiff_t(offsets[b]));
  });
}

}  // namespace

template <typename Path>
void WavefrontRenderer<Path>::generateCameraRays(uint32_t sampleIndex, uint32_t first,
                                                 uint32_t last, Workspace& ws, FrameStats& stats) {
  PathQueue<Path>& rays = ws.rays;
  auto start = Clock::now();
  const uint32_t pixels = last - first;
  const uint32_t width = uint32_t(settings_.width);
  auto cameraRay = [&](uint32_t pixel, uint32_t px, uint32_t py, Path& p) {
    RandomStream random(RandomKey{pixel, sampleIndex, 0, settings_.seed});
    float x = float(px) + random(RandomDim::PixelJitterX);
    float y = float(py) + random(RandomDim::PixelJitterY);
    setRay(p, camera_.origin(), camera_.direction(x, y), kInfinity, Vec3f(1), pixel,
           kPathAfterSpecular);
  };
  // Calls f(pixel, x, y) for pixels [begin, end), one division per range.
  auto forPixels = [width](uint32_t begin, uint32_t end, auto&& f) {
    uint32_t px = begin % width, py = begin / width;
    for (uint32_t pixel = begin; pixel != end; ++pixel) {
      f(pixel, px, py);
      if (++px == width) {
        px = 0;
        ++py;
      }
    }
  };
  if (chunked()) {
    // Every pixel's path is this rank's, and this chunk this thread's:
    // straight into the queue, in pixel order.
    rays.resize(pixels);
    forPixels(first, last, [&](uint32_t pixel, uint32_t px, uint32_t py) {
      cameraRay(pixel, px, py, rays[pixel - first]);
    });
  } else {
    const size_t blocks = (size_t(pixels) + kBlock - 1) / kBlock;
    ws.staging.resize(pixels);
    ws.blockCounts.assign(blocks, 0);
    std::atomic<uint64_t> proxyQueries{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const auto& range) {
      FrameStats local;
      for (size_t b = range.begin(); b != range.end(); ++b) {
        const uint32_t begin = uint32_t(b * kBlock),
                       end = uint32_t(std::min<size_t>(pixels, begin + kBlock));
        uint32_t kept = 0;
        forPixels(first + begin, first + end, [&](uint32_t pixel, uint32_t px, uint32_t py) {
          Path& p = ws.staging[begin + kept];
          cameraRay(pixel, px, py, p);
          kept += traversal_.keepsPrimary(pixel, TraceRay{p.origin, p.dir(), 0, kInfinity}, local);
        });
        ws.blockCounts[b] = kept;
      }
      proxyQueries += local.proxyQueries;
    });
    stats.proxyQueries += proxyQueries;
    concatenateBlocks(ws.staging, kBlock, ws.blockCounts, rays);
  }
  stats.cameraPaths += rays.size();
  stats.times.generate += secondsSince(start);
}

template <typename Path>
void WavefrontRenderer<Path>::shade(Workspace& ws, uint32_t sampleIndex, uint32_t bounce,
                                    FrameBuffer& frameBuffer, FrameStats& stats) {
  const PathQueue<Path>& rays = ws.rays;
  const std::vector<TraceHit>& hits = ws.hits;
  auto start = Clock::now();
  FERRY_CHECK(hits.size() == rays.size());
  const size_t n = rays.size();
  const size_t blocks = (n + kBlock - 1) / kBlock;
  // Each path spawns at most two rays (its continuation, then its shadow ray).
  std::atomic<uint64_t> retraceCount{0}, missCount{0}, shadowCount{0};
  // One rank traced every ray itself and kept every hit: nothing to re-trace
  // unless asked to (--retrace all).
  const bool mayRetrace = settings_.retraceAll || !chunked();

  // Shades rays [begin, end) in batches, writing their new rays from `out`
  // on; returns how many.
  auto shadeRange = [&](size_t begin, size_t end, Path* out, uint64_t& retraced, uint64_t& misses,
                        uint64_t& shadows) {
    constexpr size_t kBatch = 256;
    constexpr uint16_t kKept = 0xffff;  // no re-trace: the kept hit (or none)
    RetraceRay queries[kBatch];
    TraceHit found[kBatch];
    uint16_t retraceSlot[kBatch];  // path i's hit is found[retraceSlot[i]], or kKept
    uint32_t count = 0;
    for (size_t batch = begin; batch < end; batch += kBatch) {
      const size_t m = std::min(kBatch, end - batch);
      // Re-trace, as one batched query, every path that hit something whose
      // hit this rank does not have (all of them with --retrace all).
      size_t needed = 0;
      for (size_t i = 0; mayRetrace && i < m; ++i) {
        const Path& p = rays[batch + i];
        const bool retrace =
            !p.isShadow() && p.hasHit() && (settings_.retraceAll || !hits[batch + i].valid());
        retraceSlot[i] = retrace ? uint16_t(needed) : kKept;
        if (retrace) queries[needed++] = {p.origin, p.dir(), p.tmax};
      }
      if (needed) {
        geometry_.retrace(std::span(queries, needed), std::span(found, needed));
        retraced += needed;
      }
      for (size_t i = 0; i < m; ++i) {
        const Path& p = rays[batch + i];
        if (p.isShadow()) {
          // Its light arrives unless something was in the way.
          if (!p.has(kPathOccluded)) frameBuffer.add(p.pixel(), p.weight());
          continue;
        }
        const TraceHit& hit =
            needed && retraceSlot[i] != kKept ? found[retraceSlot[i]] : hits[batch + i];
        int spawned = shadeOne(p, hit, sampleIndex, bounce, frameBuffer, out + count, misses);
        for (int k = 0; k < spawned; ++k) shadows += out[count + k].isShadow();
        count += uint32_t(spawned);
      }
    }
    return count;
  };

  PathQueue<Path>& next = ws.next;
  if (chunked()) {
    // One thread has this wavefront: new rays go straight into the next
    // queue, in the same order as the blocks would give.
    uint64_t retraced = 0, misses = 0, shadows = 0;
    next.resize(2 * n);
    next.resize(shadeRange(0, n, next.data(), retraced, misses, shadows));
    retraceCount += retraced;
    missCount += misses;
    shadowCount += shadows;
  } else {
    ws.staging.resize(2 * n);
    ws.blockCounts.assign(blocks, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const auto& range) {
      uint64_t retraced = 0, misses = 0, shadows = 0;
      for (size_t b = range.begin(); b != range.end(); ++b) {
        const size_t begin = b * kBlock, end = std::min(n, begin + kBlock);
        ws.blockCounts[b] =
            shadeRange(begin, end, ws.staging.data() + 2 * begin, retraced, misses, shadows);
      }
      retraceCount += retraced;
      missCount += misses;
      shadowCount += shadows;
    });
    concatenateBlocks(ws.staging, 2 * kBlock, ws.blockCounts, next);
  }

  stats.shadowRays += shadowCount;
  stats.continuationRays += next.size() - shadowCount;
  stats.retraces += retraceCount;
  stats.retraceMisses += missCount;
  stats.times.shade += secondsSince(start);
}

template <typename Path>
int WavefrontRenderer<Path>::shadeOne(const Path& path, const TraceHit& hit, uint32_t sampleIndex,
                                      uint32_t bounce, FrameBuffer& frameBuffer, Path* out,
                                      uint64_t& misses) const {
  const uint32_t maxDepth = uint32_t(std::max(settings_.maxDepth, 0));
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
    return 0;
  }
  if (!hit.valid()) {
    ++misses;
    return 0;
  }
  SurfacePoint surface = reconstructSurface(scene_, surfaces_, hit);
  const Material& material = *surface.material;
  const Vec3f wo = normalize(-dir);

  if (afterSpecular && material.isEmissive()) {
    Vec3f l = throughput * material.emission;
    if (usable(l)) frameBuffer.add(pixel, l);
  }
  if (bounce >= maxDepth) return 0;

  // (Emission above counted only after a delta vertex, which spawns no shadow
  // ray: a pixel's path and shadow ray never both write the frame buffer in
  // one wavefront, which lets shade() add shadow rays in the same pass.)
  Bsdf bsdf = Bsdf::fromMaterial(material, surface.baseColor);
  Vec3f ng = surface.geometricNormal, ns = surface.shadingNormal;
  if (!bsdf.transmits() && dot(ng, wo) < 0) {
    // Opaque surfaces are two-sided: shade the side the ray arrived on.
    ng = -ng;
    ns = -ns;
  }
  Frame frame(ns);
  const Vec3f woLocal = frame.toLocal(wo);
  const RandomStream random(RandomKey{pixel, sampleIndex, bounce, settings_.seed});
  int spawned = 0;

  // Continuation, then the shadow ray: the queue order. Each is written in
  // place (no copy of a half-written path through the stack); the two draw
  // different random dimensions, so the order of computing them is free.
  [&] {
    BsdfSample bs;
    Vec2f u{random(RandomDim::BsdfU), random(RandomDim::BsdfV)};
    if (!bsdf.sample(woLocal, random(RandomDim::BsdfLobe), u, bs)) return;
    Vec3f wi = frame.toWorld(bs.wi);
    if (!bsdf.transmits() && dot(wi, ng) <= 0) return;  // shading normal sent it below the surface
    Vec3f next = throughput * bs.weight;
    if (bounce + 1 >= kRouletteStartBounce) {
      float q = std::min(1.0f, maxComponent(next));
      if (random(RandomDim::Roulette) >= q) return;
      next = next * (1 / q);
    }
    if (!usable(next)) return;
    Vec3f origin = offsetRayOrigin(surface.position, dot(wi, ng) > 0 ? ng : -ng);
    setRay(out[spawned++], origin, wi, kInfinity, next, pixel,
           bs.delta ? uint32_t(kPathAfterSpecular) : 0u);
  }();

  // Next-event estimation: exactly one light sample.
  if (bsdf.isDelta()) return spawned;
  LightSample ls;
  Vec2f u{random(RandomDim::LightSampleU), random(RandomDim::LightSampleV)};
  if (!lights_.sample(surface.position, frame, bsdf.transmits(), random(RandomDim::LightSelect), u,
                      ls))
    return spawned;
  Vec3f f = bsdf.eval(woLocal, frame.toLocal(ls.direction));
  Vec3f contribution = throughput * f * ls.radiance * (1 / ls.pdf);
  // Only light arriving on the geometric side it is evaluated for.
  bool sameSide = bsdf.transmits() || dot(ls.direction, ng) > 0;
  if (!sameSide || !usable(contribution)) return spawned;
  Vec3f origin = offsetRayOrigin(surface.position, dot(ls.direction, ng) > 0 ? ng : -ng);
  Path& shadow = out[spawned++];
  const Vec3f d = setRay(shadow, origin, ls.direction, kInfinity, contribution, pixel, kPathShadow);
  if (std::isfinite(ls.distance)) {
    // Stop short of the emitter along the ray as stored: its half-precision
    // direction is off by up to ~3e-4 rad, so it meets the emitter's plane up
    // to 3e-4 / cos(theta_light) (relative) before or after the sampled point,
    // more than the 1e-4 margin; the emitter then shadowed itself (6% too
    // dark under a square light, 11% inside a closed emitter).
    Vec3f toLight = surface.position + ls.direction * ls.distance - origin;
    float t = length(toLight) / length(d);
    float along = dot(d, ls.normal);
    if (along != 0) {
      float tPlane = dot(toLight, ls.normal) / along;
      if (tPlane > 0) t = std::min(t, tPlane);
    }
    shadow.tmax = t * (1 - 1e-4f);
  }
  return spawned;
}

template class WavefrontRenderer<Path8>;
template class WavefrontRenderer<Path64>;
template class WavefrontRenderer<PathReplay>;

}  // namespace ferry
