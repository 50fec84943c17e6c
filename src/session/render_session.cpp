#include "session/render_session.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <iterator>
#include <numeric>
#include <span>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "compositing/compositor.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/fault_injection.h"
#include "core/hash64.h"
#include "core/process_memory.h"
#include "distributed/distributed_traversal.h"
#include "distributed/proxy_bvh.h"
#include "io/checkpoints/checkpoint_file.h"
#include "io/parts/part_directory.h"
#include "io/scene_loader.h"
#include "partition/partition.h"
#include "partition/ray_sampler.h"
#include "path/path.h"
#include "render/lights.h"
#include "render/wavefront_renderer.h"
#include "trace/embree_backend.h"

namespace ferry {

// Everything this rank holds once set up. Built in place and never moved: the
// trace structures refer to the scene.
struct RenderSession::Rank {
  std::unique_ptr<tbb::global_control> threadLimit;
  Scene scene;
  Partition partition;  // its proxies move into `proxies` when the first run needs them
  std::unique_ptr<const ProxyBvh> proxies;
  std::string partitionerName;
  std::vector<int32_t> owned;
  std::unique_ptr<TraceBackend> geometry;
  int64_t embreeBytes = 0, embreePeakBytes = 0;
  std::unique_ptr<LightSampler> lights;
  SceneSummary summary;  // of the whole scene, before releasing what this rank does not own
  MemoryCost ownedEstimate;
  SetupTimes setup;
  Clock::time_point lapStart = processStart();  // where the next interval of `setup` begins
  bool firstPixel = false;                      // setup complete (run() reached its first frame)

  Rank(const SessionSettings& settings, const Communicator& comm);
  double proxyBytes() const { return proxies ? double(proxies->bytes()) : 0.0; }
  // The one place the session names the trace backend: this rank's trace
  // structures over its instances, and what Embree holds for them.
  void buildTraceStructures(Instancing instancing);
  // Ends the interval since the last lap as `field` of `setup` (until the first pixel).
  void lap(double SetupTimes::*field) {
    if (firstPixel) return;
    const Clock::time_point now = Clock::now();
    setup.*field = std::chrono::duration<double>(now - lapStart).count();
    lapStart = now;
  }
  // Called just before the first frame's camera rays: ends the set-up.
  void reachFirstPixel() {
    lap(&SetupTimes::renderer);
    if (firstPixel) return;
    setup.firstPixel = std::chrono::duration<double>(lapStart - processStart()).count();
    firstPixel = true;
  }
};

RenderSession::Rank::Rank(const SessionSettings& settings, const Communicator& comm) {
  if (settings.threads > 0)
    threadLimit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, settings.threads);
  lap(&SetupTimes::start);
  if (isPartDirectory(settings.scene)) {
    // A part directory: this rank reads only its own part and the shared data.
    RankPart part = loadRankPart(settings.scene, comm.rank(), comm.size());
    scene = std::move(part.scene);
    scene.view(settings.render.view);
    summary = summaryFromJson(part.manifest.summary);
    partition = std::move(part.partition);
    partitionerName = part.manifest.partitioner;
    scene.filmScale = part.manifest.filmScale;
    scene.filmCrop = part.manifest.filmCrop;
    scene.integrator = part.manifest.integrator;
    scene.integratorMaxDepth = part.manifest.integratorMaxDepth;
    owned.resize(scene.instances.size());
    std::iota(owned.begin(), owned.end(), 0);
    ownedEstimate = ownedMemory(scene, owned);
    lap(&SetupTimes::load);
    lights = std::make_unique<LightSampler>(part.lights);
    lap(&SetupTimes::lights);
  } else {
    scene = loadScene(settings.scene, settings.load);
    scene.view(settings.render.view);  // fail on an unknown view before building anything
    summary = summarize(scene);
    lap(&SetupTimes::load);
    // Light data is small and needed everywhere: take it from the scene as
    // given, before the partitioner rewrites it and ranks release geometry.
    lights = std::make_unique<LightSampler>(scene);
    lap(&SetupTimes::lights);
    const PartitionerOptions options = partitionerOptions(settings, comm.size());
    partition = partitionScene(scene, comm.size(), withRaySample(scene, options));
    partitionerName = options.name;
    owned = partition.instancesOf(comm.rank());
    scene.releaseAllBut(owned);
    // Hand the freed geometry back to the system, so resident memory shows what the rank holds.
    malloc_trim(0);
    ownedEstimate = ownedMemory(scene, owned);
    lap(&SetupTimes::partition);
  }
  maybeInjectFailure("load", comm.rank());
  buildTraceStructures(settings.instancing);
}

