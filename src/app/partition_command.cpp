#include "app/partition_command.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <filesystem>

#include "app/render_command.h"
#include "builtin/builtin.h"
#include "comm/communicator.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/process_memory.h"
#include "flags/render_flags.h"
#include "io/images/image_io.h"
#include "io/parts/part_directory.h"
#include "io/scene_loader.h"
#include "path/path.h"
#include "report/partition_picture.h"
#include "report/partition_report.h"
#include "scene/light_scene.h"
#include "scene/memory_cost.h"
#include "scene/mesh_store.h"
#include "scene/scene_summary.h"
#include "session/forward_prediction.h"
#include "session/partitioned_scene.h"
#include "session/session_settings.h"
#include "shapes/volume_brick.h"

namespace ferry {
namespace {

// Parses "N" or "A..B" (1 <= A <= B <= 4096); throws InputError naming --ranks.
void parseRankRange(const std::string& text, int& first, int& last) {
  auto bad = [&]() {
    return InputError(fmt::format("--ranks '{}': expected a count (8) or a range (1..128)", text));
  };
  auto parse = [&](std::string_view s, int& out) {
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) throw bad();
  };
  size_t dots = text.find("..");
  if (dots == std::string::npos) {
    parse(text, first);
    last = first;
  } else {
    parse(std::string_view(text).substr(0, dots), first);
    parse(std::string_view(text).substr(dots + 2), last);
  }
  if (first < 1 || last < first || last > 4096)
    throw InputError(
        fmt::format("--ranks '{}': counts must satisfy 1 <= first <= last <= 4096", text));
}

// The flags as the partitioner's options, checked (best when none is named).
PartitionerOptions partitionerOptions(const PartitionCommandOptions& o) {
  PartitionerOptions p = checkedPartitionerOptions(o.partition);
  p.partitioner = &chosenPartitioner(o.partition, bestPartitioner());
  return p;
}

nlohmann::json optionsJson(const PartitionerOptions& p) {
  return {{"break_objects", !p.keepObjectsWhole},
          {"replication_budget", p.replicationBudget},
          {"mesh_proxies", p.meshProxies},
          {"instance_proxies", instanceProxiesFor(p)},
          {"max_proxies", p.maxProxies},
          {"max_piece_bytes", p.maxPieceBytes},
          {"seed", p.seed},
          {"max_part", p.maxPart}};
}

std::string defaultPlotPath(const std::string& report) {
  std::filesystem::path p(report);
  p.replace_extension(".png");
  return p.string();
}

// The views --predict-forwards predicts for: every named view of the scene
// (its default one if it names none), and the command line's camera.
std::vector<PredictionView> predictionViews(const Scene& scene, const PartitionCommandOptions& o) {
  std::vector<PredictionView> views;
  for (const CameraView& v : scene.views) views.push_back({v.name, std::nullopt});
  if (views.empty()) views.push_back({"", std::nullopt});
  if (std::optional<CameraView> c = cameraFromFlags(o.camera)) views.push_back({c->name, c});
  return views;
}

ForwardPredictionOptions predictionOptions(const PartitionCommandOptions& o) {
  ForwardPredictionOptions p;
  parseImageSize(o.predictSize, p.width, p.height);
  if (o.predictPaths < 1 || o.predictPaths > kMaxPixels)
    throw InputError(
        fmt::format("--predict-paths {}: expected 1 to {}", o.predictPaths, kMaxPixels));
  if (o.predictDepth < 0 || o.predictDepth > 64)
    throw InputError(fmt::format("--predict-depth {}: expected 0 to 64", o.predictDepth));
  p.samplePaths = o.predictPaths;
  p.maxDepth = o.predictDepth;
  return p;
}

// Predicts, prints and records the predictions in the directory's manifest.
void predictAndRecord(const PartitionCommandOptions& o, const std::vector<PredictionView>& views,
                      const ForwardPredictionOptions& options) {
  const std::vector<ForwardPrediction> predictions = predictForwards(o.output, views, options);
  Manifest m = readManifest(o.output);
  m.predictions = nlohmann::json::array();
  for (const ForwardPrediction& p : predictions) m.predictions.push_back(p.toJson());
  writeManifest(o.output, m);
  if (o.quiet) return;
  int width = 0, height = 0;
  predictionSampleSize(options, width, height);
  fmt::print("predicted rays forwarded ({}x{} paths sampled for {}x{}, depth {}):\n", width, height,
             options.width, options.height, options.maxDepth);
  // Per path, and of that the shadow rays, the rays sent back to their hit
  // only to be shaded (the rest: camera rays and continuations on their way),
  // and the rays that found nothing where they were sent (the proxies' looseness).
  fmt::print("  {:<16} {:>10} {:>8} {:>9} {:>9} {:>14} {:>9}\n", "view", "per path", "shadow",
             "to shade", "no hit", "in the image", "seconds");
  for (const ForwardPrediction& p : predictions) {
    const double paths = double(std::max<uint64_t>(1, p.cameraPaths));
    fmt::print("  {:<16} {:>10.3f} {:>8.3f} {:>9.3f} {:>9.3f} {:>14.0f} {:>9.2f}\n", p.view,
               p.forwardsPerPath(), double(p.shadowRaysForwarded) / paths,
               double(p.forwardedToShade) / paths, double(p.visitsWithoutHit) / paths,
               p.forwardsPerPath() * double(options.width) * double(options.height), p.seconds);
  }
}

// What `ferry partition -o DIR` made, for the terminal.
void printPartsSummary(const PartitionCommandOptions& o, const PartitionerOptions& p, int ranks,
                       const PartitionStats& stats, const Manifest& m, double loadSeconds,
                       double writeSeconds) {
  fmt::print(
      "partitioned {} ({} estimated) for {} ranks with {}: {} units, {} distinct parts, {} "
      "proxies{}\n",
      o.scene, formatBytes(stats.inputBytes), ranks, p.chosen().name(), stats.units, stats.parts,
      stats.proxies,
      stats.unmergedProxies > stats.proxies
          ? fmt::format(" (merged from {}: --max-proxies)", stats.unmergedProxies)
          : "");
  if (stats.split.objectsBroken || stats.split.meshesCut)
    fmt::print(
        "  rewritten first: {} objects broken into meshes, {} meshes or shapes cut into {} "
        "pieces\n",
        stats.split.objectsBroken, stats.split.meshesCut, stats.split.piecesMade);
  if (p.chosen().tracesRays())
    fmt::print(
        "  sampled {} rays in {:.2f} s ({} pass two or more units); the splits separate {} "
        "({:.2f} per sampled ray)\n",
        stats.sampledRays, stats.sampleSeconds, stats.sampledRaysAcrossUnits, stats.separatedRays,
        double(stats.separatedRays) / double(std::max<uint64_t>(1, stats.sampledRays)));
  if (p.chosen().reads("replication-budget"))
    fmt::print("  replicated {} units, {} over all ranks (budget {:.1f}% = {})\n",
               stats.replicatedUnits, formatBytes(stats.replicatedBytes), 100 * p.replicationBudget,
               formatBytes(uint64_t(p.replicationBudget * double(stats.inputBytes))));
  fmt::print("  {:>5} {:>10} {:>12} {:>12}\n", "rank", "instances", "estimated", "file");
  uint64_t fileBytes = m.shared.bytes;
  for (const ManifestPart& part : m.parts) {
    fmt::print("  {:>5} {:>10} {:>12} {:>12}\n", part.rank, part.instances,
               formatBytes(part.estimatedBytes), formatBytes(part.bytes));
    fileBytes += part.bytes;
  }
  fmt::print(
      "  largest part {} ({:.1f}% of the scene)\n", formatBytes(stats.maxRankBytes()),
      100.0 * double(stats.maxRankBytes()) / double(std::max<uint64_t>(1, stats.inputBytes)));
  fmt::print("  {:.2f} s load, {:.2f} s partition, {:.2f} s write; peak resident {}\n", loadSeconds,
             stats.seconds, writeSeconds, formatBytes(readProcessMemory().peakResidentBytes));
  fmt::print("wrote {} ({} files, {}; shared data {})\n", o.output, m.parts.size() + 2,
             formatBytes(fileBytes), formatBytes(m.shared.bytes));
}

// What partitioning holds besides the geometry, per instance: the instance
// (52 B), its unit, world box, owners, proxy and the partitioners' working
// arrays. Measured on the island at scale 30 out of core (docs/memory.md).
constexpr uint64_t kPartitionBytesPerInstance = 400;

// Where the geometry goes while partitioning (--memory-budget).
struct GeometryPlan {
  uint64_t budget = 0;
  bool outOfCore = false;  // meshes kept in a spill file (scene/mesh_store.h)
  std::string why;         // for the summary
};

// A built-in is described first (counts, no geometry): its geometry is kept
// out of memory only when the whole would not fit the budget, and the
// partition is refused if even the records would not. A scene file cannot be
// weighed before it is read: with a budget given, its meshes are stored as
// they are read (pbrt streams its shapes and plymesh files; OBJ, glTF and a
// lone PLY are read whole first).
GeometryPlan planGeometry(const PartitionCommandOptions& o) {
  GeometryPlan g;
  const bool given = !o.memoryBudget.empty();
  g.budget = given ? parseBytes(o.memoryBudget, "--memory-budget") : physicalMemoryBytes() / 2;
  if (!isBuiltinSpec(o.scene)) {
    g.outOfCore = given;
    g.why = given ? "a scene file, with a budget: meshes stored as read" : "";
    return g;
  }
  const SceneSummary s = describeScene(o.scene);
  const uint64_t geometry = s.memory.meshArrays();
  const uint64_t records = s.instances * kPartitionBytesPerInstance + s.memory.texels;
  if (geometry + records <= g.budget) return g;
  if (records > g.budget)
    throw InputError(fmt::format(
        "{}: {} instances and {} of textures need about {} to partition even with the geometry "
        "out of memory, more than --memory-budget {}",
        o.scene, s.instances, formatBytes(s.memory.texels), formatBytes(records),
        formatBytes(g.budget)));
  g.outOfCore = true;
  g.why = fmt::format("{} of geometry and {} of records and textures exceed the budget",
                      formatBytes(geometry), formatBytes(records));
  return g;
}

// The spill file: next to the output, unlinked as soon as it is open.
std::string spillPath(const std::string& output) {
  std::filesystem::path target = std::filesystem::absolute(output).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();
  std::error_code ec;
  std::filesystem::create_directories(target.parent_path(), ec);
  return (target.parent_path() /
          fmt::format(".{}.geometry.{}", target.filename().string(), ::getpid()))
      .string();
}

// With the geometry out of memory, each mesh is read back whole when it is
// cut or written: one larger than the budget cannot be partitioned.
void checkLargestMesh(const Scene& scene, const GeometryPlan& g, const std::string& spec) {
  for (const Mesh& m : scene.meshes) {
    const uint64_t bytes = meshCost(m).meshArrays();
    if (2 * bytes > g.budget)
      throw InputError(fmt::format(
          "{}: mesh '{}' alone holds {} of arrays; reading it back and cutting it needs about "
          "twice that, more than --memory-budget {}",
          spec, m.name, formatBytes(bytes), formatBytes(g.budget)));
  }
}

int writeParts(const PartitionCommandOptions& o, const PartitionerOptions& p, int ranks) {
  auto start = Clock::now();
  const GeometryPlan geometryPlan = planGeometry(o);
  if (geometryPlan.outOfCore && p.chosen().tracesRays())
    throw InputError(
        "--partitioner ray-guided traces its ray sample through the whole scene in memory: it "
        "cannot partition with the geometry out of memory (use best, or a larger "
        "--memory-budget)");
  LoadOptions load;
  if (geometryPlan.outOfCore) load.meshStore = std::make_shared<MeshStore>(spillPath(o.output));
  Scene scene = loadScene(o.scene, load);
  if (const int bricks = parseVolumeBricks(o.volumeBricks)) brickVolumes(scene, bricks);
  if (geometryPlan.outOfCore) checkLargestMesh(scene, geometryPlan, o.scene);
  const double loadSeconds = secondsSince(start);
  // Checked before the work: a bad view or flag fails in a second, not after the write.
  std::vector<PredictionView> views;
  ForwardPredictionOptions prediction;
  if (o.predictForwards) {
    views = predictionViews(scene, o);
    prediction = predictionOptions(o);
  }
  const SceneSummary summary = summarize(scene);
  const Scene lights = lightScene(scene);  // from the scene as given, before any rewrite
  PartitionStats stats;
  Partition partition = partitionScene(scene, ranks, p, &stats);
  partition.checkCovers(scene);
  PartDirectoryInfo info;
  info.scene = o.scene;
  info.partitioner = p.chosen().name();
  info.options = optionsJson(p);
  info.summary = summary.toJson();
  info.inputBytes = stats.inputBytes;
  info.replicatedBytes = stats.replicatedBytes;
  info.partitionSeconds = stats.seconds;
  auto writeStart = Clock::now();
  Manifest m = writePartDirectory(o.output, scene, partition, lights, info);
  const double writeSeconds = secondsSince(writeStart);
  if (!o.quiet) {
    printPartsSummary(o, p, ranks, stats, m, loadSeconds, writeSeconds);
    if (geometryPlan.outOfCore)
      fmt::print("  geometry out of memory ({}): {} spilled, budget {}\n", geometryPlan.why,
                 formatBytes(scene.meshStore->bytes()), formatBytes(geometryPlan.budget));
  }
  if (o.predictForwards) {
    scene = Scene{};  // the parts are loaded from the directory, as ranks load them
    predictAndRecord(o, views, prediction);
  }
  return 0;
}

int writeReport(const PartitionCommandOptions& o, const PartitionerOptions& p, int first,
                int last) {
  Scene scene = loadScene(o.scene);
  if (const int bricks = parseVolumeBricks(o.volumeBricks)) brickVolumes(scene, bricks);
  const std::string name = scene.name.empty() ? o.scene : scene.name;
  MaxPartReport report = maxPartReport(std::move(scene), name, first, last, p);
  writeMaxPartCsv(o.report, report);
  const std::string plot = o.plot.empty() ? defaultPlotPath(o.report) : o.plot;
  writeMaxPartPlot(plot, report);
  if (o.quiet) return 0;
  fmt::print("largest part of {} ({} estimated), {}..{} ranks:\n", o.scene,
             formatBytes(report.inputBytes), first, last);
  fmt::print("  {:<26} {:>12} {:>12} {:>9}\n", "partitioner", fmt::format("at {}", first),
             fmt::format("at {}", last), "seconds");
  for (const MaxPartSeries& s : report.series)
    fmt::print("  {:<26} {:>12} {:>12} {:>9.2f}\n", s.label(), formatBytes(s.bytes.front()),
               formatBytes(s.bytes.back()), s.seconds);
  fmt::print("wrote {} and {}\n", o.report, plot);
  return 0;
}

}  // namespace

