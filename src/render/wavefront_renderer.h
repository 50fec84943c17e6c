// The path tracer every rank runs, as a wavefront: queues of compact paths,
// one method per stage, the render loop reading like the algorithm.
//
// One wavefront is one sample of every pixel this rank generates (on one
// rank: of a chunk of pixels, each chunk on one thread, see renderFrame). Per
// bounce: traverse (local trace, and forwarding when distributed), then one
// shading pass (add unoccluded shadow rays to the frame buffer; shade paths:
// re-trace, emission, one light sample, one continuation). A pixel sample has at most two live
// rays (its path and its shadow ray), so queues are bounded by the image size.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "render/camera.h"
#include "render/frame_buffer.h"
#include "render/lights.h"
#include "render/ray_traversal.h"
#include "render/render_stats.h"
#include "render/surface.h"

namespace ferry {

struct Scene;

struct RenderSettings {
  int width = 1280;
  int height = 720;
  int samplesPerPixel = 1;  // per frame
  int frames = 1;
  int maxDepth = 5;  // scattering events; 1 = direct lighting only
  uint32_t seed = 1;
  std::string view;  // empty: the scene's first view
  // Shading re-traces every path it shades (the paper, whose compact path
  // carries no hit) instead of only those whose hit was found on another
  // rank. The image is the same either way (tests check it); only the speed differs.
  bool retraceAll = false;
  // One rank: pixels that go through the wavefront together, on one thread
  // (WavefrontRenderer::renderFrame). Any value gives the same image.
  uint32_t chunkPixels = 8192;
  ToneMapping toneMapping;
};

// Progress of one frame: (wavefront finished, wavefronts in the frame).
using ProgressCallback = std::function<void(int done, int total)>;

template <typename Path>
class WavefrontRenderer {
 public:
  WavefrontRenderer(const Scene& scene, const TraceBackend& geometry, const LightSampler& lights,
                    RayTraversal<Path>& traversal, const RenderSettings& settings);

  // Adds frame `frame`'s samples to `frameBuffer` (this rank's partial sum).
  FrameStats renderFrame(int frame, FrameBuffer& frameBuffer,
                         const ProgressCallback& progress = {});

 private:
  // A wavefront's queues and scratch, reused from wavefront to wavefront (no
  // allocation per bounce).
  struct Workspace {
    PathQueue<Path> rays, next, staging;
    std::vector<TraceHit> hits;
    std::vector<uint32_t> blockCounts;
  };
  // One rank (the traversal keeps every primary): the image goes through in
  // chunks, each wavefront on one thread, whose stages then loop instead of
  // splitting into parallel blocks. Many ranks: one whole-image wavefront.
  bool chunked() const { return traversal_.keepsAllPrimaries(); }
  // One sample of pixels [first, last) from camera rays to the last bounce.
  void runWavefront(uint32_t sampleIndex, uint32_t first, uint32_t last, Workspace& ws,
                    FrameBuffer& frameBuffer, FrameStats& stats);
  // The camera rays of pixels [first, last) for this sample, into ws.rays.
  void generateCameraRays(uint32_t sampleIndex, uint32_t first, uint32_t last, Workspace& ws,
                          FrameStats& stats);
  // Adds each unoccluded shadow ray's contribution and shades every other
  // path (re-tracing those without a valid hit); reads ws.rays and ws.hits,
  // writes the next wavefront (continuations and shadow rays) to ws.next.
  // One pass: within a wavefront no pixel is written twice (a pixel sample's
  // shadow ray comes from a non-delta vertex, so its path does not count
  // emission there).
  void shade(Workspace& ws, uint32_t sampleIndex, uint32_t bounce, FrameBuffer& frameBuffer,
             FrameStats& stats);
  // Shades path i given its hit (invalid: escaped or re-trace missed); writes
  // its continuation and shadow ray, in that order, to out; returns how many.
  int shadeOne(const Path& path, const TraceHit& hit, uint32_t sampleIndex, uint32_t bounce,
               FrameBuffer& frameBuffer, Path* out, uint64_t& misses) const;

  const Scene& scene_;
  const TraceBackend& geometry_;  // shading's re-traces
  const LightSampler& lights_;
  RayTraversal<Path>& traversal_;
  RenderSettings settings_;
  Camera camera_;
  SurfaceTable surfaces_;  // for reconstructSurface
  Workspace workspace_;    // many ranks: the one whole-image wavefront
  tbb::enumerable_thread_specific<Workspace> chunkWorkspaces_;  // one rank: one per thread
};

}  // namespace ferry
