#include "render/wavefront_renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <span>

#include "core/clock.h"
#include "core/error.h"
#include "core/hash64.h"
#include "core/random.h"
#include "path/path.h"
#include "scene/scene.h"

namespace ferry {

CameraView RenderSettings::cameraIn(const Scene& scene) const {
  CameraView v = camera ? *camera : scene.view(view);
  if (lensRadius) v.lensRadius = *lensRadius;
  if (focalDistance) v.focalDistance = *focalDistance;
  return v;
}

template <typename Path>
WavefrontRenderer<Path>::WavefrontRenderer(const Scene& scene, const TraceBackend& geometry,
                                           const LightSampler& lights,
                                           RayTraversal<Path>& traversal,
                                           const RenderSettings& settings)
    : geometry_(geometry),
      traversal_(traversal),
      settings_(settings),
      window_(settings.window()),
      camera_(settings.cameraIn(scene), window_),
      shading_(scene, lights, uint32_t(std::max(settings.maxDepth, 0)), settings.seed,
               settings.lightStrategy, settings.lightPaths ? &camera_ : nullptr, &window_,
               settings.transmittance, settings.misHeuristic, settings.sampler,
               settings.subsurface) {
  if (uint64_t(window_.width) * uint64_t(window_.height) > kMaxPixels)
    throw InputError(fmt::format("image of {}x{} has more than {} pixels", window_.width,
                                 window_.height, kMaxPixels));
  // The pinhole rays through the film are fixed by the origin, the film
  // corners' directions and the window: their bits name the view.
  const float x0 = float(window_.x0), y0 = float(window_.y0);
  const Vec3f key[] = {camera_.origin(), camera_.direction(x0, y0),
                       camera_.direction(x0 + float(window_.width), y0),
                       camera_.direction(x0, y0 + float(window_.height))};
  const int sizes[] = {window_.x0, window_.y0, window_.width, window_.height};
  viewKey_ = hash64(sizes, sizeof sizes, hash64(key, sizeof key));
  const CameraView view = settings.cameraIn(scene);
  if (view.motion) {
    cameraMotion_ = view.motion;
    cameraStartInverse_ = view.motion->at(0).inverse();
  }
  moves_ = scene.moves();  // (a moving view included)
  clock_ = {scene.shutterOpen,       scene.shutterClose,
            scene.motionStart,       scene.motionEnd,
            settings.seed,           settings.sampler,
            uint32_t(window_.width), uint32_t(window_.filmWidth),
            uint32_t(window_.x0),    uint32_t(window_.y0)};
}

template <typename Path>
CameraRays WavefrontRenderer<Path>::cameraRays(uint32_t sampleIndex) const {
  CameraRays rays;
  rays.sample = [this, sampleIndex](uint32_t pixel) { return cameraTraceRay(sampleIndex, pixel); };
  if (!camera_.hasLens() && !cameraMotion_) {
    rays.through = [this](uint32_t pixel, float dx, float dy) {
      const float x = float(pixel % width() + uint32_t(window_.x0)) + dx;
      const float y = float(pixel / width() + uint32_t(window_.y0)) + dy;
      return TraceRay{camera_.origin(), camera_.direction(x, y), 0, kInfinity};
    };
    rays.view = viewKey_;
  }
  return rays;
}

template <typename Path>
FrameStats WavefrontRenderer<Path>::renderFrame(int frame, FrameBuffer& frameBuffer,
                                                const ProgressCallback& progress) {
  return renderPixels(frame, 0, pixelCount(), frameBuffer, progress);
}

template <typename Path>
FrameStats WavefrontRenderer<Path>::renderPixels(int frame, uint32_t firstPixel, uint32_t lastPixel,
                                                 FrameBuffer& frameBuffer,
                                                 const ProgressCallback& progress) {
  FrameStats stats;
  stats.frame = frame;
  auto frameStart = Clock::now();
  const double cpuStart = processCpuSeconds();
  FERRY_CHECK_LE(firstPixel, lastPixel);
  FERRY_CHECK_LE(lastPixel, pixelCount());
  // Light paths add to any pixel from any thread.
  if (shading_.lightPaths()) frameBuffer.setAtomicAdds(true);
  frameBuffer.setSampleClamp(settings_.sampleClamp);
  frameBuffer.setAovs(settings_.aovs);
  stats.times.generate += secondsSince(frameStart);  // (the frame buffer, sized at the first)
  const uint32_t spp = uint32_t(settings_.samplesPerPixel), groups = settings_.dataGroups;
  for (int s = 0; s < settings_.samplesPerPixel; ++s) {
    const uint32_t sampleIndex = uint32_t(frame * settings_.samplesPerPixel + s);
    PixelSet set = PixelSet::range(firstPixel, lastPixel);
    if (groups > 1 && spp >= groups) {
      if (sampleIndex % groups != settings_.dataGroup) continue;  // another group's
    } else if (groups > 1) {
      // Fewer samples a frame than groups: the groups g = s (mod spp) take
      // sample s, each every takers-th band of its pixels (every pixel sample
      // once over the groups, and the frame buffers sum exactly: the same
      // image; bands of a few rows spread the sky and the ground alike).
      const uint32_t slot = uint32_t(s), group = settings_.dataGroup;
      if (group % spp != slot) continue;
      const uint32_t takers = (groups - slot + spp - 1) / spp, j = group / spp;
      set = PixelSet::interleaved(firstPixel, lastPixel, kGroupBandRows * width(), takers, j);
    }
    traversal_.setPathTimes(pathTimes(sampleIndex));
    if (traversal_.runsSamples()) {
      // The traversal runs the sample (the overlapped distributed exchange):
      // it calls back for camera paths and shading as rays become ready.
      SampleStages stages(*this, sampleIndex, frameBuffer);
      traversal_.runSample(sampleIndex, set, stages, stats);
    } else if (!chunked()) {
      // Many ranks: the whole image in one wavefront (each bounce is a
      // collective exchange), every stage parallel inside the rank.
      runWavefront(sampleIndex, set, workspace_, frameBuffer, stats);
    } else {
      // One rank: chunks of pixels, each taken from camera ray to last bounce
      // by one thread, so that its queues (paths, kept hits, spawned rays:
      // ~130 bytes a pixel) stay in that core's cache from stage to stage and
      // no thread waits for another at the end of every stage
      // (docs/performance.md, "Why chunks"). Chunks are disjoint pixel ranges
      // and each pixel sample is the same computation, adding to the frame
      // buffer in the same order: the image does not depend on the chunks.
      // (Stage times are then summed over the threads.)
      // (Chunks of a set's runs: a band of a split sample is one or more.)
      const uint32_t chunk = std::max(1u, settings_.chunkPixels);
      std::vector<PixelSet> chunks;
      set.forEachRun([&](uint32_t first, uint32_t last) {
        for (uint32_t b = first; b < last; b = chunks.back().last)
          chunks.push_back(PixelSet::range(b, b + std::min(chunk, last - b)));
      });
      tbb::enumerable_thread_specific<FrameStats> chunkStats;
      tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks.size(), 1), [&](const auto& range) {
        for (size_t c = range.begin(); c != range.end(); ++c) {
          // Isolated: while its stages wait, this thread takes no other chunk,
          // which would reuse its workspace.
          tbb::this_task_arena::isolate([&] {
            runWavefront(sampleIndex, chunks[c], chunkWorkspaces_.local(), frameBuffer,
                         chunkStats.local());
          });
        }
      });
      for (const FrameStats& local : chunkStats)
        stats.merge(local);  // counters and stage times summed
    }
    // Every path and shadow ray of this sample is done on every rank: its
    // totals are complete.
    if (frameBuffer.sampleClamp().active())
      frameBuffer.finishSample(traversal_.sumOverRanks(frameBuffer.sampleSums()));
    if (progress) progress(s + 1, settings_.samplesPerPixel);
  }
  const MediumCounts media = shading_.takeMediumCounts();
  stats.mediumRealCollisions += media.realCollisions;
  stats.mediumNullCollisions += media.nullCollisions;
  stats.mediumMajorantCells += media.majorantCells;
  stats.seconds = secondsSince(frameStart);
  stats.cpuSeconds = processCpuSeconds() - cpuStart;
  stats.busiestRankCpuSeconds = stats.cpuSeconds;
  return stats;
}