void addPartitionCommand(CLI::App& app, PartitionCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "partition",
      "Split a scene over ranks, one part file per rank, for `ferry render DIR`:\n"
      "  ferry partition builtin:island --ranks 8 --partitioner best -o island-8\n"
      "  mpirun -np 8 ferry render island-8 -o island.png\n"
      "or report the largest part for every rank count and partitioner (the paper's Figure 4):\n"
      "  ferry partition builtin:island --report max-part.csv --ranks 1..128");
  cmd->add_option("scene", o.scene, "Scene file or built-in, as for ferry render")
      ->capture_default_str();
  cmd->add_option("--ranks", o.ranks, "Rank count (8), or for --report a range (1..128)")
      ->capture_default_str();
  addPartitionFlags(cmd, o.partition, "--partitioner", "Default: best.");
  cmd->add_option("-o,--output", o.output, "Directory to write the parts and manifest.json into");
  cmd->add_option(
      "--report", o.report,
      "Write the largest part's estimated bytes per rank count and partitioner as CSV, and\n"
      "a plot of it as PNG (see --plot)");
  cmd->add_option("--volume-bricks", o.volumeBricks,
                  "Grid volumes split into bricks of N voxels a side, placed like meshes\n"
                  "(auto: grids of 2^24 samples or more; 0: whole, held by every rank)")
      ->capture_default_str();
  cmd->add_option("--plot", o.plot, "PNG for --report (default: the report's name with .png)");
  cmd->add_option(
      "--memory-budget", o.memoryBudget,
      "Memory to partition in, e.g. 2GiB (default: half the machine's). A scene whose\n"
      "geometry would not fit is partitioned with its meshes in a temporary spill file\n"
      "next to -o, read back one at a time to cut and write them: the parts are the same");
  cmd->add_option("--seed", o.partition.options.seed,
                  "random, ray-guided: the seed of their samples")
      ->capture_default_str();
  cmd->add_flag(
      "--predict-forwards", o.predictForwards,
      "After writing, predict the rays forwarded per camera path for each named view (and a\n"
      "--look-from camera) by rendering a sample of paths through the parts, every rank a\n"
      "thread of this process (no MPI); printed and written into manifest.json");
  cmd->add_option("--predict-paths", o.predictPaths, "Camera paths the prediction samples")
      ->capture_default_str();
  cmd->add_option("--predict-size", o.predictSize,
                  "The image predicted for: its aspect shapes the sample")
      ->capture_default_str();
  cmd->add_option("--predict-depth", o.predictDepth, "Maximum path depth of the prediction")
      ->capture_default_str();
  addCameraFlags(cmd, o.camera);
  cmd->add_flag("-q,--quiet", o.quiet, "Print nothing but errors");
}

