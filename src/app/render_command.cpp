#include "app/render_command.h"

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <malloc.h>
#include <algorithm>

#include <charconv>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>

#include "app/image_output.h"
#include "app/partition_command.h"
#include "app/progress.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/fault_injection.h"
#include "core/process_memory.h"
#include "distributed/distributed_traversal.h"
#include "io/image_io.h"
#include "io/part_directory.h"
#include "io/scene_loader.h"
#include "mpi/communicator.h"
#include "mpi/compositor.h"
#include "partition/partition.h"
#include "partition/partitioner.h"
#include "render/lights.h"
#include "render/wavefront_renderer.h"
#include "scene/scene_summary.h"
#include "trace/embree_backend.h"
#include "trace/path.h"

namespace ferry {
namespace {

void validate(const RenderOptions& o) {
  if (o.samplesPerPixel < 1)
    throw InputError(fmt::format("--spp {}: must be at least 1", o.samplesPerPixel));
  if (o.frames < 1) throw InputError(fmt::format("--frames {}: must be at least 1", o.frames));
  if (o.maxDepth < 0)
    throw InputError(fmt::format("--max-depth {}: must be 0 or more", o.maxDepth));
  if (o.threads < 0)
    throw InputError(fmt::format("--threads {}: must be 0 (all) or more", o.threads));
  checkOutputPath(o.output);
  parseForwardingMode(o.forwarding);
  if (o.pathLayout != "auto" && o.pathLayout != "mask" && o.pathLayout != "replay")
    throw InputError(
        fmt::format("--path-layout '{}': expected auto, mask or replay", o.pathLayout));
  if (o.retrace != "remote" && o.retrace != "all")
    throw InputError(fmt::format("--retrace '{}': expected remote or all", o.retrace));
  if (o.instancing != "shared" && o.instancing != "always")
    throw InputError(fmt::format("--instancing '{}': expected shared or always", o.instancing));
  checkPartitionerName(o.partition);
  if (!(o.replicationBudget >= 0 && o.replicationBudget <= 1))
    throw InputError(fmt::format("--replication-budget {}: expected a fraction from 0 to 1",
                                 o.replicationBudget));
}

// Everything a rank holds once set up.
struct RankSetup {
  Scene scene;
  Partition partition;
  std::vector<int32_t> owned;
  std::unique_ptr<TraceBackend> geometry;
  std::unique_ptr<LightSampler> lights;
  SceneSummary summary;  // of the whole scene, before releasing what this rank does not own
  MemoryCost ownedEstimate;
  double loadSeconds = 0, buildSeconds = 0;
};

// Per-rank figures gathered for the stats: what each rank really holds.
struct RankMemory {
  std::vector<double> estimated, embree, embreePeak, resident, residentPeak;
};

RankMemory gatherMemory(const Communicator& comm, const RankSetup& setup) {
  ProcessMemory m = readProcessMemory();
  int n = comm.size();
  auto spread = [&](double mine) {
    std::vector<double> v(n, 0.0);
    v[comm.rank()] = mine;
    return comm.sum(std::span<const double>(v));
  };
  return {spread(double(setup.ownedEstimate.total())), spread(double(setup.geometry->bytes().now)),
          spread(double(setup.geometry->bytes().peak)), spread(double(m.residentBytes)),
          spread(double(m.peakResidentBytes))};
}

// Sums every counter over ranks (seconds: the slowest rank).
FrameStats reduceFrameStats(const Communicator& comm, const FrameStats& mine) {
  double maxBounces = comm.max(double(mine.perBounce.size()));
  FrameStats local = mine;
  local.perBounce.resize(size_t(maxBounces));
  std::vector<uint64_t> counters = {
      local.cameraPaths,   local.continuationRays, local.shadowRays,
      local.closestTraces, local.occlusionTraces,  local.retraces,
      local.retraceMisses, local.proxyQueries,     local.replayQueries};
  for (const ExchangeCounters& c : local.perBounce) {
    counters.push_back(c.raysForwarded);
    counters.push_back(c.bytesSent);
    counters.push_back(c.rounds);
  }
  std::vector<uint64_t> s = comm.sum(std::span<const uint64_t>(counters));
  std::vector<double> times = {local.times.generate, local.times.trace, local.times.exchange,
                               local.times.shade, local.times.composite};
  std::vector<double> t = comm.sum(std::span<const double>(times));
  FrameStats out;
  out.frame = mine.frame;
  out.seconds = comm.max(mine.seconds);
  out.cameraPaths = s[0];
  out.continuationRays = s[1];
  out.shadowRays = s[2];
  out.closestTraces = s[3];
  out.occlusionTraces = s[4];
  out.retraces = s[5];
  out.retraceMisses = s[6];
  out.proxyQueries = s[7];
  out.replayQueries = s[8];
  for (size_t b = 0; b < local.perBounce.size(); ++b)
    out.perBounce.push_back({s[9 + 3 * b], s[10 + 3 * b], s[11 + 3 * b]});
  out.times = {t[0], t[1], t[2], t[3], t[4]};
  return out;
}

// How this rank loads a scene file: only rank 0 speaks (warnings, progress).
LoadOptions sceneLoadOptions(const RenderOptions& o, const Communicator& comm) {
  LoadOptions l;
  l.envFallback = o.envFallback;
  if (!comm.isRoot()) {
    l.warn = [](const std::string&) {};
  } else if (!o.quiet) {
    l.progress = [last = -1](uint64_t done, uint64_t total, const std::string& what) mutable {
      int tenth = total ? int(10 * done / total) : 10;
      if (tenth == last) return;
      last = tenth;
      fmt::print(stderr, "load: {}% of {}\n", tenth * 10, what);
    };
  }
  return l;
}

// The image size and file a scene asks for (pbrt's Film) when the command
// line does not say.
void applySceneDefaults(const Scene& scene, RenderOptions& o, RenderSettings& settings) {
  if (!o.sizeGiven && scene.filmWidth && scene.filmHeight) {
    o.size = fmt::format("{}x{}", *scene.filmWidth, *scene.filmHeight);
    parseImageSize(o.size, settings.width, settings.height);
  }
  if (!o.outputGiven && !scene.filmFilename.empty()) {
    std::string ext = std::filesystem::path(scene.filmFilename).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (ext == ".png" || ext == ".exr" || ext == ".pfm") {
      o.output = scene.filmFilename;
      checkOutputPath(o.output);
    } else {
      fmt::print(
          stderr,
          "ferry: warning: the scene's output file {} has an unsupported format; writing {}\n",
          scene.filmFilename, o.output);
    }
  }
}

// Fills `s` in place: the Embree structures refer to its scene, so it must not move afterwards.
void setUp(const RenderOptions& o, const RenderSettings& settings, const Communicator& comm,
           RankSetup& s) {
  auto start = Clock::now();
  if (isPartDirectory(o.scene)) {
    // A part directory: this rank reads only its own part and the shared data.
    RankPart part = loadRankPart(o.scene, comm.rank(), comm.size());
    s.scene = std::move(part.scene);
    s.scene.view(settings.view);
    s.summary = summaryFromJson(part.manifest.summary);
    s.partition = std::move(part.partition);
    s.owned.resize(s.scene.instances.size());
    for (size_t i = 0; i < s.owned.size(); ++i) s.owned[i] = int32_t(i);
    s.lights = std::make_unique<LightSampler>(part.lights);
  } else {
    s.scene = loadScene(o.scene, sceneLoadOptions(o, comm));
    s.scene.view(settings.view);  // fail on an unknown view before building anything
    s.summary = summarize(s.scene);
    // Light data is small and needed everywhere: take it from the scene as
    // given, before the partitioner rewrites it and ranks release geometry.
    s.lights = std::make_unique<LightSampler>(s.scene);
    s.partition = partitionScene(s.scene, comm.size(), renderPartitionerOptions(o));
    s.owned = s.partition.instancesOf(comm.rank());
    s.scene.releaseAllBut(s.owned);
    // Hand the freed geometry back to the system, so resident memory shows what the rank holds.
    malloc_trim(0);
  }
  s.ownedEstimate = ownedMemory(s.scene, s.owned);
  s.loadSeconds = secondsSince(start);
  maybeInjectFailure("load", comm.rank());
  auto build = Clock::now();
  s.geometry = makeEmbreeBackend(
      s.scene, s.owned, o.instancing == "always" ? Instancing::Always : Instancing::Shared);
  s.buildSeconds = secondsSince(build);
}

void writeStats(const RenderOptions& o, const RenderSettings& settings, const RankSetup& setup,
                const RenderStats& stats, const RankMemory& memory, uint64_t received,
                uint64_t revisits, uint64_t compositeBytes, int ranks, double totalSeconds,
                const std::string& layout, size_t pathBytes) {
  nlohmann::json j;
  j["scene"] = setup.summary.toJson();
  j["settings"] = {{"width", settings.width},
                   {"height", settings.height},
                   {"spp", settings.samplesPerPixel},
                   {"frames", settings.frames},
                   {"max_depth", settings.maxDepth},
                   {"seed", settings.seed},
                   {"view", o.view},
                   {"threads", o.threads},
                   {"ranks", ranks},
                   {"forwarding", o.forwarding},
                   {"retrace", o.retrace},
                   {"instancing", o.instancing},
                   {"partition", o.partition},
                   {"output", o.output},
                   {"path_layout", layout},
                   {"path_bytes", pathBytes}};
  j["render"] = stats.toJson();
  j["render"]["rays_received"] = received;
  j["render"]["revisits"] = revisits;
  j["render"]["composite_bytes_sent"] = compositeBytes;
  nlohmann::json perRank = nlohmann::json::array();
  for (int r = 0; r < ranks; ++r)
    perRank.push_back({{"rank", r},
                       {"estimated_bytes", memory.estimated[r]},
                       {"embree_bytes", memory.embree[r]},
                       {"embree_peak_bytes", memory.embreePeak[r]},
                       {"resident_bytes", memory.resident[r]},
                       {"peak_resident_bytes", memory.residentPeak[r]}});
  j["memory"] = {
      {"scene_estimated_bytes", setup.summary.memory.total()},
      {"max_estimated_bytes", *std::max_element(memory.estimated.begin(), memory.estimated.end())},
      {"max_embree_bytes", *std::max_element(memory.embree.begin(), memory.embree.end())},
      {"max_peak_resident_bytes",
       *std::max_element(memory.residentPeak.begin(), memory.residentPeak.end())},
      {"per_rank", perRank}};
  j["seconds"] = {
      {"load", setup.loadSeconds}, {"build", setup.buildSeconds}, {"total", totalSeconds}};
  writeFileAtomically(o.statsPath, [&](const std::string& tmp) {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
    if (!out) throw InputError(fmt::format("{}: could not write", o.statsPath));
  });
}

template <typename Path>
std::string layoutName() {
  if constexpr (Path::kReplay)
    return "replay";
  else
    return sizeof(typename Path::Mask) == 1 ? "mask8" : "mask64";
}

template <typename Path>
int renderOnRanks(const RenderOptions& o, const RenderSettings& settings, RankSetup& setup,
                  const Communicator& comm, Clock::time_point start) {
  const bool talk = comm.isRoot() && !o.quiet;
  // One rank needs no forwarding machinery (no proxy queries, no collectives per round).
  std::unique_ptr<RayTraversal<Path>> traversal;
  DistributedTraversal<Path>* distributed = nullptr;
  if (comm.size() == 1) {
    traversal = std::make_unique<LocalTraversal<Path>>(*setup.geometry);
  } else {
    auto d = std::make_unique<DistributedTraversal<Path>>(comm, *setup.geometry, setup.partition,
                                                          parseForwardingMode(o.forwarding));
    distributed = d.get();
    traversal = std::move(d);
  }
  WavefrontRenderer<Path> renderer(setup.scene, *setup.geometry, *setup.lights, *traversal,
                                   settings);
  FrameBuffer frameBuffer(settings.width, settings.height);
  RenderStats stats;
  Progress rendering("render", settings.frames * settings.samplesPerPixel, talk);
  for (int frame = 0; frame < settings.frames; ++frame) {
    FrameStats mine = renderer.renderFrame(frame, frameBuffer, [&](int done, int) {
      rendering.update(frame * settings.samplesPerPixel + done, fmt::format("frame {}", frame + 1));
    });
    stats.frames.push_back(reduceFrameStats(comm, mine));
  }
  rendering.finish();

  auto compositeStart = Clock::now();
  const float scale = 1.0f / float(settings.frames * settings.samplesPerPixel);
  const bool png = o.output.size() >= 4 && (o.output.substr(o.output.size() - 4) == ".png" ||
                                            o.output.substr(o.output.size() - 4) == ".PNG");
  uint64_t compositeBytes = 0;
  std::vector<Vec3f> linear;
  std::vector<uint8_t> rgba;
  if (png)
    rgba = compositeToneMapped(comm, frameBuffer, scale, settings.toneMapping, compositeBytes);
  else
    linear = compositeLinear(comm, frameBuffer, scale, compositeBytes);
  double compositeSeconds = comm.max(secondsSince(compositeStart));
  if (!stats.frames.empty()) stats.frames.back().times.composite += compositeSeconds;
  compositeBytes = comm.sum(compositeBytes);
  RankMemory memory = gatherMemory(comm, setup);
  uint64_t received = comm.sum(distributed ? distributed->received() : 0);
  uint64_t revisits = comm.sum(distributed ? distributed->revisits() : 0);

  if (!comm.isRoot()) return 0;
  if (png)
    writePng(o.output, settings.width, settings.height, rgba);
  else
    writeRenderedImage(o.output, settings.width, settings.height, linear, settings.toneMapping);
  if (!o.quiet) {
    fmt::print("{}", stats.summaryText(comm.size()));
    auto maxOf = [](const std::vector<double>& v) {
      return uint64_t(*std::max_element(v.begin(), v.end()));
    };
    fmt::print("  {:<22}{} of {} estimated, {} Embree, {} peak resident (largest rank)\n",
               "memory per rank", formatBytes(maxOf(memory.estimated)),
               formatBytes(setup.summary.memory.total()), formatBytes(maxOf(memory.embree)),
               formatBytes(maxOf(memory.residentPeak)));
    fmt::print("  {:<22}{} ({} sent by direct send)\n", "composite",
               fmt::format("{:.3f} s", compositeSeconds), formatBytes(compositeBytes));
    if (revisits) fmt::print("  {:<22}{}\n", "REVISITS", revisits);
    fmt::print("  {:<22}{}\n", "wrote", o.output);
  }
  if (!o.statsPath.empty())
    writeStats(o, settings, setup, stats, memory, received, revisits, compositeBytes, comm.size(),
               secondsSince(start), layoutName<Path>(), sizeof(Path));
  return 0;
}

}  // namespace

void parseImageSize(const std::string& text, int& width, int& height) {
  auto bad = [&]() {
    return InputError(fmt::format("--size '{}': expected WIDTHxHEIGHT, e.g. 1280x720", text));
  };
  size_t x = text.find_first_of("xX");
  if (x == std::string::npos) throw bad();
  auto parse = [&](std::string_view s, int& out) {
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) throw bad();
  };
  parse(std::string_view(text).substr(0, x), width);
  parse(std::string_view(text).substr(x + 1), height);
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InputError(fmt::format("--size '{}': each side must be between 1 and 16384", text));
  if (uint64_t(width) * uint64_t(height) > kMaxPixels)
    throw InputError(fmt::format("--size '{}': more than {} pixels", text, kMaxPixels));
}

