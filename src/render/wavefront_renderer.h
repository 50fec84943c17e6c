// The path tracer every rank runs, as a wavefront: queues of compact paths,
// one method per stage, the render loop reading like the algorithm.
//
// One wavefront is one sample of every pixel this rank generates (on one
// rank: of a chunk of pixels, see pixelChunk). Per bounce: traverse (local
// trace, and forwarding when distributed), then one shading pass (add
// unoccluded shadow rays to the frame buffer; shade paths: re-trace, emission,
// one light sample, one continuation). A pixel sample has at most two live
// rays (its path and its shadow ray), so queues are bounded by the image size.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/frame_buffer.h"
#include "render/lights.h"
#include "render/ray_traversal.h"
#include "render/render_stats.h"

namespace ferry {

struct Scene;

struct RenderSettings {
  int width = 1280;
  int height = 720;
  int samplesPerPixel = 1;  // per frame
  int frames = 1;
  int maxDepth = 5;         // scattering events; 1 = direct lighting only
  uint32_t seed = 1;
  std::string view;         // empty: the scene's first view
  // Shading re-traces every path it shades (the paper, whose compact path
  // carries no hit) instead of only those whose hit was found on another
  // rank. The image is the same either way (tests check it); only the speed differs.
  bool retraceAll = false;
  // One rank: pixels per worker thread that go through the wavefront together
  // (WavefrontRenderer::pixelChunk). Any value gives the same image.
  uint32_t chunkPixelsPerThread = 8192;
  ToneMapping toneMapping;
};

// Progress of one frame: (wavefront finished, wavefronts in the frame).
using ProgressCallback = std::function<void(int done, int total)>;

template <typename Path>
class WavefrontRenderer {
 public:
  WavefrontRenderer(const Scene& scene, const LocalGeometry& geometry, const LightSampler& lights,
                    RayTraversal<Path>& traversal, const RenderSettings& settings);

  // Adds frame `frame`'s samples to `frameBuffer` (this rank's partial sum).
  FrameStats renderFrame(int frame, FrameBuffer& frameBuffer, const ProgressCallback& progress = {});

 private:
  // How many pixels go through the wavefront together. Many ranks: all of
  // them (every wavefront is a collective exchange). One rank: chunks of
  // 8 K pixels per worker thread, so that a chunk's queues (paths, kept hits,
  // spawned rays: ~130 bytes a pixel) stay in cache from stage to stage
  // instead of streaming the whole image through memory at every stage
  // (docs/performance.md). The image does not depend on it: each pixel sample
  // is the same computation, and its contributions reach the frame buffer in
  // the same order (sample by sample, bounce by bounce).
  uint32_t pixelChunk() const;
  // The camera rays of pixels [begin, end) for this sample.
  void generateCameraRays(uint32_t sampleIndex, uint32_t begin, uint32_t end, PathQueue<Path>& rays,
                          FrameStats& stats);
  // Adds each unoccluded shadow ray's contribution and shades every other
  // path (re-tracing those without a valid hits[i]); writes the next
  // wavefront (continuations and shadow rays) to `next`. One pass: within a
  // wavefront no pixel is written twice (a pixel sample's shadow ray comes
  // from a non-delta vertex, so its path does not count emission there).
  void shade(const PathQueue<Path>& rays, const std::vector<TraceHit>& hits, uint32_t sampleIndex,
             uint32_t bounce, FrameBuffer& frameBuffer, PathQueue<Path>& next, FrameStats& stats);
  // Shades path i given its hit (invalid: escaped or re-trace missed); writes
  // its continuation and shadow ray, in that order, to out; returns how many.
  int shadeOne(const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
               FrameBuffer& frameBuffer, Path* out, uint64_t& misses) const;

  const Scene& scene_;
  const LocalGeometry& geometry_;
  const LightSampler& lights_;
  RayTraversal<Path>& traversal_;
  RenderSettings settings_;
  Camera camera_;
  std::vector<Affine3f> instanceInverses_;  // for reconstructSurface
  // Queues and scratch reused from wavefront to wavefront (no allocation per bounce).
  PathQueue<Path> rays_, next_, staging_;
  std::vector<TraceHit> hits_;
  std::vector<uint32_t> blockCounts_;
};

}  // namespace ferry