template <typename Path>
void WavefrontRenderer<Path>::runWavefront(uint32_t sampleIndex, const PixelSet& set, Workspace& ws,
                                           FrameBuffer& frameBuffer, FrameStats& stats) {
  generateCameraRays(sampleIndex, set, ws, stats);
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
[[gnu::always_inline]] inline void WavefrontRenderer<Path>::makeCameraPath(uint32_t sampleIndex,
                                                                           uint32_t pixel,
                                                                           uint32_t px, uint32_t py,
                                                                           Path& path) const {
  RandomStream random(RandomKey{shading_.randomPixel(pixel), sampleIndex, 0, settings_.seed},
                      settings_.sampler);
  // The film's pixel (a crop's image is offset in it), then the jitter.
  float x = float(px + uint32_t(window_.x0)) + random(RandomDim::PixelJitterX);
  float y = float(py + uint32_t(window_.y0)) + random(RandomDim::PixelJitterY);
  Vec3f origin = camera_.origin(), direction;
  if (camera_.hasLens())
    camera_.ray(x, y, {random(RandomDim::LensU), random(RandomDim::LensV)}, origin, direction);
  else
    direction = camera_.planePoint(x, y);  // makeRay's encoding normalizes it
  if (cameraMotion_) {                     // where the camera is at this path's time
    const Affine3f moved = cameraMotion_->at(clock_.u(pixel, sampleIndex)) * cameraStartInverse_;
    origin = moved.transformPoint(origin);
    direction = moved.transformVector(direction);
  }
  makeRay(path, origin, direction, kInfinity, Vec3f(1), pixel, kPathAfterSpecular);
  if (shading_.cameraMedium() != kNoMedium) setPathMedium(path, shading_.cameraMedium());
}

template <typename Path>
TraceRay WavefrontRenderer<Path>::cameraTraceRay(uint32_t sampleIndex, uint32_t pixel) const {
  Path p;
  makeCameraPath(sampleIndex, pixel, pixel % width(), pixel / width(), p);
  return TraceRay{p.origin, p.dir(), 0, kInfinity};
}

template <typename Path>
size_t WavefrontRenderer<Path>::appendLightPaths(uint32_t sampleIndex,
                                                 std::span<const uint32_t> pixels,
                                                 PathQueue<Path>& out) const {
  if (!shading_.lightPaths()) return 0;
  // Made in place, then compacted in order (an emitter sample may fail).
  const size_t first = out.size();
  out.resize(first + pixels.size());
  size_t made = first;
  for (uint32_t pixel : pixels)
    if (shading_.makeLightPath(pixel, sampleIndex, out[made])) ++made;
  out.resize(made);
  return made - first;
}

template <typename Path>
void WavefrontRenderer<Path>::makeCameraPaths(uint32_t sampleIndex,
                                              std::span<const uint32_t> pixels, Path* out) const {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels.size(), 2048), [&](const auto& range) {
    for (size_t i = range.begin(); i != range.end(); ++i)
      makeCameraPath(sampleIndex, pixels[i], pixels[i] % width(), pixels[i] / width(), out[i]);
  });
}