int runPartition(const PartitionCommandOptions& o) {
  const PartitionerOptions p = partitionerOptions(o);
  if (o.output.empty() && o.report.empty())
    throw InputError(
        "ferry partition: give -o DIR (write parts) or --report FILE.csv (largest part per rank "
        "count)");
  if (o.predictForwards && o.output.empty())
    throw InputError("--predict-forwards goes with -o DIR (it renders from the parts)");
  if (o.camera.given() && !o.predictForwards)
    throw InputError("--look-from and --look-at go with --predict-forwards in ferry partition");
  int first = 0, last = 0;
  parseRankRange(o.ranks, first, last);
  if (!o.report.empty()) {
    if (first == last) first = 1;  // a single count N: report 1..N
    writeReport(o, p, first, last);
  }
  if (!o.output.empty()) {
    if (o.ranks.find("..") != std::string::npos)
      throw InputError(fmt::format("--ranks '{}': -o needs one rank count", o.ranks));
    if (last > kMaxRanks)
      throw InputError(
          fmt::format("--ranks {}: parts are made for 1 to {} ranks", last, kMaxRanks));
    writeParts(o, p, last);
  }
  return 0;
}

int runShowPartition(const RenderOptions& o, const Communicator& comm) {
  std::string error;
  if (comm.isRoot()) {
    try {
      int width = 0, height = 0;
      parseImageSize(o.size, width, height);
      const std::string& out = o.output;
      if (imageFormatOf(out) != ImageFormat::Png)
        throw InputError(fmt::format("{}: --show-partition writes a PNG", out));
      SessionSettings settings;
      settings.scene = o.scene;
      applyPartitionerFlags(o, settings);
      const int ranks = o.showPartition > 0 ? o.showPartition : comm.size();
      PartitionedScene loaded = loadPartitionedScene(settings, ranks, -1);
      const std::string title =
          loaded.manifest
              ? fmt::format("{}: {}, {} ranks (from {})",
                            loaded.manifest->summary.value("name", o.scene), loaded.partitioner,
                            loaded.manifest->ranks, o.scene)
              : fmt::format("{}: {}{}, {} ranks", loaded.scene.name, loaded.partitioner,
                            settings.partitioning.keepObjectsWhole ? " (objects whole)" : "",
                            ranks);
      const Scene& scene = loaded.scene;
      const Partition& partition = loaded.partition;
      PictureOptions picture;
      picture.width = width;
      picture.height = height;
      picture.view = o.view;
      picture.title = title;
      writePng(out, width, height, partitionPicture(scene, partition, picture));
      if (!o.quiet) fmt::print("wrote {}\n", out);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  return comm.agreeOnFailure(!error.empty(), error) ? 1 : 0;
}

}  // namespace ferry
