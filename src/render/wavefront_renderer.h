// The path tracer every rank runs, as a wavefront: typed queues of compact
// paths (path/path.h: RayQueues, paths and shadow rays), one method per
// stage, the render loop reading like the algorithm.
//
// One wavefront is one sample of every pixel this rank generates (on one
// rank: of a chunk of pixels, each chunk on one thread, see renderFrame). Per
// bounce: traverse (local trace, and forwarding when distributed), then
// shade: shadow rays add their light where nothing was in the way; paths are
// shaded (re-trace where the hit is not kept, then the steps of
// render/path_shading.h: emission, one continuation, one light sample), each
// kind of new ray into its own queue. A pixel sample has at most two live rays
// (its path and its shadow ray), so queues are bounded by the image size.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "media/volume_look.h"
#include "render/camera.h"
#include "render/frame_buffer.h"
#include "render/lights.h"
#include "render/path_shading.h"
#include "render/ray_traversal.h"
#include "render/render_stats.h"
#include "scene/scene.h"

namespace ferry {

struct Scene;

struct RenderSettings {
  int width = 1280;  // the film; the image is the part `crop` selects
  int height = 720;
  CropWindow crop;  // --crop, pbrt's cropwindow
  FilmWindow window() const { return filmWindow(width, height, crop); }
  // The image rendered: the film, or the crop window's part of it.
  int imageWidth() const { return window().width; }
  int imageHeight() const { return window().height; }
  int samplesPerPixel = 1;  // per frame
  int frames = 1;
  int maxDepth = 5;  // scattering events; 1 = direct lighting only
  uint32_t seed = 1;
  // How a path vertex's random numbers are drawn (--sampler, core/random.h).
  SamplerKind sampler = SamplerKind::Sobol;
  std::string view;  // empty: the scene's first view
  // A camera given outright (--look-from/--look-at, the viewer): used instead of `view`.
  std::optional<CameraView> camera;
  // pbrt's film clamp of each camera sample (Film "maxsampleluminance",
  // "maxcomponentvalue"; --max-sample-luminance): render/frame_buffer.h.
  SampleClamp sampleClamp;
  // --aov: the first-surface features summed beside the colour
  // (render/aov.h); empty: none, and the frame buffer holds none.
  std::vector<Aov> aovs;
  // --lens-radius, --focal-distance: the thin lens of whichever camera is used.
  std::optional<float> lensRadius, focalDistance;
  // The camera rendered: `camera`, else the scene's view `view`, with the lens set above.
  CameraView cameraIn(const Scene& scene) const;
  // Shading re-traces every path it shades (the paper, whose compact path
  // carries no hit) instead of only those whose hit was found on another
  // rank. The image is the same either way (tests check it); only the speed differs.
  bool retraceAll = false;
  // Which samples find emitters and the sky (render/path_shading.h): MIS of
  // light and BSDF samples (--mis on), light samples only (--mis off).
  LightStrategy lightStrategy = LightStrategy::Mis;
  // How MIS weighs its strategies (--mis-heuristic): the same image in
  // expectation, but for pbrt-v3's mirrored emitters (docs/path-tracer.md).
  MisHeuristic misHeuristic = MisHeuristic::Power;
  // How light samples choose among the lights (--light-choice; the session
  // builds the LightSampler with it).
  LightChoice lightChoice = LightChoice::Near;
  // Light paths (render/path_shading.h): one per pixel sample, connected to
  // the camera, weighed by MIS against the camera path's two strategies.
  // Needs MIS and an emissive triangle (else there are none).
  bool lightPaths = false;
  // How shadow rays through participating media estimate their
  // transmittance (--transmittance): ratio tracking, or delta tracking (a baseline).
  TransmittanceEstimator transmittance = TransmittanceEstimator::Ratio;
  // Where light entering a subsurface material leaves (--subsurface): pbrt's
  // BSSRDF by probes (the session then takes the probe path layout), or a
  // random walk.
  SubsurfaceMethod subsurface = SubsurfaceMethod::Probes;
  // Volumes drawn through a transfer function: opacity scale and colour map
  // (--volume-opacity, --color-map, the viewer); the session applies it.
  VolumeLook volumeLook;
  // One rank: pixels that go through the wavefront together, on one thread
  // (WavefrontRenderer::renderFrame). Any value gives the same image.
  uint32_t chunkPixels = 8192;
  ToneMapping toneMapping;
  // Data groups (the session sets them): this rank renders only the samples
  // whose index modulo dataGroups is dataGroup (with fewer samples a frame
  // than groups, the groups that take a sample split its pixels); the groups' frame buffers
  // add up to the image.
  uint32_t dataGroups = 1;
  uint32_t dataGroup = 0;
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
  // The same for pixels [first, last) only (the viewer renders a frame in
  // slices, so that a camera change can abandon the rest). Collective when
  // distributed: every rank passes the same range.
  FrameStats renderPixels(int frame, uint32_t first, uint32_t last, FrameBuffer& frameBuffer,
                          const ProgressCallback& progress = {});