void addRenderCommand(CLI::App& app, RenderOptions& o) {
  CLI::App* render = app.add_subcommand(
      "render",
      "Path trace a scene and write the image. Run under mpirun to spread the scene over ranks:\n"
      "  mpirun -np 4 ferry render builtin:island -o island.png\n"
      "The image is the same whatever the rank count, --threads, --partition or --forwarding\n"
      "(up to floating-point summation order).");
  render
      ->add_option("scene", o.scene,
                   "Scene file (.obj, .ply, .pbrt, .gltf, .glb) or built-in: builtin:island, "
                   "builtin:landscape, builtin:cornell,\n"
                   "builtin:furnace, with parameters as builtin:island?scale=4&seed=7")
      ->capture_default_str();
  render->add_option("--size", o.size, "Image size WIDTHxHEIGHT")->capture_default_str();
  render->add_option("--spp", o.samplesPerPixel, "Samples (paths) per pixel in each frame")
      ->capture_default_str();
  render->add_option("--frames", o.frames, "Frames to render and accumulate progressively")
      ->capture_default_str();
  render
      ->add_option("--max-depth", o.maxDepth,
                   "Maximum scattering events per path (1: direct light only, 0: emitters only)")
      ->capture_default_str();
  render->add_option("--view", o.view, "Named camera view of the scene (default: its first view)");
  render->add_option("--seed", o.seed, "Seed of every random number; same seed, same image")
      ->capture_default_str();
  render->add_option("--threads", o.threads, "Worker threads per rank (0: all cores)")
      ->capture_default_str();
  render
      ->add_option("-o,--output", o.output,
                   "Output image: .png (tone mapped), .exr or .pfm (linear radiance)")
      ->capture_default_str();
  render->add_option(
      "--stats", o.statsPath,
      "Write counters (rays traced, forwarded, bytes sent, rounds per bounce), timings and\n"
      "memory per rank as JSON to this file");
  render->add_option("--exposure", o.exposure, "Exposure in stops for the PNG tone mapping")
      ->capture_default_str();
  render
      ->add_option(
          "--forwarding", o.forwarding,
          "How rays travel between ranks: proxies (the paper: closest proxy of an unvisited\n"
          "owner), ring (every rank in turn, as barney), broadcast (every rank, closest hit\n"
          "wins, as Kilauea)")
      ->capture_default_str();
  render
      ->add_option(
          "--path-layout", o.pathLayout,
          "The path on the wire: auto (8-rank mask, 64-rank mask, replay above 64 ranks),\n"
          "mask (visited ranks as a bit mask; up to 64 ranks) or replay (only the generating\n"
          "rank; any rank recomputes the visited ranks from the proxies)")
      ->capture_default_str();
  render
      ->add_option(
          "--retrace", o.retrace,
          "Which shaded paths re-trace their ray to recover the hit (the compact path carries\n"
          "none): remote (only those whose hit another rank found; a rank keeps the hits it\n"
          "found) or all (every one, as the paper). The image is the same.")
      ->capture_default_str();
  render
      ->add_option(
          "--instancing", o.instancing,
          "Which objects get an Embree instance level: shared (objects placed more than once\n"
          "or transformed; an object placed once, untransformed, is put in the top-level BVH,\n"
          "which saves every ray an instance transform) or always (every object). Instanced\n"
          "objects are never flattened either way. The image is the same.")
      ->capture_default_str();
  render
      ->add_option(
          "--partitioner,--partition", o.partition,
          "How the scene is split over ranks, made on the fly on every rank: spatial-simple,\n"
          "spatial-sah, object-naive, object-proxies, bvh-style, best (the paper's six), or\n"
          "round-robin, random (for testing). Not used for a part directory.")
      ->capture_default_str();
  render->add_flag("--keep-objects-whole", o.keepObjectsWhole,
                   "Partitioners keep non-instanced content whole (default: broken into meshes)");
  render
      ->add_option(
          "--replication-budget", o.replicationBudget,
          "best: copies of large, cheap content may add this fraction of the scene's bytes")
      ->capture_default_str();
  render->add_flag(
      "--show-partition{-1}", o.showPartition,
      "Instead of rendering, draw what each rank owns (replicated content checkerboarded)\n"
      "and the proxies as box outlines, to -o (PNG); =N: for N ranks (default: the MPI ranks)");
  render->add_flag("-q,--quiet", o.quiet, "No progress and no summary on the terminal");
  render->add_flag("--env-fallback", o.envFallback,
                   "Render a scene whose environment map is missing with a constant white\n"
                   "environment instead (the file is named in a warning)");
  render->callback([&o, render]() {
    o.sizeGiven = render->get_option("--size")->count() > 0;
    o.outputGiven = render->get_option("--output")->count() > 0;
  });
}