// What a traversal that runs whole samples calls back: the renderer's camera
// paths and its shading stage (on the whole-image workspace, whose queues
// are swapped in and out, not copied).
template <typename Path>
class WavefrontRenderer<Path>::SampleStages final : public SampleShading<Path> {
 public:
  SampleStages(WavefrontRenderer& renderer, uint32_t sampleIndex, FrameBuffer& frameBuffer)
      : renderer_(renderer),
        sampleIndex_(sampleIndex),
        frameBuffer_(frameBuffer),
        cameraRays_(renderer.cameraRays(sampleIndex)) {}

  const CameraRays& cameraRays() const override { return cameraRays_; }
  void cameraPaths(std::span<const uint32_t> pixels, PathQueue<Path>& out,
                   FrameStats& stats) override {
    auto start = Clock::now();
    const size_t first = out.size();
    out.resize(first + pixels.size());
    renderer_.makeCameraPaths(sampleIndex_, pixels, out.data() + first);
    stats.cameraPaths += pixels.size();
    stats.lightPaths += renderer_.appendLightPaths(sampleIndex_, pixels, out);
    stats.times.generate += secondsSince(start);
  }
  void shade(uint32_t bounce, RayQueues<Path>& ready, std::vector<TraceHit>& hits,
             RayQueues<Path>& next, FrameStats& stats) override {
    Workspace& ws = renderer_.workspace_;
    std::swap(ws.rays, ready);
    std::swap(ws.hits, hits);
    renderer_.shade(ws, sampleIndex_, bounce, frameBuffer_, stats);
    std::swap(ws.rays, ready);
    std::swap(ws.hits, hits);
    std::swap(ws.next, next);
  }

 private:
  WavefrontRenderer& renderer_;
  uint32_t sampleIndex_;
  FrameBuffer& frameBuffer_;
  CameraRays cameraRays_;
};

