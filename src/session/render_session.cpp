#include "session/render_session.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iterator>
#include <numeric>
#include <span>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "comm/idle_backoff.h"
#include "compositing/compositor.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/fault_injection.h"
#include "core/hash64.h"
#include "core/process_memory.h"
#include "distributed/distributed_traversal.h"
#include "distributed/proxy_bvh.h"
#include "io/checkpoints/checkpoint_file.h"
#include "io/parts/manifest.h"
#include "io/volumes/volume_files.h"
#include "media/volume_look.h"
#include "partition/partition.h"
#include "path/path.h"
#include "render/aov.h"
#include "render/camera.h"
#include "render/lights.h"
#include "render/wavefront_renderer.h"
#include "session/partitioned_scene.h"
#include "shapes/unstructured_volume.h"
#include "shapes/volume_brick.h"
#include "trace/embree_backend.h"

namespace ferry {

// Everything this rank holds once set up. Built in place and never moved: the
// trace structures refer to the scene.
struct RenderSession::Rank {
  int threads = 0;  // worker threads (workerThreads)
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

  // From settings.scene, or from `given` (the whole scene, in memory) when set.
  Rank(const SessionSettings& settings, const Communicator& comm, Scene* given,
       PartitionedScene* part);
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
  // Called just before the first frame's camera rays: ends the set-up, once
  // every rank is there (so that a frame's time is the same span on every
  // rank, and its stage times add up to it).
  void reachFirstPixel(const Communicator& comm) {
    if (firstPixel) return;
    lap(&SetupTimes::renderer);
    // A non-blocking sum waited for with naps, not a barrier: Open MPI's
    // blocking wait spins, and on an oversubscribed machine the ranks still
    // setting up need the cores.
    const SumHandle together = comm.startSum({1});
    std::vector<uint64_t> ranks;
    for (IdleBackoff backoff; !comm.sumDone(together, ranks);) comm.waitForMessage(backoff.next());
    lap(&SetupTimes::ready);
    setup.firstPixel = std::chrono::duration<double>(lapStart - processStart()).count();
    firstPixel = true;
  }
};

namespace {

// This rank's bricks of a "bricks:" manifest as its piece (collective: a
// rank that cannot load its bricks ends every rank with its message).
PartitionedScene loadBrickPieces(const SessionSettings& settings, const Communicator& comm) {
  Scene piece;
  std::string error;
  try {
    piece = loadBrickPiece(settings.scene, comm.rank(), comm.size());  // the look: applyVolumeLook
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (const std::string failure = comm.failureMessage(!error.empty(), error); !failure.empty())
    throw InputError(failure);
  return distributedPiece(std::move(piece), comm);
}

// A .pvtu or .pvti on this rank: its own pieces only, normalised and framed
// by what every rank read (collective, as loadBrickPieces).
std::string lowerExtension(const std::string& spec) {
  std::string extension = std::filesystem::path(spec).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return extension;
}
bool isPiecesSpec(const std::string& spec) {
  const std::string extension = lowerExtension(spec);
  return extension == ".pvtu" || extension == ".pvti";
}
PartitionedScene loadPieces(const SessionSettings& settings, const Communicator& comm) {
  const PieceAgreement agree = [&](const PieceSummary& mine, const std::string& readError) {
    if (const std::string failure = comm.failureMessage(!readError.empty(), readError);
        !failure.empty())
      throw InputError(failure);
    std::vector<double> extremes = {-mine.lo,          mine.hi,           -mine.box.lower.x,
                                    -mine.box.lower.y, -mine.box.lower.z, mine.box.upper.x,
                                    mine.box.upper.y,  mine.box.upper.z,  double(mine.field)};
    for (const VolumeField& f : mine.fields) extremes.insert(extremes.end(), {-f.lo, f.hi});
    const std::vector<double> all = comm.max(std::span<const double>(extremes));
    const uint64_t counts[2] = {mine.cells, mine.skipped};
    const std::vector<uint64_t> sums = comm.sum(std::span<const uint64_t>(counts));
    PieceSummary out;
    out.lo = -all[0];
    out.hi = all[1];
    out.box.lower = Vec3f(float(-all[2]), float(-all[3]), float(-all[4]));
    out.box.upper = Vec3f(float(all[5]), float(all[6]), float(all[7]));
    out.cells = sums[0];
    out.skipped = sums[1];
    out.field = int32_t(all[8]);
    out.fields = mine.fields;
    for (size_t i = 0; i < out.fields.size(); ++i)
      out.fields[i].lo = -all[9 + 2 * i], out.fields[i].hi = all[10 + 2 * i];
    return out;
  };
  // Every rank meets every collective: the agreement's, then this one.
  Scene piece;
  std::string error;
  try {
    piece = lowerExtension(settings.scene) == ".pvti"
                ? loadVtkImagePiecesScene(settings.scene, settings.load.field, comm.rank(),
                                          comm.size(), agree)
                : loadVtkPiecesScene(settings.scene, settings.load.field, comm.rank(), comm.size(),
                                     agree);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (const std::string failure = comm.failureMessage(!error.empty(), error); !failure.empty())
    throw InputError(failure);
  return distributedPiece(std::move(piece), comm);
}

}  // namespace

RenderSession::Rank::Rank(const SessionSettings& settings, const Communicator& comm, Scene* given,
                          PartitionedScene* part) {
  const int cores = tbb::info::default_concurrency();
  threads = workerThreads(settings.threads, cores, comm.ranksOnThisMachine());
  if (threads != cores)
    threadLimit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, threads);
  lap(&SetupTimes::start);
  // A volume already spread in bricks: each rank loads its own, no partitioning.
  PartitionedScene fromBricks;
  if (!part && !given && isBrickManifestSpec(settings.scene)) {
    fromBricks = loadBrickPieces(settings, comm);
    part = &fromBricks;
  } else if (!part && !given && isPiecesSpec(settings.scene)) {
    fromBricks = loadPieces(settings, comm);
    part = &fromBricks;
  }
  PartitionedScene loaded =
      part
          ? std::move(*part)
          : loadPartitionedScene(settings, comm.size(), comm.rank(), given, [&](Scene& whole) {
              whole.view(settings.render.view);  // fail on an unknown view before building anything
              if (settings.volumeBrickVoxels != 0)
                brickVolumes(whole, settings.volumeBrickVoxels);  // the look: applyVolumeLook
              summary = summarize(whole);
              lap(&SetupTimes::load);
              // Light data is small and needed everywhere: take it from the scene
              // as given, before the partitioner rewrites it and ranks release geometry.
              lights = std::make_unique<LightSampler>(whole, settings.render.lightChoice);
              lap(&SetupTimes::lights);
            });
  scene = std::move(loaded.scene);
  partition = std::move(loaded.partition);
  partitionerName = std::move(loaded.partitioner);
  if (const std::optional<Manifest>& manifest = loaded.manifest) {
    // A part directory: this rank read only its own part and the shared data.
    scene.view(settings.render.view);
    summary = summaryFromJson(manifest->summary);
    scene.filmScale = manifest->filmScale;
    scene.filmMaxSampleLuminance = manifest->filmMaxSampleLuminance;
    scene.filmMaxComponentValue = manifest->filmMaxComponentValue;
    scene.filmCrop = manifest->filmCrop;
    scene.integrator = manifest->integrator;
    scene.integratorMaxDepth = manifest->integratorMaxDepth;
    scene.shutterOpen = manifest->shutterOpen, scene.shutterClose = manifest->shutterClose;
    scene.motionStart = manifest->motionStart, scene.motionEnd = manifest->motionEnd;
    owned.resize(scene.instances.size());
    std::iota(owned.begin(), owned.end(), 0);
    ownedEstimate = ownedMemory(scene, owned);
    lap(&SetupTimes::load);
    lights = std::make_unique<LightSampler>(loaded.lights, settings.render.lightChoice);
    lap(&SetupTimes::lights);
  } else {
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

// Sums every counter over ranks (seconds: the slowest rank; CPU seconds: the
// sum, and the busiest rank's).
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
  const std::vector<double> largest = comm.max(std::vector<double>{mine.seconds, mine.cpuSeconds});
  out.seconds = largest[0];
  out.busiestRankCpuSeconds = largest[1];
  return out;
}

// The sum of every rank's frame buffer times `scale`, as `pixels` asks, and
// the AOVs the buffer has (their values with linear pixels only), on rank 0
// (collective). Adds the bytes this rank
// sent to `bytesSent`.
FrameImage composite(const Communicator& comm, const FrameBuffer& frameBuffer, float scale,
                     FrameSink::Pixels pixels, const ToneMapping& toneMapping,
                     uint64_t& bytesSent) {
  FrameImage image;
  image.width = frameBuffer.width();
  image.height = frameBuffer.height();
  const std::vector<Aov>& aovs = frameBuffer.aovs();
  const bool showsAov = pixels == FrameSink::Pixels::ToneMapped && toneMapping.aov >= 0 &&
                        std::find(aovs.begin(), aovs.end(), Aov(toneMapping.aov)) != aovs.end();
  if (showsAov) {
    const std::vector<float> values = compositeAovs(comm, frameBuffer, scale, bytesSent);
    if (comm.isRoot())
      image.rgba = aovPicture(values, aovs, Aov(toneMapping.aov),
                              size_t(image.width) * size_t(image.height));
  } else if (pixels == FrameSink::Pixels::ToneMapped) {
    image.rgba = compositeToneMapped(comm, frameBuffer, scale, toneMapping, bytesSent);
  } else {
    image.linear = compositeLinear(comm, frameBuffer, scale, bytesSent);
  }
  image.aovs = aovs;
  if (pixels == FrameSink::Pixels::Linear && frameBuffer.hasAovs())
    image.aovValues = compositeAovs(comm, frameBuffer, scale, bytesSent);
  return image;
}

template <typename Path>
std::string layoutName() {
  if constexpr (Path::kProbes)
    return "probe";
  else if constexpr (Path::kReplay)
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
        "path-layout mask: {} ranks do not fit a 64-bit mask (use replay or auto)", ranks));
}

RenderSession::RenderSession(const SessionSettings& settings, const Communicator& comm)
    : RenderSession(settings, comm, nullptr, nullptr) {}

RenderSession::RenderSession(Scene scene, const SessionSettings& settings, const Communicator& comm)
    : RenderSession(settings, comm, &scene, nullptr) {}

RenderSession::RenderSession(PartitionedScene part, const SessionSettings& settings,
                             const Communicator& comm)
    : RenderSession(settings, comm, nullptr, &part) {}

RenderSession::RenderSession(const SessionSettings& settings, const Communicator& comm,
                             Scene* given, PartitionedScene* part)
    : settings_(settings), comm_(comm) {
  FERRY_CHECK_GE(settings.render.frames, 1);
  FERRY_CHECK_GE(settings.render.samplesPerPixel, 1);
  checkRankCount(comm.size(), settings.pathLayout);
  if (given) given->validate();
  settings_.render.retraceAll = settings.retrace == Retrace::All;
  if (settings.dataGroups > 1) {
    // Data groups: each holds the whole scene over size / groups ranks and
    // renders every groups-th sample; the frame buffers add up over all ranks.
    const int groups = settings.dataGroups, ranks = comm.size();
    if (ranks % groups != 0)
      throw InputError(fmt::format("{} data groups: {} ranks do not split into groups of one size",
                                   groups, ranks));
    groupComm_ = comm.split(comm.rank() / (ranks / groups));
    settings_.render.dataGroups = uint32_t(groups);
    settings_.render.dataGroup = uint32_t(comm.rank() / (ranks / groups));
  }
  rank_ = std::make_unique<Rank>(settings_, group(), given, part);
  // Light paths do not go through media: a scene with media renders by
  // camera paths alone (their medium rides where light paths keep a ratio).
  // (Volume bricks are spread over ranks: the whole scene's summary counts them.)
  const bool media = rank_->scene.hasMedia() || rank_->summary.volumeBricks > 0;
  if (media && settings_.lightPaths.value_or(false))
    throw InputError(
        fmt::format("light paths were asked for, but scene '{}' has participating media, which "
                    "light paths do not cross; render it without them",
                    rank_->scene.name));
  // Nor do they move: a light path's connection to the camera is keyed by
  // the pixel it lands on, not by the light path's own time.
  const bool moves = rank_->summary.movingInstances > 0 ||
                     std::any_of(rank_->scene.views.begin(), rank_->scene.views.end(),
                                 [](const CameraView& v) { return v.motion != nullptr; });
  if (moves && settings_.lightPaths.value_or(false))
    throw InputError(
        fmt::format("light paths were asked for, but scene '{}' moves (motion blur), which "
                    "light paths do not follow; render it without them",
                    rank_->scene.name));
  settings_.render.lightPaths =
      !media && !moves &&
      settings_.lightPaths.value_or(integratorWantsLightPaths(rank_->scene.integrator));
  for (const Medium& m : rank_->scene.media) loadedTransfers_.push_back(m.transfer);
  // This rank's bricks, by the volume they were made from (the session owns
  // its scene: a given one is moved in).
  for (const Geometry& g : rank_->scene.geometries) {
    const auto* brick = dynamic_cast<const VolumeBrick*>(g.shape.get());
    if (!brick || !brick->volume().transfer) continue;
    auto group = std::find_if(loadedBricks_.begin(), loadedBricks_.end(),
                              [&](const auto& b) { return b.madeFrom == &brick->volume(); });
    if (group == loadedBricks_.end())
      group = loadedBricks_.insert(
          loadedBricks_.end(),
          {&brick->volume(), std::make_shared<const VolumeBrick::Volume>(brick->volume()), {}});
    group->bricks.push_back(const_cast<VolumeBrick*>(brick));
  }
  for (const Geometry& g : rank_->scene.geometries)
    if (const auto* cells = dynamic_cast<const UnstructuredVolume*>(g.shape.get()))
      loadedCells_.push_back({const_cast<UnstructuredVolume*>(cells), cells->transfer()});
  if (!settings_.render.volumeLook.isDefault()) applyVolumeLook(settings_.render.volumeLook);
}

bool RenderSession::hasTransferFunctionVolumes() const {
  return !loadedBricks_.empty() || !loadedCells_.empty() ||
         std::any_of(loadedTransfers_.begin(), loadedTransfers_.end(),
                     [](const auto& t) { return t != nullptr; });
}

void RenderSession::setVolumeLook(const VolumeLook& look) {
  if (!(look.opacity > 0) || !std::isfinite(look.opacity))
    throw InputError(fmt::format("volume opacity {}: expected a positive scale", look.opacity));
  applyVolumeLook(look);
  settings_.render.volumeLook = look;
}

void RenderSession::applyVolumeLook(const VolumeLook& look) {
  // Every rank checks the look the same way (flags and the viewer checked it first).
  const auto restyle = [&look](const TransferFunction& loaded) {
    try {
      return std::make_shared<const TransferFunction>(restyled(loaded, look));
    } catch (const std::invalid_argument& e) {
      throw InputError(
          fmt::format("{} (the colour maps: {})", e.what(), fmt::join(colorMapNames(), ", ")));
    }
  };
  for (size_t i = 0; i < loadedTransfers_.size(); ++i)
    if (loadedTransfers_[i])
      setTransferFunction(rank_->scene.media[i], restyle(*loadedTransfers_[i]));
  for (LoadedBricks& group : loadedBricks_) {
    auto volume = std::make_shared<VolumeBrick::Volume>(*group.loaded);
    volume->transfer = restyle(*group.loaded->transfer);
    for (VolumeBrick* brick : group.bricks) brick->restyle(volume);
  }
  for (const auto& [cells, loaded] : loadedCells_) cells->restyle(restyle(*loaded));
}

RenderSession::~RenderSession() = default;

int RenderSession::threads() const {
  return rank_->threads;
}

std::pair<uint64_t, std::string> RenderSession::imageIdentity() const {
  const RenderSettings& r = settings_.render;
  // The scene as its summary counts it (what it is made of, whatever the
  // ranks), and every setting that changes a pixel; not the rank count,
  // partitioner, exchange or threads, which do not. "key=value" fields, so
  // that a mismatch can name the ones that differ.
  const std::string summary = rank_->summary.toJson().dump();
  const CameraView v = r.cameraIn(rank_->scene);
  const std::string description =
      fmt::format(
          "scene={} (content {}); size={}x{}; spp={}; max-depth={}; light-strategy={}; seed={}; "
          "view={} from "
          "({}, {}, {}) at ({}, {}, {}) up ({}, {}, {}) fov {}",
          settings_.scene, hashToHex(hash64(summary.data(), summary.size())), r.width, r.height,
          r.samplesPerPixel, r.maxDepth, lightStrategyName(r.lightStrategy), r.seed, v.name,
          v.from.x, v.from.y, v.from.z, v.at.x, v.at.y, v.at.z, v.up.x, v.up.y, v.up.z, v.fovY) +
      (v.lensRadius > 0
           ? fmt::format("; lens radius {} focal distance {}", v.lensRadius, v.focalDistance)
           : std::string()) +
      (r.sampleClamp.active()
           ? fmt::format("; sample-clamp={} {}",
                         r.sampleClamp.measure == SampleClamp::Measure::Luminance ? "luminance"
                                                                                  : "component",
                         r.sampleClamp.limit)
           : std::string()) +
      (r.lightPaths ? "; light-paths=on" : "") +
      (r.misHeuristic != MisHeuristic::Power
           ? std::string("; mis-heuristic=") + misHeuristicName(r.misHeuristic)
           : std::string()) +
      (r.lightChoice != LightChoice::Near
           ? std::string("; light-choice=") + lightChoiceName(r.lightChoice)
           : std::string()) +
      (r.transmittance == TransmittanceEstimator::Delta ? "; transmittance=delta" : "") +
      (r.subsurface == SubsurfaceMethod::Walks ? "; subsurface=walk" : "") +
      // Checkpoints from before --sampler drew independent numbers and name no sampler.
      (r.sampler != SamplerKind::Independent ? std::string("; sampler=") + samplerName(r.sampler)
                                             : std::string()) +
      (r.volumeLook.opacity != 1 ? fmt::format("; volume-opacity={}", r.volumeLook.opacity)
                                 : std::string()) +
      (r.volumeLook.colorMap.empty() ? std::string() : "; color-map=" + r.volumeLook.colorMap) +
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
        fmt::format("{}: the checkpoint holds {} frames already; a render of {} frames asks "
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

void RenderSession::setSampleClamp(const SampleClamp& clamp) {
  settings_.render.sampleClamp = clamp;
}

void RenderSession::setSamples(int samplesPerPixel, int frames) {
  FERRY_CHECK_GE(samplesPerPixel, 1);
  FERRY_CHECK_GE(frames, 1);
  settings_.render.samplesPerPixel = samplesPerPixel;
  settings_.render.frames = frames;
}

void RenderSession::setMaxDepth(int maxDepth) {
  FERRY_CHECK_GE(maxDepth, 0);
  settings_.render.maxDepth = maxDepth;
}

void RenderSession::setView(const std::string& view, const std::optional<CameraView>& camera) {
  if (!camera) rank_->scene.view(view);  // an unknown name fails here, before any collective
  settings_.render.view = view;
  settings_.render.camera = camera;
  if (camera) {  // a camera given outright brings its own lens
    settings_.render.lensRadius.reset();
    settings_.render.focalDistance.reset();
  }
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

template <typename Path>
std::unique_ptr<RayTraversal<Path>> RenderSession::makeTraversal(
    DistributedTraversal<Path>** distributed) {
  Rank& rank = *rank_;
  // One rank needs no forwarding machinery (no proxy queries, no collectives per round).
  if (group().size() == 1) return std::make_unique<LocalTraversal<Path>>(*rank.geometry);
  if (!rank.proxies) {
    // The tree consumes the proxies: a rank holds each proxy once.
    rank.proxies = std::make_unique<const ProxyBvh>(
        std::move(rank.partition.proxies), group().rank(), std::move(rank.partition.proxyShapes),
        std::move(rank.partition.proxyPlacements));
    malloc_trim(0);  // the builder's temporaries go back to the system
  }
  auto d = std::make_unique<DistributedTraversal<Path>>(
      group(), *rank.geometry, rank.partition, *rank.proxies, settings_.forwarding,
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
    camera.lensRadius = lensRadius;
    camera.focalDistance = focalDistance;
  }
  if (flags & kSettings) {
    settings.width = width;
    settings.height = height;
    settings.samplesPerPixel = samplesPerPixel;
    settings.maxDepth = maxDepth;
  }
  if (flags & kExposure) settings.toneMapping.exposure = exposure;
  if (flags & kDisplay) settings.toneMapping.aov = display;
  if (flags & kVolume) {
    settings.volumeLook.opacity = volumeOpacity;
    settings.volumeLook.colorMap = colorMap >= 0 && size_t(colorMap) < colorMapNames().size()
                                       ? colorMapNames()[size_t(colorMap)]
                                       : std::string();
  }
}

// The frames of one run, whatever the path layout: the render settings, the
// frame buffer, and the renderer over this rank's traversal (FramesFor).
class RenderSession::Frames {
 public:
  explicit Frames(const RenderSettings& render)
      : render(render), buffer(render.imageWidth(), render.imageHeight()) {}
  virtual ~Frames() = default;
  uint32_t pixels() const { return uint32_t(render.imageWidth()) * uint32_t(render.imageHeight()); }
  // Pixels [first, last) of `frame`, with `progress` (collective when distributed).
  virtual FrameStats renderPixels(uint32_t first, uint32_t last) = 0;
  // A renderer for `render` as it is now (after a change), over the same traversal.
  virtual void restart() = 0;
  virtual uint64_t raysReceived() const = 0;
  virtual uint64_t revisits() const = 0;
  virtual std::string layout() const = 0;
  virtual size_t pathBytes() const = 0;

  RenderSettings render;
  FrameBuffer buffer;
  int frame = 0;              // the frame index the next renderPixels renders
  ProgressCallback progress;  // for the next renderPixels
};

template <typename Path>
class RenderSession::FramesFor final : public RenderSession::Frames {
 public:
  FramesFor(const Scene& scene, const TraceBackend& geometry, const LightSampler& lights,
            std::unique_ptr<RayTraversal<Path>> traversal, DistributedTraversal<Path>* distributed,
            const RenderSettings& render)
      : Frames(render),
        scene_(scene),
        geometry_(geometry),
        lights_(lights),
        traversal_(std::move(traversal)),
        distributed_(distributed) {
    restart();
  }
  FrameStats renderPixels(uint32_t first, uint32_t last) override {
    return renderer_->renderPixels(frame, first, last, buffer, progress);
  }
  void restart() override {
    renderer_ =
        std::make_unique<WavefrontRenderer<Path>>(scene_, geometry_, lights_, *traversal_, render);
  }
  uint64_t raysReceived() const override { return distributed_ ? distributed_->received() : 0; }
  uint64_t revisits() const override { return distributed_ ? distributed_->revisits() : 0; }
  std::string layout() const override { return layoutName<Path>(); }
  size_t pathBytes() const override { return sizeof(Path); }

 private:
  const Scene& scene_;
  const TraceBackend& geometry_;
  const LightSampler& lights_;
  std::unique_ptr<RayTraversal<Path>> traversal_;
  DistributedTraversal<Path>* distributed_;
  std::unique_ptr<WavefrontRenderer<Path>> renderer_;
};

// What a run does around the frame loop (RenderSession::renderFrames): which
// frame comes next, how it is sliced, what follows it. Batch and interactive
// renders are its two kinds.
class RenderSession::FramePolicy {
 public:
  virtual ~FramePolicy() = default;
  // Once, before the first frame.
  virtual void start(Frames&) {}
  // Before each frame (collective): false ends the run. Sets frames.frame and
  // frames.progress, and may change frames.render (then restarts frames).
  virtual bool next(Frames& frames) = 0;
  // Slices of this frame, the same on every rank.
  virtual uint32_t slices(const Frames&) { return 1; }
  // After each slice but the last (collective): true abandons the frame.
  virtual bool abandon() { return false; }
  virtual void abandoned() {}
  // After a whole frame: this rank's stats, and its time from the first slice.
  virtual void finished(Frames& frames, FrameStats mine, double seconds) = 0;
  // Once, after the last frame.
  virtual void done(Frames&) {}
};

template <typename Path>
void RenderSession::renderFrames(FramePolicy& policy, const RenderSettings& render) {
  Rank& rank = *rank_;
  rank.lap(&SetupTimes::agree);
  DistributedTraversal<Path>* distributed = nullptr;
  std::unique_ptr<RayTraversal<Path>> traversal = makeTraversal<Path>(&distributed);
  rank.lap(&SetupTimes::proxies);
  FramesFor<Path> frames(rank.scene, *rank.geometry, *rank.lights, std::move(traversal),
                         distributed, render);
  policy.start(frames);
  while (policy.next(frames)) {
    const uint32_t pixels = frames.pixels(), slices = policy.slices(frames);
    rank.reachFirstPixel(comm_);
    const auto start = Clock::now();
    FrameStats mine;
    bool abandon = false;
    for (uint32_t slice = 0; slice < slices && !abandon; ++slice) {
      const uint32_t first = uint32_t(uint64_t(pixels) * slice / slices);
      const uint32_t last = uint32_t(uint64_t(pixels) * (slice + 1) / slices);
      if (slices == 1)
        mine = frames.renderPixels(first, last);
      else
        mine.merge(frames.renderPixels(first, last));
      if (slice + 1 < slices) abandon = policy.abandon();
    }
    if (abandon)
      policy.abandoned();
    else
      policy.finished(frames, std::move(mine), secondsSince(start));
  }
  policy.done(frames);
}

template <typename F>
void RenderSession::withPathLayout(F&& f) {
  // Masks while they fit (8 then 64 ranks), else replay (or as forced).
  const int ranks = group().size();
  // (Parts hold only the materials they use: the ranks agree.)
  const bool probed =
      group().sum(uint64_t(sceneTakesProbes(scene(), SubsurfaceMethod::Probes))) > 0;
  if (probed && settings_.render.subsurface == SubsurfaceMethod::Walks &&
      group().sum(uint64_t(std::any_of(scene().media.begin(), scene().media.end(),
                                       [](const Medium& m) { return m.subsurface; }))) == 0)
    throw InputError(
        "walking subsurface materials needs the media inside them, which part files do not "
        "keep: render the scene file, or probe them (the subsurface setting)");
  if (probed && settings_.render.subsurface == SubsurfaceMethod::Probes)
    f.template operator()<PathProbe>();
  else if (settings_.pathLayout == PathLayout::Replay ||
           (settings_.pathLayout == PathLayout::Auto && ranks > 64))
    f.template operator()<PathReplay>();
  else if (ranks <= 8)
    f.template operator()<Path8>();
  else
    f.template operator()<Path64>();
}

// A batch render: frames 0 to render.frames - 1 (after a checkpoint's, and
// up to the time limit), checkpoints, images to a sink, and the report.
class RenderSession::BatchFrames final : public RenderSession::FramePolicy {
 public:
  BatchFrames(RenderSession& session, FrameSink& sink, const SessionProgress& progress)
      : session_(session),
        comm_(session.comm_),
        rank_(*session.rank_),
        settings_(session.settings_),
        sink_(sink),
        sinkFrames_(sink.frames()),
        sinkPixels_(sink.pixels()),
        progress_(progress) {
    // A resumed render starts after the checkpoint's frames, with its image
    // on rank 0 (the other ranks add to zero: the composite is the same sum).
    firstFrame_ = session.resume_ ? session.resume_->frames : 0;
    comm_.broadcast(firstFrame_);
    lastFrame_ = settings_.render.frames - 1;
    frame_ = firstFrame_ - 1;
  }

  void start(Frames& frames) override {
    if (std::unique_ptr<Checkpoint>& resume = session_.resume_) {
      FERRY_CHECK_EQ(resume->sums.size(), frames.buffer.fixedSum().size());
      frames.buffer.fixedSum() = std::move(resume->sums);
      resume.reset();
    }
    runStart_ = Clock::now();
  }

  bool next(Frames& frames) override {
    if (++frame_ > lastFrame_) return false;
    double secondsLeft = -1;
    if (settings_.timeLimitSeconds > 0)
      secondsLeft = std::max(0.0, settings_.timeLimitSeconds - secondsSince(runStart_));
    frames.frame = frame_;
    frames.progress = [this, frame = frame_, secondsLeft](int done, int total) {
      if (progress_) progress_({frame, done, total, false, secondsLeft});
    };
    return true;
  }

  void finished(Frames& frames, FrameStats mine, double) override {
    const int frame = frame_;
    report_.stats.frames.push_back(sumOverRanks(comm_, mine));
    // The frame that crosses the time limit is the last (every rank agrees:
    // the slowest rank's clock decides).
    if (settings_.timeLimitSeconds > 0 &&
        comm_.max(secondsSince(runStart_)) >= settings_.timeLimitSeconds)
      lastFrame_ = frame;
    if (!settings_.checkpoint.empty() &&
        (frame == lastFrame_ || (frame + 1 - firstFrame_) % settings_.checkpointEvery == 0))
      writeCheckpointAfter(frames, frame);
    if (sinkFrames_ == FrameSink::Frames::Every && frame < lastFrame_) {
      double seconds = 0;
      FrameImage image = compositeAfter(frames, frame, seconds);
      // The other ranks go on into the next frame's collectives: a failure
      // here must end them too.
      if (comm_.isRoot()) try {
          sink_.receive(image);
        } catch (const std::exception& e) {
          comm_.abortAll(e.what());
        }
    }
  }

  // After the last frame: the final image to the sink, and the report.
  void done(Frames& frames) override {
    const RenderSettings& render = settings_.render;
    if (progress_) progress_({lastFrame_, render.samplesPerPixel, render.samplesPerPixel, true});
    FrameImage image = compositeAfter(frames, lastFrame_, report_.compositeSeconds);
    report_.compositeBytes = comm_.sum(compositeBytes_);
    report_.memory =
        rankMemory(comm_, double(rank_.ownedEstimate.total()), double(rank_.embreeBytes),
                   double(rank_.embreePeakBytes), rank_.proxyBytes());
    report_.setup = rankSetupTimes(comm_, rank_.setup);
    report_.raysReceived = comm_.sum(frames.raysReceived());
    report_.revisits = comm_.sum(frames.revisits());
    report_.pathLayout = frames.layout();
    report_.pathBytes = frames.pathBytes();
    // After the last collective: what the sink throws ends only this rank.
    if (comm_.isRoot()) sink_.receive(image);
  }

  SessionReport takeReport() { return std::move(report_); }

 private:
  FrameImage compositeAfter(Frames& frames, int frame, double& seconds) {
    const auto start = Clock::now();
    const float scale = imageScale(rank_.scene, frame + 1, settings_.render.samplesPerPixel);
    FrameImage image = composite(comm_, frames.buffer, scale, sinkPixels_,
                                 settings_.render.toneMapping, compositeBytes_);
    image.frame = frame;
    image.last = frame == lastFrame_;
    seconds = comm_.max(secondsSince(start));
    report_.stats.frames[size_t(frame - firstFrame_)].times.composite += seconds;
    return image;
  }

  void writeCheckpointAfter(Frames& frames, int frame) {
    uint64_t sent = 0;
    std::vector<int64_t> sums = compositeFixed(comm_, frames.buffer, sent);
    compositeBytes_ += sent;
    if (!comm_.isRoot()) return;
    const RenderSettings& render = settings_.render;
    Checkpoint c;
    std::tie(c.identity, c.description) = session_.imageIdentity();
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
  }

  RenderSession& session_;
  const Communicator& comm_;
  Rank& rank_;
  const SessionSettings& settings_;
  FrameSink& sink_;
  const FrameSink::Frames sinkFrames_;
  const FrameSink::Pixels sinkPixels_;
  const SessionProgress& progress_;
  SessionReport report_;
  int firstFrame_ = 0, lastFrame_ = 0, frame_ = 0;
  uint64_t compositeBytes_ = 0;  // this rank's, over every composite
  Clock::time_point runStart_;
};

SessionReport RenderSession::run(FrameSink& sink, const SessionProgress& progress) {
  BatchFrames policy(*this, sink, progress);
  withPathLayout([&]<typename Path>() { renderFrames<Path>(policy, settings_.render); });
  return policy.takeReport();
}

// An interactive render: frame after frame, accumulating, with rank 0's
// control asked for changes before each frame and told after it.
class RenderSession::InteractiveFrames final : public RenderSession::FramePolicy {
 public:
  InteractiveFrames(RenderSession& session, InteractiveControl* control, uint64_t maxFrames,
                    double sliceSeconds)
      : session_(session),
        comm_(session.comm_),
        rank_(*session.rank_),
        control_(control),
        maxFrames_(maxFrames),
        sliceSeconds_(sliceSeconds) {}

  // How the render ended (after it has).
  InteractiveEnd end() const {
    InteractiveEnd e = end_;
    e.frames = frames_;
    return e;
  }

  bool next(Frames& frames) override {
    if (maxFrames_ > 0 && frames_ >= maxFrames_) return false;
    ++frames_;
    ViewChange change;
    if (comm_.isRoot()) change = control_->takeChange();
    comm_.broadcast(change);
    if (change.flags & ViewChange::kQuit) return false;
    RenderSettings& render = frames.render;
    const int oldWidth = render.imageWidth(), oldHeight = render.imageHeight();
    change.applyTo(*render.camera, render);
    if (change.flags & ViewChange::kField) {
      end_.field = change.field;
      end_.camera = *render.camera;
      end_.render = render;
      return false;
    }
    if (change.flags & ViewChange::kVolume) session_.applyVolumeLook(render.volumeLook);
    if (change.flags & ViewChange::kFocus) focusAt(change.focusX, change.focusY, render);
    constexpr uint32_t kRestart =
        ViewChange::kCamera | ViewChange::kSettings | ViewChange::kVolume | ViewChange::kFocus;
    if (change.flags & kRestart) {
      if (render.imageWidth() != oldWidth || render.imageHeight() != oldHeight)
        frames.buffer = FrameBuffer(render.imageWidth(), render.imageHeight());
      else
        frames.buffer.clear();
      accumulated_ = 0;
      frames.restart();
    }
    frames.frame = accumulated_;
    return true;
  }

  // A focus pick: the focal distance becomes the distance along the view
  // axis to the nearest hit of the camera's centre ray through image point
  // (x, y), the nearest over every rank's geometry (collective).
  void focusAt(float x, float y, RenderSettings& render) {
    const FilmWindow window = render.window();
    const Camera camera(*render.camera, window);
    const Vec3f direction = camera.direction(float(window.x0) + x * float(window.width),
                                             float(window.y0) + y * float(window.height));
    double nearest = kInfinity;
    if (rank_.geometry) {
      const TraceHit hit = rank_.geometry->intersect({camera.origin(), direction});
      if (hit.valid()) nearest = hit.t;
    }
    nearest = -comm_.max(-nearest);
    const double along = nearest * double(camera.cosToAxis(direction));
    if (std::isfinite(along) && along > 0) render.camera->focalDistance = float(along);
  }

  // A long frame goes through in slices of about `sliceSeconds` (judged by
  // the last frame's time, the same on every rank), with rank 0's word in
  // between on whether a change is waiting: a camera move abandons the rest
  // of the frame instead of waiting for it (what was added is cleared with
  // the accumulation the change restarts). Each slice costs a distributed
  // render the overlap at its end, so short frames stay whole.
  uint32_t slices(const Frames& frames) override {
    const double bySeconds = sliceSeconds_ > 0 ? lastFrameSeconds_ / sliceSeconds_ : 64;
    return std::clamp<uint32_t>(
        std::min<uint32_t>(uint32_t(std::min(bySeconds, 64.0)), frames.pixels() / 4096), 1, 64);
  }

  bool abandon() override {
    bool abandon = comm_.isRoot() && control_->restartPending();
    comm_.broadcast(abandon);
    return abandon;
  }

  void abandoned() override { ++abandoned_; }

  void finished(Frames& frames, FrameStats mine, double seconds) override {
    const RenderSettings& render = frames.render;
    mine.frame = accumulated_;
    mine.seconds = seconds;
    InteractiveFrame frame;
    frame.abandoned = std::exchange(abandoned_, 0);
    frame.stats = sumOverRanks(comm_, mine);
    lastFrameSeconds_ = frame.stats.seconds;
    ++accumulated_;
    const auto start = Clock::now();
    frame.image = composite(comm_, frames.buffer,
                            imageScale(rank_.scene, accumulated_, render.samplesPerPixel),
                            FrameSink::Pixels::ToneMapped, render.toneMapping, compositeBytes_);
    frame.stats.times.composite = comm_.max(secondsSince(start));
    frame.memory = rankMemory(comm_, double(rank_.ownedEstimate.total()), double(rank_.embreeBytes),
                              double(rank_.embreePeakBytes), rank_.proxyBytes());
    if (!comm_.isRoot()) return;
    frame.accumulated = accumulated_;
    frame.camera = *render.camera;
    frame.settings = render;
    frame.image.frame = accumulated_ - 1;
    try {
      control_->publish(frame);
    } catch (const std::exception& e) {
      comm_.abortAll(e.what());  // the other ranks are in the next frame's collectives
    }
  }

 private:
  RenderSession& session_;
  const Communicator& comm_;
  Rank& rank_;
  InteractiveControl* control_;
  const uint64_t maxFrames_;
  const double sliceSeconds_;
  uint64_t frames_ = 0;  // frames begun, abandoned ones too
  InteractiveEnd end_;   // a field change ends the render (InteractiveEnd)
  int accumulated_ = 0;
  uint64_t compositeBytes_ = 0, abandoned_ = 0;
  double lastFrameSeconds_ = 0;  // the slowest rank's, of the last whole frame
};

InteractiveEnd RenderSession::runInteractive(InteractiveControl* control, uint64_t maxFrames,
                                             double sliceSeconds) {
  FERRY_CHECK(!comm_.isRoot() || control);
  InteractiveFrames policy(*this, control, maxFrames, sliceSeconds);
  RenderSettings render = settings_.render;
  render.frames = 1;
  render.camera = render.cameraIn(rank_->scene);
  withPathLayout([&]<typename Path>() { renderFrames<Path>(policy, render); });
  return policy.end();
}

}  // namespace ferry