void RenderSession::Rank::buildTraceStructures(Instancing instancing) {
  geometry = makeEmbreeBackend(scene, owned, instancing);
  embreeBytes = geometry->bytes().now;
  embreePeakBytes = geometry->bytes().peak;
  lap(&SetupTimes::build);
}

namespace {

// Sums every counter over ranks (seconds: the slowest rank; CPU seconds: the sum).
FrameStats sumOverRanks(const Communicator& comm, const FrameStats& mine) {
  FrameStats local = mine;
  local.perBounce.resize(size_t(comm.max(double(mine.perBounce.size()))));
  const std::vector<uint64_t> counters = local.counterValues();
  std::vector<double> times = local.stageTimeValues();
  times.push_back(mine.cpuSeconds);
  FrameStats out;
  out.frame = mine.frame;
  out.setCounterValues(comm.sum(std::span<const uint64_t>(counters)));
  std::vector<double> summed = comm.sum(std::span<const double>(times));
  out.cpuSeconds = summed.back();
  summed.pop_back();
  out.setStageTimeValues(summed);
  out.seconds = comm.max(mine.seconds);
  return out;
}

// The sum of every rank's frame buffer times `scale`, as `pixels` asks, on
// rank 0 (collective). Adds the bytes this rank sent to `bytesSent`.
FrameImage composite(const Communicator& comm, const FrameBuffer& frameBuffer, float scale,
                     FrameSink::Pixels pixels, const ToneMapping& toneMapping,
                     uint64_t& bytesSent) {
  FrameImage image;
  image.width = frameBuffer.width();
  image.height = frameBuffer.height();
  if (pixels == FrameSink::Pixels::ToneMapped)
    image.rgba = compositeToneMapped(comm, frameBuffer, scale, toneMapping, bytesSent);
  else
    image.linear = compositeLinear(comm, frameBuffer, scale, bytesSent);
  return image;
}

template <typename Path>
std::string layoutName() {
  if constexpr (Path::kReplay)
    return "replay";
  else
    return sizeof(typename Path::Mask) == 1 ? "mask8" : "mask64";
}

}  // namespace

void checkRankCount(int ranks, PathLayout layout) {
  if (ranks > kMaxRanks)
    throw InputError(fmt::format("{} ranks: Ferry supports up to {} ranks", ranks, kMaxRanks));
  if (layout == PathLayout::Mask && ranks > 64)
    throw InputError(fmt::format(
        "--path-layout mask: {} ranks do not fit a 64-bit mask (use replay or auto)", ranks));
}

RenderSession::RenderSession(const SessionSettings& settings, const Communicator& comm)
    : settings_(settings), comm_(comm) {
  FERRY_CHECK_GE(settings.render.frames, 1);
  FERRY_CHECK_GE(settings.render.samplesPerPixel, 1);
  checkRankCount(comm.size(), settings.pathLayout);
  settings_.render.retraceAll = settings.retrace == Retrace::All;
  rank_ = std::make_unique<Rank>(settings_, comm_);
  settings_.render.lightPaths =
      settings_.lightPaths.value_or(integratorWantsLightPaths(rank_->scene.integrator));
}

RenderSession::~RenderSession() = default;

std::pair<uint64_t, std::string> RenderSession::imageIdentity() const {
  const RenderSettings& r = settings_.render;
  // The scene as its summary counts it (what it is made of, whatever the
  // ranks), and every setting that changes a pixel; not the rank count,
  // partitioner, exchange or threads, which do not. "key=value" fields, so
  // that a mismatch can name the ones that differ.
  const std::string summary = rank_->summary.toJson().dump();
  const CameraView& v = r.camera ? *r.camera : rank_->scene.view(r.view);
  const std::string description =
      fmt::format(
          "scene={} (content {}); size={}x{}; spp={}; max-depth={}; light-strategy={}; seed={}; "
          "view={} from "
          "({}, {}, {}) at ({}, {}, {}) up ({}, {}, {}) fov {}",
          settings_.scene, hashToHex(hash64(summary.data(), summary.size())), r.width, r.height,
          r.samplesPerPixel, r.maxDepth, lightStrategyName(r.lightStrategy), r.seed, v.name,
          v.from.x, v.from.y, v.from.z, v.at.x, v.at.y, v.at.z, v.up.x, v.up.y, v.up.z, v.fovY) +
      (r.lightPaths ? "; light-paths=on" : "") +
      (r.crop.whole()
           ? std::string()
           : fmt::format("; crop={},{},{},{}", r.crop.x0, r.crop.x1, r.crop.y0, r.crop.y1));
  return {hash64(description.data(), description.size()), description};
}