template <typename Path>
void WavefrontRenderer<Path>::generateCameraRays(uint32_t sampleIndex, const PixelSet& set,
                                                 Workspace& ws, FrameStats& stats) {
  PathQueue<Path>& rays = ws.rays.paths;
  ws.rays.shadowRays.clear();
  auto start = Clock::now();
  const uint32_t width = this->width();
  auto cameraRay = [&](uint32_t pixel, uint32_t px, uint32_t py, Path& p) {
    makeCameraPath(sampleIndex, pixel, px, py, p);
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
  double collectives = 0;  // seconds of the owners' collectives, counted elsewhere
  if (chunked()) {
    // Every pixel's path is this rank's, and this chunk this thread's:
    // straight into the queue, in pixel order.
    rays.resize(set.size());
    size_t next = 0;
    set.forEachRun([&](uint32_t first, uint32_t last) {
      forPixels(first, last, [&](uint32_t pixel, uint32_t px, uint32_t py) {
        cameraRay(pixel, px, py, rays[next++]);
      });
    });
    stats.cameraPaths += rays.size();
    if (shading_.lightPaths()) {
      set.list(ws.primaryPixels);
      stats.lightPaths += appendLightPaths(sampleIndex, ws.primaryPixels, rays);
    }
  } else {
    // Many ranks: the traversal says which pixels' paths are this rank's
    // (proxy-guided, one collective), then their camera rays go into the
    // queue in pixel order.
    // (The owners' collectives count as wait and exchange, not as generate.)
    const double before = stats.times.wait + stats.times.exchange;
    traversal_.primaryPixels(set, cameraRays(sampleIndex), ws.primaryPixels, stats);
    collectives = stats.times.wait + stats.times.exchange - before;
    const std::vector<uint32_t>& mine = ws.primaryPixels;
    rays.resize(mine.size());
    makeCameraPaths(sampleIndex, mine, rays.data());
    stats.cameraPaths += rays.size();
    // This rank's pixels' light paths too: each index on exactly one rank.
    stats.lightPaths += appendLightPaths(sampleIndex, mine, rays);
  }
  stats.times.generate += secondsSince(start) - collectives;
}

template <typename Path>
void WavefrontRenderer<Path>::shade(Workspace& ws, uint32_t sampleIndex, uint32_t bounce,
                                    FrameBuffer& frameBuffer, FrameStats& stats) {
  auto start = Clock::now();
  addUnoccludedLight(ws.rays.shadowRays, frameBuffer);
  shadePaths(ws, sampleIndex, bounce, frameBuffer, stats);
  stats.times.shade += secondsSince(start);
}

template <typename Path>
void WavefrontRenderer<Path>::addUnoccludedLight(const PathQueue<Path>& shadowRays,
                                                 FrameBuffer& frameBuffer) const {
  auto addRange = [&](size_t begin, size_t end) {
    for (size_t i = begin; i != end; ++i) {
      const Path& ray = shadowRays[i];
      uint32_t pixel;
      if (!ray.has(kPathOccluded) && shading_.shadowRayPixel(ray, pixel)) {
        if (ray.has(kPathLight))
          frameBuffer.addSplat(pixel, ray.weight());
        else
          frameBuffer.add(pixel, ray.weight());
      }
    }
  };
  if (chunked()) {
    addRange(0, shadowRays.size());
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, shadowRays.size(), kBlock),
                      [&](const auto& range) { addRange(range.begin(), range.end()); });
  }
}

template <typename Path>
void WavefrontRenderer<Path>::shadePaths(Workspace& ws, uint32_t sampleIndex, uint32_t bounce,
                                         FrameBuffer& frameBuffer, FrameStats& stats) {
  const size_t n = ws.rays.paths.size();
  FERRY_CHECK_EQ(ws.hits.size(), n);
  // Each path makes at most one continuation and one shadow ray.
  RayQueues<Path>& next = ws.next;
  ShadeCounts total;
  if (chunked()) {
    // One thread has this wavefront: new rays go straight into the next
    // queues, in the same order as the blocks would give.
    next.paths.resize(n);
    next.shadowRays.resize(n);
    total = shadePathRange(ws, 0, n, sampleIndex, bounce, frameBuffer, next.paths.data(),
                           next.shadowRays.data());
    next.paths.resize(total.continuations);
    next.shadowRays.resize(total.shadowRays);
  } else {
    const size_t blocks = (n + kBlock - 1) / kBlock;
    ws.staging.paths.resize(n);
    ws.staging.shadowRays.resize(n);
    ws.pathCounts.assign(blocks, 0);
    ws.shadowCounts.assign(blocks, 0);
    std::atomic<uint64_t> retraced{0}, retraceMisses{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const auto& range) {
      uint64_t localRetraced = 0, localMisses = 0;
      for (size_t b = range.begin(); b != range.end(); ++b) {
        const size_t begin = b * kBlock, end = std::min(n, begin + kBlock);
        const ShadeCounts counts =
            shadePathRange(ws, begin, end, sampleIndex, bounce, frameBuffer,
                           ws.staging.paths.data() + begin, ws.staging.shadowRays.data() + begin);
        ws.pathCounts[b] = counts.continuations;
        ws.shadowCounts[b] = counts.shadowRays;
        localRetraced += counts.retraced;
        localMisses += counts.retraceMisses;
      }
      retraced += localRetraced;
      retraceMisses += localMisses;
    });
    concatenateBlocks(ws.staging.paths, kBlock, ws.pathCounts, next.paths);
    concatenateBlocks(ws.staging.shadowRays, kBlock, ws.shadowCounts, next.shadowRays);
    total.retraced = retraced;
    total.retraceMisses = retraceMisses;
  }
  stats.continuationRays += next.paths.size();
  stats.shadowRays += next.shadowRays.size();
  stats.retraces += total.retraced;
  stats.retraceMisses += total.retraceMisses;
}

