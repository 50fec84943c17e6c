// A render on every rank of a communicator, from the scene to the images:
// the frame loop above the wavefront renderer.
//
// Construction sets this rank up: loads the scene (or this rank's part of a
// part directory), partitions it, keeps this rank's instances, builds the
// trace structures and the light sampler. run() picks the traversal (local
// on one rank, distributed by forwarding on many) and the path layout,
// renders the frames, sums the stats over ranks, composites the ranks'
// partial frame buffers and hands the images to a FrameSink.
//
// Both are collective: every rank of `comm` constructs a session with the
// same settings and calls run() with the same kind of sink. The session
// prints nothing; progress goes through a callback.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "comm/communicator.h"
#include "distributed/distributed_traversal.h"
#include "render/camera.h"
#include "render/render_stats.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"
#include "session/frame_sink.h"
#include "session/partitioned_scene.h"
#include "session/session_settings.h"
#include "shapes/unstructured_volume.h"
#include "shapes/volume_brick.h"

namespace ferry {

struct Checkpoint;

// Per-rank memory, each vector indexed by rank (the same on every rank).
struct RankMemory {
  std::vector<double> estimated;     // the memory model's estimate of what the rank holds
  std::vector<double> embree;        // bytes Embree holds for the rank's structures
  std::vector<double> embreePeak;    // and its peak while building them
  std::vector<double> proxies;       // the proxy tree (every rank holds every proxy)
  std::vector<double> resident;      // resident set after rendering
  std::vector<double> residentPeak;  // peak resident set
};

// Where a rank's time to its first pixel went, in seconds: consecutive
// intervals from the process's start (core/clock.h) to the first frame's
// first camera ray (the renderer's first act in a frame), so they add up to
// firstPixel. Named once, in kSetupTimes (the JSON, the sum over ranks and
// the summary walk it).
struct SetupTimes {
  double start = 0;       // process start to the session: MPI's start-up, flags, settings
  double load = 0;        // reading the scene, or this rank's part and the shared data
  double partition = 0;   // on the fly: the ray sample, partitioning, dropping what others own
  double lights = 0;      // the light sampler
  double build = 0;       // the trace structures (Embree's BVHs)
  double agree = 0;       // from set-up to run(): the command's agreement on set-up errors (this
                          // rank waiting for the slowest), the image sink, a checkpoint read
  double proxies = 0;     // the traversal: on many ranks the proxy BVH and owner masks
  double renderer = 0;    // the renderer (camera, light tables) and the frame buffer
  double ready = 0;       // waiting for the slowest rank, so that the first frame starts together
  double firstPixel = 0;  // all of the above: process start to the first camera ray
};
inline constexpr StatsField<SetupTimes, double> kSetupTimes[] = {
    {nullptr, "start", &SetupTimes::start},
    {nullptr, "load", &SetupTimes::load},
    {nullptr, "partition", &SetupTimes::partition},
    {nullptr, "lights", &SetupTimes::lights},
    {nullptr, "build", &SetupTimes::build},
    {nullptr, "agree", &SetupTimes::agree},
    {nullptr, "proxies", &SetupTimes::proxies},
    {nullptr, "renderer", &SetupTimes::renderer},
    {nullptr, "ready", &SetupTimes::ready},
    {nullptr, "first_pixel", &SetupTimes::firstPixel},
};

// What a session measured, the same on every rank.
struct SessionReport {
  RenderStats stats;  // per frame, summed over ranks (seconds: the slowest rank)
  RankMemory memory;
  std::vector<SetupTimes> setup;  // per rank: its first run()'s set-up (run() again: the same)
  uint64_t raysReceived = 0;      // counted by receivers (stats count senders)
  uint64_t revisits = 0;          // rays that came back to a rank they had visited (must be 0)
  uint64_t compositeBytes = 0;    // sent by direct send over all composites and ranks
  double compositeSeconds = 0;    // the final image's composite, slowest rank
  std::string pathLayout;         // mask8, mask64 or replay
  size_t pathBytes = 0;           // sizeof the path on the wire
};

// How far run() is: called after every sample of every frame, then once
// with `rendered` set when the last frame is done (compositing and the final
// image follow).
struct RenderProgress {
  int frame = 0;            // the frame being rendered (0-based)
  int samplesDone = 0;      // of that frame
  int samplesPerFrame = 0;  // wavefronts per frame
  bool rendered = false;
  double secondsLeft = -1;  // of a time limit (-1: none)
};
using SessionProgress = std::function<void(const RenderProgress&)>;

// A change an interactive viewer asks for, applied by every rank at the next
// frame boundary (rank 0's is broadcast: plain data). Any change but the
// exposure restarts the accumulation.
struct ViewChange {
  enum : uint32_t {
    kCamera = 1,
    kSettings = 2,
    kExposure = 4,
    kQuit = 8,
    kVolume = 16,
    kFocus = 32,
    kDisplay = 64,  // what the picture shows: the colour or an AOV (no restart)
    kField = 128    // render another array of the VTK data: the scene is read again
  };
  uint32_t flags = 0;
  float from[3], at[3], up[3];
  float fovY;
  float lensRadius, focalDistance;  // the thin lens (CameraView)
  // kFocus: focus on the nearest surface under this point of the image
  // (fractions of its width and height, y down), found over every rank's
  // geometry after the other changes; the focal distance stays where none is.
  float focusX, focusY;
  int32_t width, height, samplesPerPixel, maxDepth;
  float exposure;
  int32_t display;  // kDisplay: an Aov's value, -1 the colour (ToneMapping::aov)
  float volumeOpacity;
  int32_t colorMap;  // into colorMapNames(); -1: each volume's own colours
  int32_t field;     // kField: into Scene::volumeFields
  // The change made to a camera and settings (only the parts its flags name).
  void applyTo(CameraView& camera, RenderSettings& settings) const;
};

// What an interactive render reports after every frame (rank 0).
struct InteractiveFrame {
  uint64_t abandoned = 0;   // frames abandoned for a change since the last published one
  FrameImage image;         // the accumulated image, tone mapped
  int accumulated = 0;      // frames in it since the last change
  FrameStats stats;         // this frame, summed over ranks (seconds: the slowest rank)
  RankMemory memory;        // now, per rank
  CameraView camera;        // what the image shows
  RenderSettings settings;  // size, samples per frame, depth, exposure
};

// How an interactive render ended: asked to quit or its frames done, or
// asked to render another array of the scene's VTK data (ViewChange::kField):
// then the caller reads the scene again with that array and goes on from
// `camera` and `render`, where the changes so far left them.
struct InteractiveEnd {
  int32_t field = -1;   // >= 0: read again rendering Scene::volumeFields[field]
  uint64_t frames = 0;  // frames begun (a frame limit spans the readings)
  CameraView camera;
  RenderSettings render;
};

// Drives an interactive render (the viewer, rank 0): asked for changes
// before every frame, told every frame.
class InteractiveControl {
 public:
  virtual ~InteractiveControl() = default;
  // What changed since the last call (and forget it).
  virtual ViewChange takeChange() = 0;
  // Whether a change is waiting that restarts the accumulation (or quits):
  // then the frame being rendered is abandoned at its next slice.
  virtual bool restartPending() = 0;
  virtual void publish(const InteractiveFrame& frame) = 0;
};

// Throws InputError if a session cannot run on `ranks` ranks with `layout`
// (more than kMaxRanks, or masks asked for above 64 ranks). The session
// checks it when made; a command line may check it first.
void checkRankCount(int ranks, PathLayout layout);

class RenderSession {
 public:
  // Sets this rank up; throws InputError for what the user can fix (scene,
  // view, rank count, path layout). Every rank usually meets the same error:
  // the caller agrees on failure (Communicator::agreeOnFailure).
  RenderSession(const SessionSettings& settings, const Communicator& comm);
  // The same for a scene in memory, the whole of it on every rank, instead
  // of settings.scene (which then only names it): partitioned on the fly as
  // a loaded one. Throws InputError if the scene is not valid (Scene::validate).
  RenderSession(Scene scene, const SessionSettings& settings, const Communicator& comm);
  // This rank's part, already made (distributedPiece: data that is spread
  // over the ranks as given); settings.scene only names it.
  RenderSession(PartitionedScene part, const SessionSettings& settings, const Communicator& comm);
  ~RenderSession();
  RenderSession(const RenderSession&) = delete;
  RenderSession& operator=(const RenderSession&) = delete;