namespace {

// The "key=value" fields of two identity descriptions that differ, as
// "key: A in the checkpoint, B here".
std::string differingFields(const std::string& theirs, const std::string& ours) {
  auto fields = [](const std::string& text) {
    std::vector<std::pair<std::string, std::string>> out;
    size_t start = 0;
    while (start < text.size()) {
      size_t end = text.find("; ", start);
      if (end == std::string::npos) end = text.size();
      const std::string field = text.substr(start, end - start);
      const size_t eq = field.find('=');
      out.push_back({field.substr(0, eq), eq == std::string::npos ? "" : field.substr(eq + 1)});
      start = end + 2;
    }
    return out;
  };
  const auto a = fields(theirs), b = fields(ours);
  std::string out;
  for (const auto& [key, value] : b) {
    auto it =
        std::find_if(a.begin(), a.end(), [&key = key](const auto& f) { return f.first == key; });
    const std::string there = it == a.end() ? "(none)" : it->second;
    if (there == value) continue;
    if (!out.empty()) out += "; ";
    out += fmt::format("{}: {} in the checkpoint, {} here", key, there, value);
  }
  return out.empty() ? "the settings that shape the image differ" : out;
}

}  // namespace

void RenderSession::resumeFrom(const std::string& path) {
  auto checkpoint = std::make_unique<Checkpoint>(readCheckpoint(path));
  const auto [identity, description] = imageIdentity();
  if (checkpoint->identity != identity)
    throw InputError(fmt::format("{}: this checkpoint is of another render ({})", path,
                                 differingFields(checkpoint->description, description)));
  if (checkpoint->frames >= settings_.render.frames)
    throw InputError(
        fmt::format("{}: the checkpoint holds {} frames already; --frames {} asks "
                    "for no more (ask for more frames to continue)",
                    path, checkpoint->frames, settings_.render.frames));
  resume_ = std::move(checkpoint);
}

void RenderSession::setImageSize(int width, int height) {
  settings_.render.width = width;
  settings_.render.height = height;
}

void RenderSession::setCrop(const CropWindow& crop) {
  settings_.render.crop = crop;
}

void RenderSession::setMaxDepth(int maxDepth) {
  FERRY_CHECK_GE(maxDepth, 0);
  settings_.render.maxDepth = maxDepth;
}

void RenderSession::setView(const std::string& view, const std::optional<CameraView>& camera) {
  if (!camera) rank_->scene.view(view);  // an unknown name fails here, before any collective
  settings_.render.view = view;
  settings_.render.camera = camera;
}

const Scene& RenderSession::scene() const {
  return rank_->scene;
}
const SceneSummary& RenderSession::summary() const {
  return rank_->summary;
}
const std::string& RenderSession::partitionerName() const {
  return rank_->partitionerName;
}
const SetupTimes& RenderSession::setupTimes() const {
  return rank_->setup;
}

SessionReport RenderSession::run(FrameSink& sink, const SessionProgress& progress) {
  // The layout: masks while they fit (8 then 64 ranks), else replay (or as forced).
  const int ranks = comm_.size();
  if (settings_.pathLayout == PathLayout::Replay ||
      (settings_.pathLayout == PathLayout::Auto && ranks > 64))
    return runWithLayout<PathReplay>(sink, progress);
  if (ranks <= 8) return runWithLayout<Path8>(sink, progress);
  return runWithLayout<Path64>(sink, progress);
}

template <typename Path>
std::unique_ptr<RayTraversal<Path>> RenderSession::makeTraversal(
    DistributedTraversal<Path>** distributed) {
  Rank& rank = *rank_;
  // One rank needs no forwarding machinery (no proxy queries, no collectives per round).
  if (comm_.size() == 1) return std::make_unique<LocalTraversal<Path>>(*rank.geometry);
  if (!rank.proxies) {
    // The tree consumes the proxies: a rank holds each proxy once.
    rank.proxies = std::make_unique<const ProxyBvh>(std::move(rank.partition.proxies), comm_.rank(),
                                                    std::move(rank.partition.proxyShapes),
                                                    std::move(rank.partition.proxyPlacements));
    malloc_trim(0);  // the builder's temporaries go back to the system
  }
  auto d = std::make_unique<DistributedTraversal<Path>>(
      comm_, *rank.geometry, rank.partition, *rank.proxies, settings_.forwarding,
      settings_.exchange, settings_.render.chunkPixels);
  if (distributed) *distributed = d.get();
  return d;
}