 private:
  // A wavefront's queues and scratch, reused from wavefront to wavefront (no
  // allocation per bounce).
  struct Workspace {
    RayQueues<Path> rays, next, staging;
    std::vector<TraceHit> hits;  // per rays.paths entry: its kept hit (invalid: re-trace)
    std::vector<uint32_t> pathCounts, shadowCounts;  // per block: rays it wrote to staging
    std::vector<uint32_t> primaryPixels;  // many ranks: pixels whose camera paths are this rank's
  };
  struct RetraceBatch;
  class SampleStages;  // SampleShading for a traversal that runs whole samples
  // What shading a range of paths made and counted.
  struct ShadeCounts {
    uint32_t continuations = 0, shadowRays = 0;
    uint64_t retraced = 0, retraceMisses = 0;
  };
  // One rank (the traversal keeps every primary): the image goes through in
  // chunks, each wavefront on one thread, whose stages then loop instead of
  // splitting into parallel blocks. Many ranks: one whole-image wavefront.
  bool chunked() const { return traversal_.keepsAllPrimaries(); }
  // When data groups split a sample's pixels: bands of this many rows each.
  static constexpr uint32_t kGroupBandRows = 4;
  // One sample of the pixels of `set` from camera rays to the last bounce.
  void runWavefront(uint32_t sampleIndex, const PixelSet& set, Workspace& ws,
                    FrameBuffer& frameBuffer, FrameStats& stats);
  // Pixel `pixel`'s (at px, py) camera path for sample `sampleIndex`.
  void makeCameraPath(uint32_t sampleIndex, uint32_t pixel, uint32_t px, uint32_t py,
                      Path& path) const;
  uint32_t width() const { return uint32_t(window_.width); }  // of the image
  uint32_t pixelCount() const { return uint32_t(window_.width) * uint32_t(window_.height); }
  // The camera ray of `pixel`'s path, as the proxy-guided ownership asks it.
  TraceRay cameraTraceRay(uint32_t sampleIndex, uint32_t pixel) const;
  // Sample `sampleIndex`'s camera rays, and this view's, for primaryPixels.
  CameraRays cameraRays(uint32_t sampleIndex) const;
  // The camera paths of `pixels` into out[0, pixels.size()), in parallel.
  void makeCameraPaths(uint32_t sampleIndex, std::span<const uint32_t> pixels, Path* out) const;
  // With light paths: the light paths of `pixels` (one each, same index)
  // appended to `out`, in pixel order; returns how many.
  size_t appendLightPaths(uint32_t sampleIndex, std::span<const uint32_t> pixels,
                          PathQueue<Path>& out) const;
  // The camera rays of the pixels of `set` for this sample, into ws.rays.
  void generateCameraRays(uint32_t sampleIndex, const PixelSet& set, Workspace& ws,
                          FrameStats& stats);
  // Shadow rays add their light, paths are shaded; reads ws.rays and ws.hits,
  // writes the next wavefront to ws.next. Within a wavefront no pixel is
  // written twice (a pixel sample's shadow ray comes from a non-delta vertex,
  // so its path does not count emission there): the two kinds are shaded in
  // any order, and a pixel's sum does not depend on the queue order.
  void shade(Workspace& ws, uint32_t sampleIndex, uint32_t bounce, FrameBuffer& frameBuffer,
             FrameStats& stats);
  // Each unoccluded shadow ray's contribution, to the frame buffer.
  void addUnoccludedLight(const PathQueue<Path>& shadowRays, FrameBuffer& frameBuffer) const;
  // Shades ws.rays.paths: continuations to ws.next.paths, shadow rays to
  // ws.next.shadowRays, each in path order (blocks concatenated in order).
  void shadePaths(Workspace& ws, uint32_t sampleIndex, uint32_t bounce, FrameBuffer& frameBuffer,
                  FrameStats& stats);
  // Shades paths [begin, end) in batches (re-trace, then each path), writing
  // their continuations from `continuations` on and their shadow rays from
  // `shadowRays` on.
  ShadeCounts shadePathRange(const Workspace& ws, size_t begin, size_t end, uint32_t sampleIndex,
                             uint32_t bounce, FrameBuffer& frameBuffer, Path* continuations,
                             Path* shadowRays) const;
  // Re-traces, as one batched query, each of paths[0, count) that hit
  // something whose hit this rank does not keep (every one that hit, with
  // --retrace all); returns how many. The one call shading makes to the trace.
  size_t retraceBatch(const Path* paths, const TraceHit* kept, size_t count, uint32_t sampleIndex,
                      RetraceBatch& batch) const;
  // The motion times of sample `sampleIndex`'s rays (none when nothing moves).
  PathTimes pathTimes(uint32_t sampleIndex) const {
    return moves_ ? PathTimes{&clock_, sampleIndex} : PathTimes{};
  }

  const TraceBackend& geometry_;  // shading's re-traces
  RayTraversal<Path>& traversal_;
  RenderSettings settings_;
  FilmWindow window_;  // the part of the film the image is
  Camera camera_;
  uint64_t viewKey_ = 0;  // CameraRays::view of this camera and window
  MotionClock clock_;     // when rays are (scene/motion.h)
  // A moving camera: its motion, and its start pose's inverse.
  std::shared_ptr<const InstanceMotion> cameraMotion_;
  Affine3f cameraStartInverse_;
  bool moves_ = false;  // whether anything in the scene moves
  PathShading<Path> shading_;
  Workspace workspace_;  // many ranks: the one whole-image wavefront
  tbb::enumerable_thread_specific<Workspace> chunkWorkspaces_;  // one rank: one per thread
};

}  // namespace ferry