  // Renders every frame, composites what the sink asks for on every rank and
  // gives it to rank 0's sink. What this throws comes from the middle of
  // collective work, so the caller ends every rank (Communicator::abortAll)
  // -- except what rank 0's sink throws for the final image, which comes
  // after the last collective, when the other ranks have returned. (What the
  // sink throws for an earlier image ends every rank here.)
  SessionReport run(FrameSink& sink, const SessionProgress& progress = {});

  // Renders frame after frame, accumulating, until rank 0's control says
  // quit (or `maxFrames` frames, if > 0): before each frame rank 0 asks its
  // control for changes and broadcasts them; after each frame every rank
  // composites and rank 0 publishes. Collective; `control` is used on rank 0
  // only (may be null elsewhere). A frame longer than `sliceSeconds` goes
  // through in slices, between which a waiting change abandons it (0: as
  // many slices as the image allows, for tests).
  // Returns how it ended (InteractiveEnd).
  InteractiveEnd runInteractive(InteractiveControl* control, uint64_t maxFrames = 0,
                                double sliceSeconds = 0.2);

  // Before run(): renders at this size instead (a scene's own, pbrt's Film).
  void setImageSize(int width, int height);
  // Before run(): renders only this part of the image (pbrt's cropwindow).
  void setCrop(const CropWindow& crop);
  // Before run(): clamps each camera sample (pbrt's Film maxsampleluminance,
  // maxcomponentvalue: render/frame_buffer.h).
  void setSampleClamp(const SampleClamp& clamp);
  // Before run(): samples per pixel in each frame, and frames.
  void setSamples(int samplesPerPixel, int frames);
  // Before run(): the maximum path depth (RenderSettings::maxDepth), a
  // scene's own (pbrt's Integrator maxdepth).
  void setMaxDepth(int maxDepth);
  // Before run(): renders this view instead (a named one, or `camera` if
  // given, with its own lens: the lens settings then no longer apply);
  // throws InputError for an unknown name. run() may be called again
  // after it (the bandwidth predictor renders several views from one load).
  void setView(const std::string& view, const std::optional<CameraView>& camera);
  // Before run(): restyles every volume drawn through a transfer function
  // (whole or in bricks, on every rank) by `look`, from its loaded transfer
  // function; InputError for an unknown colour map or a bad opacity.
  void setVolumeLook(const VolumeLook& look);
  // Rank 0, before run() (not collective): continues the render held in a
  // checkpoint (io/checkpoints/checkpoint_file.h): run() starts after its frames, with
  // its image. Throws InputError naming the file if it cannot be read, or
  // was made with another scene or other settings that shape the image
  // (size, samples per frame, depth, seed, view), or holds every frame asked for.
  void resumeFrom(const std::string& path);
  // What a checkpoint must match: a hash of the scene and the settings that
  // shape the image, and those settings in words (the same on every rank).
  std::pair<uint64_t, std::string> imageIdentity() const;
  const SessionSettings& settings() const { return settings_; }
  const Communicator& communicator() const { return comm_; }
  // The worker threads this rank runs (settings().threads, or what
  // workerThreads chose for 0).
  int threads() const;
  // The ranks that hold the scene together: this rank's data group, or all.
  const Communicator& group() const { return groupComm_ ? *groupComm_ : comm_; }
  // This rank's scene (its part, after partitioning): for its film settings.
  const Scene& scene() const;
  // The whole scene, summarized before this rank released what it does not own.
  const SceneSummary& summary() const;
  // Whether this rank holds volumes drawn through a transfer function (whose
  // look RenderSettings::volumeLook changes): media, or bricks (which other
  // ranks may hold instead: ask every rank).
  bool hasTransferFunctionVolumes() const;
  // The partitioner that made the parts: a part directory's (from its
  // manifest) or the one run on the fly.
  const std::string& partitionerName() const;
  // This rank's set-up so far: up to the first pixel once run() has begun
  // its first frame.
  const SetupTimes& setupTimes() const;