namespace {

// What turns the frame buffer's sum into the image: the average of the
// samples so far, times the Film's scale (pbrt).
float imageScale(const Scene& scene, int frames, int samplesPerPixel) {
  return scene.filmScale / float(frames * samplesPerPixel);
}

// Every rank's set-up times, on every rank (one collective).
std::vector<SetupTimes> rankSetupTimes(const Communicator& comm, const SetupTimes& times) {
  const size_t n = size_t(comm.size()), fields = std::size(kSetupTimes);
  std::vector<double> mine(n * fields, 0.0);
  for (size_t k = 0; k < fields; ++k)
    mine[size_t(comm.rank()) * fields + k] = times.*kSetupTimes[k].member;
  const std::vector<double> all = comm.sum(std::span<const double>(mine));
  std::vector<SetupTimes> out(n);
  for (size_t r = 0; r < n; ++r)
    for (size_t k = 0; k < fields; ++k) out[r].*kSetupTimes[k].member = all[r * fields + k];
  return out;
}

// Every rank's memory now, on every rank (one collective).
RankMemory rankMemory(const Communicator& comm, double estimated, double embree, double embreePeak,
                      double proxies) {
  const ProcessMemory memory = readProcessMemory();
  const size_t n = size_t(comm.size()), me = size_t(comm.rank());
  std::vector<double> mine(6 * n, 0.0);
  const double values[6] = {estimated,
                            embree,
                            embreePeak,
                            proxies,
                            double(memory.residentBytes),
                            double(memory.peakResidentBytes)};
  for (size_t k = 0; k < 6; ++k) mine[k * n + me] = values[k];
  const std::vector<double> all = comm.sum(std::span<const double>(mine));
  auto column = [&](size_t k) {
    return std::vector<double>(all.begin() + ptrdiff_t(k * n),
                               all.begin() + ptrdiff_t((k + 1) * n));
  };
  return {column(0), column(1), column(2), column(3), column(4), column(5)};
}

}  // namespace

void ViewChange::applyTo(CameraView& camera, RenderSettings& settings) const {
  if (flags & kCamera) {
    camera.from = Vec3f(from[0], from[1], from[2]);
    camera.at = Vec3f(at[0], at[1], at[2]);
    camera.up = Vec3f(up[0], up[1], up[2]);
    camera.fovY = fovY;
  }
  if (flags & kSettings) {
    settings.width = width;
    settings.height = height;
    settings.samplesPerPixel = samplesPerPixel;
    settings.maxDepth = maxDepth;
  }
  if (flags & kExposure) settings.toneMapping.exposure = exposure;
}

void RenderSession::runInteractive(InteractiveControl* control, uint64_t maxFrames,
                                   double sliceSeconds) {
  FERRY_CHECK(!comm_.isRoot() || control);
  const int ranks = comm_.size();
  if (settings_.pathLayout == PathLayout::Replay ||
      (settings_.pathLayout == PathLayout::Auto && ranks > 64))
    return interactiveWithLayout<PathReplay>(control, maxFrames, sliceSeconds);
  if (ranks <= 8) return interactiveWithLayout<Path8>(control, maxFrames, sliceSeconds);
  interactiveWithLayout<Path64>(control, maxFrames, sliceSeconds);
}