int runRender(const RenderOptions& o, const Communicator& comm) {
  if (o.showPartition != 0) return runShowPartition(o, comm);
  auto start = Clock::now();
  RenderSettings settings;
  std::unique_ptr<tbb::global_control> threadLimit;
  std::optional<RankSetup> setup;
  std::string error;
  RenderOptions effective = o;  // with the scene's own size and output file where none was given
  try {
    validate(o);
    if (comm.size() > kMaxRanks)
      throw InputError(
          fmt::format("{} ranks: Ferry supports up to {} ranks", comm.size(), kMaxRanks));
    if (o.pathLayout == "mask" && comm.size() > 64)
      throw InputError(
          fmt::format("--path-layout mask: {} ranks do not fit a 64-bit mask (use replay or auto)",
                      comm.size()));
    parseImageSize(o.size, settings.width, settings.height);
    settings.samplesPerPixel = o.samplesPerPixel;
    settings.frames = o.frames;
    settings.maxDepth = o.maxDepth;
    settings.seed = o.seed;
    settings.retraceAll = o.retrace == "all";
    settings.view = o.view;
    settings.toneMapping.exposure = o.exposure;
    if (o.threads > 0)
      threadLimit = std::make_unique<tbb::global_control>(
          tbb::global_control::max_allowed_parallelism, o.threads);
    Progress loading("load", 1, comm.isRoot() && !o.quiet);
    loading.update(0, o.scene);
    setUp(o, settings, comm, setup.emplace());
    applySceneDefaults(setup->scene, effective, settings);
    loading.finish(
        fmt::format("{:.2f} s load, {:.2f} s build", setup->loadSeconds, setup->buildSeconds));
  } catch (const std::exception& e) {
    error = e.what();
  }
  // Errors while setting up are usually the same on every rank: report once, exit cleanly.
  if (comm.agreeOnFailure(!error.empty(), error)) return 1;

  try {
    // The layout: masks while they fit (8 then 64 ranks), else replay (or as forced).
    if (o.pathLayout == "replay" || (o.pathLayout == "auto" && comm.size() > 64))
      return renderOnRanks<PathReplay>(effective, settings, *setup, comm, start);
    if (comm.size() <= 8) return renderOnRanks<Path8>(effective, settings, *setup, comm, start);
    return renderOnRanks<Path64>(effective, settings, *setup, comm, start);
  } catch (const InputError& e) {
    // Only rank 0 writes files, after every collective: the others have finished.
    if (comm.isRoot()) {
      fmt::print(stderr, "ferry: error: {}\n", e.what());
      return 1;
    }
    comm.abortAll(e.what());
  } catch (const std::exception& e) {
    comm.abortAll(e.what());
  }
}

}  // namespace ferry