 private:
  struct Rank;

  RenderSession(const SessionSettings& settings, const Communicator& comm, Scene* given,
                PartitionedScene* part);
  // Restyles every transfer-function volume from its loaded transfer
  // function; throws InputError for a look that cannot be (unknown map).
  void applyVolumeLook(const VolumeLook& look);
  class Frames;  // the frame loop's frames, renderer and frame buffer
  template <typename Path>
  class FramesFor;
  class FramePolicy;  // what a run does around the frame loop: batch or interactive
  class BatchFrames;
  class InteractiveFrames;
  // The frame loop: batch and interactive renders alike.
  template <typename Path>
  void renderFrames(FramePolicy& policy, const RenderSettings& render);
  // Calls f.template operator()<Path>() with the path layout for this rank count.
  template <typename F>
  void withPathLayout(F&& f);
  // The traversal this session's ranks use (local on one rank); `distributed`
  // set when it is the distributed one.
  template <typename Path>
  std::unique_ptr<RayTraversal<Path>> makeTraversal(DistributedTraversal<Path>** distributed);

  SessionSettings settings_;
  const Communicator& comm_;
  std::unique_ptr<Communicator> groupComm_;  // data groups: this rank's
  std::unique_ptr<Rank> rank_;
  std::unique_ptr<Checkpoint> resume_;  // rank 0, from resumeFrom()
  // Per medium, its transfer function as loaded (null: none).
  std::vector<std::shared_ptr<const TransferFunction>> loadedTransfers_;
  // This rank's volume bricks drawn through a transfer function, by volume
  // as loaded (applyVolumeLook restyles them from it).
  struct LoadedBricks {
    const VolumeBrick::Volume* madeFrom;  // what the bricks shared when made (a key only)
    std::shared_ptr<const VolumeBrick::Volume> loaded;
    std::vector<VolumeBrick*> bricks;
  };
  std::vector<LoadedBricks> loadedBricks_;
  // This rank's unstructured volumes and their transfer functions as loaded.
  std::vector<std::pair<UnstructuredVolume*, std::shared_ptr<const TransferFunction>>> loadedCells_;
};

}  // namespace ferry