template <typename Path>
void RenderSession::interactiveWithLayout(InteractiveControl* control, uint64_t maxFrames,
                                          double sliceSeconds) {
  Rank& rank = *rank_;
  rank.lap(&SetupTimes::agree);
  std::unique_ptr<RayTraversal<Path>> traversal = makeTraversal<Path>(nullptr);
  rank.lap(&SetupTimes::proxies);
  RenderSettings render = settings_.render;
  render.frames = 1;
  if (!render.camera) render.camera = rank.scene.view(render.view);
  auto renderer = std::make_unique<WavefrontRenderer<Path>>(rank.scene, *rank.geometry,
                                                            *rank.lights, *traversal, render);
  // Reused from frame to frame; made anew only when the image size changes.
  FrameBuffer frameBuffer(render.imageWidth(), render.imageHeight());
  int accumulated = 0;
  uint64_t compositeBytes = 0, abandoned = 0;
  double lastFrameSeconds = 0;  // the slowest rank's, of the last whole frame
  for (uint64_t frames = 0; maxFrames == 0 || frames < maxFrames; ++frames) {
    ViewChange change;
    if (comm_.isRoot()) change = control->takeChange();
    comm_.broadcast(change);
    if (change.flags & ViewChange::kQuit) break;
    const int oldWidth = render.imageWidth(), oldHeight = render.imageHeight();
    change.applyTo(*render.camera, render);
    if (change.flags & (ViewChange::kCamera | ViewChange::kSettings)) {
      if (render.imageWidth() != oldWidth || render.imageHeight() != oldHeight)
        frameBuffer = FrameBuffer(render.imageWidth(), render.imageHeight());
      else
        frameBuffer.clear();
      accumulated = 0;
      renderer = std::make_unique<WavefrontRenderer<Path>>(rank.scene, *rank.geometry, *rank.lights,
                                                           *traversal, render);
    }
    // A long frame goes through in slices of about `sliceSeconds` (judged by
    // the last frame's time, the same on every rank), with rank 0's word in
    // between on whether a change is waiting: a camera move abandons the
    // rest of the frame instead of waiting for it (what was added is cleared
    // with the accumulation the change restarts). Each slice costs a
    // distributed render the overlap at its end, so short frames stay whole.
    const uint32_t pixels = uint32_t(render.imageWidth()) * uint32_t(render.imageHeight());
    const double bySeconds = sliceSeconds > 0 ? lastFrameSeconds / sliceSeconds : 64;
    const uint32_t slices = std::clamp<uint32_t>(
        std::min<uint32_t>(uint32_t(std::min(bySeconds, 64.0)), pixels / 4096), 1, 64);
    FrameStats mine;
    bool abandon = false;
    rank.reachFirstPixel();
    const auto frameStart = Clock::now();
    for (uint32_t slice = 0; slice < slices && !abandon; ++slice) {
      const uint32_t first = uint32_t(uint64_t(pixels) * slice / slices);
      const uint32_t last = uint32_t(uint64_t(pixels) * (slice + 1) / slices);
      mine.merge(renderer->renderPixels(accumulated, first, last, frameBuffer));
      if (slice + 1 < slices) {
        abandon = comm_.isRoot() && control->restartPending();
        comm_.broadcast(abandon);
      }
    }
    if (abandon) {
      ++abandoned;
      continue;
    }
    mine.frame = accumulated;
    mine.seconds = secondsSince(frameStart);
    InteractiveFrame frame;
    frame.abandoned = std::exchange(abandoned, 0);
    frame.stats = sumOverRanks(comm_, mine);
    lastFrameSeconds = frame.stats.seconds;
    ++accumulated;
    const auto start = Clock::now();
    frame.image =
        composite(comm_, frameBuffer, imageScale(rank.scene, accumulated, render.samplesPerPixel),
                  FrameSink::Pixels::ToneMapped, render.toneMapping, compositeBytes);
    frame.stats.times.composite = comm_.max(secondsSince(start));
    frame.memory = rankMemory(comm_, double(rank.ownedEstimate.total()), double(rank.embreeBytes),
                              double(rank.embreePeakBytes), rank.proxyBytes());
    if (!comm_.isRoot()) continue;
    frame.accumulated = accumulated;
    frame.camera = *render.camera;
    frame.settings = render;
    frame.image.frame = accumulated - 1;
    try {
      control->publish(frame);
    } catch (const std::exception& e) {
      comm_.abortAll(e.what());  // the other ranks are in the next frame's collectives
    }
  }
}