// A batch of re-trace queries (a few hundred keep the arrays in cache): the
// paths that need one, densely, and for each path of the batch where its
// answer is.
template <typename Path>
struct WavefrontRenderer<Path>::RetraceBatch {
  static constexpr size_t kCapacity = 256;
  static constexpr uint16_t kKept = 0xffff;  // no re-trace: the kept hit (or none)
  RetraceRay queries[kCapacity];
  TraceHit found[kCapacity];
  uint16_t slot[kCapacity];  // path i's hit is found[slot[i]], or kKept
  size_t retraced = 0;

  // Path i's hit: re-traced, or the one kept.
  const TraceHit& hitOf(size_t i, const TraceHit& kept) const {
    return retraced && slot[i] != kKept ? found[slot[i]] : kept;
  }
};

template <typename Path>
typename WavefrontRenderer<Path>::ShadeCounts WavefrontRenderer<Path>::shadePathRange(
    const Workspace& ws, size_t begin, size_t end, uint32_t sampleIndex, uint32_t bounce,
    FrameBuffer& frameBuffer, Path* continuations, Path* shadowRays) const {
  const PathQueue<Path>& paths = ws.rays.paths;
  const std::vector<TraceHit>& kept = ws.hits;
  // One rank traced every ray itself and kept every hit: nothing to re-trace
  // unless asked to (--retrace all).
  const bool mayRetrace = settings_.retraceAll || !chunked();
  ShadeCounts counts;
  RetraceBatch batch;
  for (size_t first = begin; first < end; first += RetraceBatch::kCapacity) {
    const size_t m = std::min(RetraceBatch::kCapacity, end - first);
    if (mayRetrace)
      counts.retraced += retraceBatch(&paths[first], &kept[first], m, sampleIndex, batch);
    for (size_t i = 0; i < m; ++i) {
      const Path& path = paths[first + i];
      const TraceHit& hit = batch.hitOf(i, kept[first + i]);
      if (path.hasHit() && !hit.valid()) {
        ++counts.retraceMisses;  // the re-trace lost the hit (counted: never seen in tests)
        continue;
      }
      const auto spawned =
          shading_.shadePath(path, hit, sampleIndex, bounce, frameBuffer,
                             continuations[counts.continuations], shadowRays[counts.shadowRays]);
      counts.continuations += spawned.continuation;
      counts.shadowRays += spawned.shadowRay;
    }
  }
  return counts;
}

template <typename Path>
size_t WavefrontRenderer<Path>::retraceBatch(const Path* paths, const TraceHit* kept, size_t count,
                                             uint32_t sampleIndex, RetraceBatch& batch) const {
  const PathTimes times = pathTimes(sampleIndex);
  size_t needed = 0;
  for (size_t i = 0; i < count; ++i) {
    const Path& p = paths[i];
    const bool retrace = p.hasHit() && (settings_.retraceAll || !kept[i].valid());
    batch.slot[i] = retrace ? uint16_t(needed) : RetraceBatch::kKept;
    if (retrace) batch.queries[needed++] = {p.origin, p.dir(), p.tmax, times.of(p.pixel())};
  }
  if (needed) geometry_.retrace(std::span(batch.queries, needed), std::span(batch.found, needed));
  batch.retraced = needed;
  return needed;
}

template class WavefrontRenderer<Path8>;
template class WavefrontRenderer<Path64>;
template class WavefrontRenderer<PathReplay>;
template class WavefrontRenderer<PathProbe>;

}  // namespace ferry