template <typename Path>
SessionReport RenderSession::runWithLayout(FrameSink& sink, const SessionProgress& progress) {
  Rank& rank = *rank_;
  // A resumed render starts after the checkpoint's frames, with its image on
  // rank 0 (the other ranks add to zero: the composite is the same sum).
  int firstFrame = resume_ ? resume_->frames : 0;
  comm_.broadcast(firstFrame);
  rank.lap(&SetupTimes::agree);
  const RenderSettings& render = settings_.render;
  DistributedTraversal<Path>* distributed = nullptr;
  std::unique_ptr<RayTraversal<Path>> traversal = makeTraversal<Path>(&distributed);
  rank.lap(&SetupTimes::proxies);
  WavefrontRenderer<Path> renderer(rank.scene, *rank.geometry, *rank.lights, *traversal, render);
  FrameBuffer frameBuffer(render.imageWidth(), render.imageHeight());
  const FrameSink::Frames frames = sink.frames();
  const FrameSink::Pixels pixels = sink.pixels();
  SessionReport report;
  RenderStats& stats = report.stats;
  uint64_t compositeBytes = 0;        // this rank's, over every composite
  int lastFrame = render.frames - 1;  // earlier if the time limit says so
  auto compositeAfter = [&](int frame, double& seconds) {
    auto start = Clock::now();
    const float scale = imageScale(rank.scene, frame + 1, render.samplesPerPixel);
    FrameImage image =
        composite(comm_, frameBuffer, scale, pixels, render.toneMapping, compositeBytes);
    image.frame = frame;
    image.last = frame == lastFrame;
    seconds = comm_.max(secondsSince(start));
    stats.frames[size_t(frame - firstFrame)].times.composite += seconds;
    return image;
  };

  if (resume_) {
    FERRY_CHECK_EQ(resume_->sums.size(), frameBuffer.fixedSum().size());
    frameBuffer.fixedSum() = std::move(resume_->sums);
    resume_.reset();
  }
  const auto runStart = Clock::now();
  auto writeCheckpointAfter = [&](int frame) {
    uint64_t sent = 0;
    std::vector<int64_t> sums = compositeFixed(comm_, frameBuffer, sent);
    compositeBytes += sent;
    if (!comm_.isRoot()) return;
    Checkpoint c;
    std::tie(c.identity, c.description) = imageIdentity();
    c.width = render.imageWidth();
    c.height = render.imageHeight();
    c.frames = frame + 1;
    c.samplesPerPixel = render.samplesPerPixel;
    c.sums = std::move(sums);
    try {
      writeCheckpoint(settings_.checkpoint, c);
    } catch (const std::exception& e) {
      comm_.abortAll(e.what());  // the other ranks are in the next collective
    }
  };

  for (int frame = firstFrame; frame <= lastFrame; ++frame) {
    double secondsLeft = -1;
    if (settings_.timeLimitSeconds > 0)
      secondsLeft = std::max(0.0, settings_.timeLimitSeconds - secondsSince(runStart));
    rank.reachFirstPixel();
    FrameStats mine = renderer.renderFrame(frame, frameBuffer, [&](int done, int total) {
      if (progress) progress({frame, done, total, false, secondsLeft});
    });
    stats.frames.push_back(sumOverRanks(comm_, mine));
    // The frame that crosses the time limit is the last (every rank agrees:
    // the slowest rank's clock decides).
    if (settings_.timeLimitSeconds > 0 &&
        comm_.max(secondsSince(runStart)) >= settings_.timeLimitSeconds)
      lastFrame = frame;
    if (!settings_.checkpoint.empty() &&
        (frame == lastFrame || (frame + 1 - firstFrame) % settings_.checkpointEvery == 0))
      writeCheckpointAfter(frame);
    if (frames == FrameSink::Frames::Every && frame < lastFrame) {
      double seconds = 0;
      FrameImage image = compositeAfter(frame, seconds);
      // The other ranks go on into the next frame's collectives: a failure
      // here must end them too.
      if (comm_.isRoot()) try {
          sink.receive(image);
        } catch (const std::exception& e) {
          comm_.abortAll(e.what());
        }
    }
  }

  if (progress) progress({lastFrame, render.samplesPerPixel, render.samplesPerPixel, true});

  FrameImage image = compositeAfter(lastFrame, report.compositeSeconds);
  report.compositeBytes = comm_.sum(compositeBytes);
  report.memory = rankMemory(comm_, double(rank.ownedEstimate.total()), double(rank.embreeBytes),
                             double(rank.embreePeakBytes), rank.proxyBytes());
  report.setup = rankSetupTimes(comm_, rank.setup);
  report.raysReceived = comm_.sum(distributed ? distributed->received() : 0);
  report.revisits = comm_.sum(distributed ? distributed->revisits() : 0);
  report.pathLayout = layoutName<Path>();
  report.pathBytes = sizeof(Path);
  // After the last collective: what the sink throws ends only this rank.
  if (comm_.isRoot()) sink.receive(image);
  return report;
}

}  // namespace ferry
