#include "flags/render_flags.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <filesystem>

#include "comm/communicator.h"
#include "core/error.h"
#include "distributed/distributed_traversal.h"
#include "distributed/forwarding.h"
#include "io/images/image_io.h"
#include "media/volume_look.h"
#include "path/path.h"
#include "render/aov.h"
#include "render/camera.h"
#include "session/image_file_sink.h"
#include "session/render_session.h"
#include "shapes/volume_brick.h"

namespace ferry {
namespace {

// How this rank loads a scene file: only rank 0 speaks (warnings, progress).
LoadOptions sceneLoadOptions(const RenderOptions& o, const Communicator& comm) {
  LoadOptions l;
  l.envFallback = o.envFallback;
  l.field = o.field;
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

}  // namespace

// `parse(value)`, its InputError prefixed with the flag (lower layers name
// the setting, not the flag).
template <typename Parse>
auto parseFlag(const char* flag, const std::string& value, Parse parse) {
  try {
    return parse(value);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", flag, e.what()));
  }
}

SessionSettings sessionSettings(const RenderOptions& o, const Communicator& comm) {
  if (o.samplesPerPixel < 1)
    throw InputError(fmt::format("--spp {}: must be at least 1", o.samplesPerPixel));
  if (o.frames < 1) throw InputError(fmt::format("--frames {}: must be at least 1", o.frames));
  if (o.maxDepth < 0)
    throw InputError(fmt::format("--max-depth {}: must be 0 or more", o.maxDepth));
  if (o.threads < 0)
    throw InputError(fmt::format("--threads {}: must be 0 (all) or more", o.threads));
  if (o.writesImage) checkOutputPath(o.output);
  SessionSettings s;
  s.forwarding = parseFlag("--forwarding", o.forwarding, parseForwardingMode);
  s.exchange =
      resolveExchangeMode(parseFlag("--exchange", o.exchange, parseExchangeMode), s.forwarding);
  if (o.chunkPixels < 1)
    throw InputError(fmt::format("--chunk {}: must be at least 1", o.chunkPixels));
  s.render.chunkPixels = o.chunkPixels;
  if (o.checkpointEvery < 1)
    throw InputError(fmt::format("--checkpoint-every {}: must be at least 1", o.checkpointEvery));
  if (!(o.timeLimit >= 0))
    throw InputError(fmt::format("--time-limit {}: must be 0 (none) or more seconds", o.timeLimit));
  if (!o.checkpoint.empty()) {
    const std::filesystem::path dir = std::filesystem::path(o.checkpoint).parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
      throw InputError(fmt::format("--checkpoint {}: directory '{}' does not exist", o.checkpoint,
                                   dir.string()));
  }
  s.render.aovs = parseFlag("--aov", o.aov, parseAovList);
  if (!s.render.aovs.empty() && !o.resume.empty())
    throw InputError(fmt::format(
        "--aov {} with --resume: a checkpoint holds the colour only; render again from the start",
        o.aov));
  s.checkpoint = o.checkpoint;
  s.checkpointEvery = o.checkpointEvery;
  s.timeLimitSeconds = o.timeLimit;
  s.pathLayout = parseFlag("--path-layout", o.pathLayout, parsePathLayout);
  s.retrace = parseFlag("--retrace", o.retrace, parseRetrace);
  s.instancing = parseFlag("--instancing", o.instancing, parseInstancing);
  applyPartitionerFlags(o, s);
  checkRankCount(comm.size(), s.pathLayout);
  parseImageSize(o.size, s.render.width, s.render.height);
  if (!o.crop.empty()) s.render.crop = parseCropWindow("--crop", o.crop);
  if (!std::isnan(o.maxSampleLuminance)) {
    if (!(o.maxSampleLuminance >= 0) || !std::isfinite(o.maxSampleLuminance))
      throw InputError(fmt::format("--max-sample-luminance {}: expected 0 (no clamp) or more",
                                   o.maxSampleLuminance));
    if (o.maxSampleLuminance > 0)
      s.render.sampleClamp = {SampleClamp::Measure::Luminance, o.maxSampleLuminance};
  }
  s.render.samplesPerPixel = o.samplesPerPixel;
  s.render.frames = o.frames;
  s.render.maxDepth = o.maxDepth;
  if (o.mis != "on" && o.mis != "off")
    throw InputError(fmt::format("--mis {}: expected on or off", o.mis));
  s.render.lightStrategy = o.mis == "on" ? LightStrategy::Mis : LightStrategy::LightSamples;
  if (o.misHeuristic != "power" && o.misHeuristic != "balance")
    throw InputError(fmt::format("--mis-heuristic {}: expected power or balance", o.misHeuristic));
  s.render.misHeuristic = o.misHeuristic == "power" ? MisHeuristic::Power : MisHeuristic::Balance;
  if (o.lightChoice != "near" && o.lightChoice != "power")
    throw InputError(fmt::format("--light-choice {}: expected near or power", o.lightChoice));
  s.render.lightChoice = o.lightChoice == "near" ? LightChoice::Near : LightChoice::Power;
  if (o.lightPaths == "on" || o.lightPaths == "off")
    s.lightPaths = o.lightPaths == "on";
  else if (o.lightPaths != "auto")
    throw InputError(fmt::format("--light-paths {}: expected auto, on or off", o.lightPaths));
  if (s.lightPaths.value_or(false) && s.render.lightStrategy != LightStrategy::Mis)
    throw InputError("--light-paths on needs --mis on (light paths are weighed by MIS)");
  if (o.transmittance != "ratio" && o.transmittance != "delta")
    throw InputError(fmt::format("--transmittance {}: expected ratio or delta", o.transmittance));
  s.render.transmittance =
      o.transmittance == "ratio" ? TransmittanceEstimator::Ratio : TransmittanceEstimator::Delta;
  if (o.subsurface != "probe" && o.subsurface != "walk")
    throw InputError(fmt::format("--subsurface {}: expected probe or walk", o.subsurface));
  s.render.subsurface =
      o.subsurface == "probe" ? SubsurfaceMethod::Probes : SubsurfaceMethod::Walks;
  const std::optional<SamplerKind> sampler = samplerNamed(o.sampler);
  if (!sampler)
    throw InputError(fmt::format("--sampler {}: expected sobol or independent", o.sampler));
  s.render.sampler = *sampler;
  if (!(o.volumeOpacity > 0) || !std::isfinite(o.volumeOpacity))
    throw InputError(
        fmt::format("--volume-opacity {}: expected a positive scale", o.volumeOpacity));
  if (!o.colorMap.empty() && !colorMap(o.colorMap))
    throw InputError(fmt::format("--color-map {}: expected one of {}", o.colorMap,
                                 fmt::join(colorMapNames(), ", ")));
  s.render.volumeLook = {o.volumeOpacity, o.colorMap};
  s.volumeBrickVoxels = parseVolumeBricks(o.volumeBricks);
  if (o.dataGroups < 1 || comm.size() % o.dataGroups != 0)
    throw InputError(fmt::format(
        "--data-groups {}: expected a divisor of the rank count ({}): groups of equal size",
        o.dataGroups, comm.size()));
  s.dataGroups = o.dataGroups;
  s.render.seed = o.seed;
  s.render.view = o.view;
  s.render.toneMapping.exposure = o.exposure;
  s.scene = o.scene;
  s.load = sceneLoadOptions(o, comm);
  s.threads = o.threads;
  s.render.camera = cameraFromFlags(o.camera);
  lensFromFlags(o.camera, s.render.lensRadius, s.render.focalDistance);
  return s;
}

void applyPartitionerFlags(const RenderOptions& o, SessionSettings& settings) {
  if (!o.partition.partitioner.empty())
    settings.partitioner = &partitionerNamed(o.partition.partitioner);
  settings.partitioning = checkedPartitionerOptions(o.partition);
  settings.render.seed =
      o.seed;  // the partitioner's seed too (--show-partition reads it from here)
}

void addRenderingOptions(CLI::App* command, RenderOptions& o) {
  command
      ->add_option("scene", o.scene,
                   "Scene file (.obj, .ply, .pbrt, .gltf, .glb) or built-in: builtin:island, "
                   "builtin:landscape, builtin:cornell,\n"
                   "builtin:furnace, with parameters as builtin:island?scale=4&seed=7")
      ->capture_default_str();
  command->add_option("--size", o.size, "Image size WIDTHxHEIGHT")->capture_default_str();
  command->add_option("--crop", o.crop,
                      "Render only this part of the image, X0,X1,Y0,Y1 as fractions of its\n"
                      "width and height, y down (pbrt's cropwindow); the output holds that part");
  command->add_option("--max-sample-luminance", o.maxSampleLuminance,
                      "Scale each camera sample whose luminance exceeds this down to it, as\n"
                      "pbrt-v3's Film maxsampleluminance (light path splats one by one); 0: no\n"
                      "clamp. Default: the scene's own (pbrt's Film), else none");
  command->add_option("--spp", o.samplesPerPixel, "Samples (paths) per pixel in each frame")
      ->capture_default_str();
  command
      ->add_option("--max-depth", o.maxDepth,
                   "Maximum scattering events per path (1: direct light only, 0: emitters only);\n"
                   "default: a pbrt scene's Integrator \"maxdepth\", else 5")
      ->capture_default_str();
  command
      ->add_option("--mis", o.mis,
                   "Multiple importance sampling: on (light and BSDF samples both find emitters\n"
                   "and the environment map, weighed by the power heuristic) or off (emitters\n"
                   "only through light samples, as the paper)")
      ->capture_default_str();
  command
      ->add_option("--mis-heuristic", o.misHeuristic,
                   "How MIS weighs its strategies: power (Veach's power heuristic, pbrt's path\n"
                   "integrator's) or balance (pbrt's bdpt's). The same image in expectation\n"
                   "but for pbrt-v3's mirrored emitters; only the noise differs")
      ->capture_default_str();
  command
      ->add_option("--light-choice", o.lightChoice,
                   "How a light sample chooses among emitters: near (by power over squared\n"
                   "distance) or power (by power alone, pbrt's \"power\" light sample\n"
                   "strategy). Unbiased either way")
      ->capture_default_str();
  command
      ->add_option("--light-paths", o.lightPaths,
                   "Light paths: on (each pixel sample also traces a path from an emitter and\n"
                   "connects it to the camera, weighed by MIS: light through glass, small\n"
                   "apertures), off, or auto (on when the pbrt scene's Integrator is bdpt)")
      ->capture_default_str();
  command
      ->add_option("--transmittance", o.transmittance,
                   "How shadow rays through participating media estimate transmittance: ratio\n"
                   "(ratio tracking) or delta (delta tracking: 0 or 1, a baseline to compare)")
      ->capture_default_str();
  command
      ->add_option("--subsurface", o.subsurface,
                   "Where light entering a subsurface material leaves: probe (pbrt's BSSRDF,\n"
                   "found by probe rays) or walk (a random walk through the medium inside)")
      ->capture_default_str();
  command
      ->add_option("--sampler", o.sampler,
                   "How a path's random numbers are drawn: sobol (a Sobol' sequence per pair\n"
                   "of numbers, shuffled and shifted per pixel: less noise at equal samples) or\n"
                   "independent (independent hashes)")
      ->capture_default_str();
  command
      ->add_option("--volume-opacity", o.volumeOpacity,
                   "Volumes drawn through a transfer function (raw: grids): their opacity scale\n"
                   "times this")
      ->capture_default_str();
  command->add_option("--color-map", o.colorMap,
                      "Volumes drawn through a transfer function: this colour map instead of\n"
                      "their own (cool-to-warm, viridis, inferno, black-body, grayscale)");
  command
      ->add_option("--volume-bricks", o.volumeBricks,
                   "Grid volumes (raw:, .vdb, builtin:volume, a pbrt grid medium filling its\n"
                   "box) split into bricks of N voxels a side, which the partitioner spreads\n"
                   "over the ranks like meshes. auto: grids of 2^24 samples or more, in\n"
                   "bricks of a sixteenth of their largest side (32 to 128); 0: every rank\n"
                   "holds every volume whole")
      ->capture_default_str();
  command
      ->add_option("--data-groups", o.dataGroups,
                   "Split the ranks into G groups of equal size that each hold the whole scene\n"
                   "(spread over their ranks; a part directory for that many ranks) and render\n"
                   "every G-th sample: memory traded for speed, the same image")
      ->capture_default_str();
  command->add_option("--view", o.view, "Named camera view of the scene (default: its first view)");
  command->add_option("--seed", o.seed, "Seed of every random number; same seed, same image")
      ->capture_default_str();
  command
      ->add_option(
          "--threads", o.threads,
          "Worker threads per rank (0: all cores; 2 x cores / ranks when ranks share a machine)")
      ->capture_default_str();
  command->add_option("--exposure", o.exposure, "Exposure in stops for the PNG tone mapping")
      ->capture_default_str();
  command
      ->add_option(
          "--forwarding", o.forwarding,
          "How rays travel between ranks: proxies (the paper: closest proxy of an unvisited\n"
          "owner), ring (every rank in turn, as barney), broadcast (every rank, closest hit\n"
          "wins, as Kilauea)")
      ->capture_default_str();
  command
      ->add_option(
          "--exchange", o.exchange,
          "How ranks exchange rays: overlapped (rays leave as soon as a batch is traced, in\n"
          "non-blocking messages, while the rank works on other chunks and bounces; no\n"
          "collective per round), bulk (the paper's: a whole-image wavefront per bounce, one\n"
          "all-to-all per round) or auto (overlapped; bulk for --forwarding broadcast)")
      ->capture_default_str();
  command
      ->add_option("--chunk", o.chunkPixels,
                   "Camera paths a rank takes at once (and the largest batch it traces at\n"
                   "once). The image is the same for any value.")
      ->capture_default_str();
  command
      ->add_option(
          "--path-layout", o.pathLayout,
          "The path on the wire: auto (8-rank mask, 64-rank mask, replay above 64 ranks),\n"
          "mask (visited ranks as a bit mask; up to 64 ranks) or replay (only the generating\n"
          "rank; any rank recomputes the visited ranks from the proxies)")
      ->capture_default_str();
  command
      ->add_option(
          "--retrace", o.retrace,
          "Which shaded paths re-trace their ray to recover the hit (the compact path carries\n"
          "none): remote (only those whose hit another rank found; a rank keeps the hits it\n"
          "found) or all (every one, as the paper). The image is the same.")
      ->capture_default_str();
  command
      ->add_option(
          "--instancing", o.instancing,
          "Which objects get an Embree instance level: shared (objects placed more than once\n"
          "or transformed; an object placed once, untransformed, is put in the top-level BVH,\n"
          "which saves every ray an instance transform) or always (every object). Instanced\n"
          "objects are never flattened either way. The image is the same.")
      ->capture_default_str();
  addPartitionFlags(command, o.partition, "--partitioner,--partition",
                    "Made on the fly on every rank; default: best on more than one rank. Not used\n"
                    "for a part directory (its manifest names the partitioner that made it).");
  command->add_flag("-q,--quiet", o.quiet, "No progress and no summary on the terminal");
  command->add_flag("--env-fallback", o.envFallback,
                    "Render a scene whose environment map is missing with a constant white\n"
                    "environment instead (the file is named in a warning)");
  command->add_option(
      "--field", o.field,
      "The array a VTK file is rendered by: a .vti's, .vtu's, .pvtu's or .vts's point or cell\n"
      "array, a .pvti's point array (default: its active scalars), a .vtp's radius (default:\n"
      "radius)");
  addCameraFlags(command, o.camera);
}

int parseVolumeBricks(const std::string& value) {
  if (value == "auto") return kAutoBricks;
  int voxels = -1;
  const char* end = value.data() + value.size();
  const auto [at, error] = std::from_chars(value.data(), end, voxels);
  if (error != std::errc() || at != end || voxels < 0)
    throw InputError(fmt::format(
        "--volume-bricks {}: expected auto, 0 (whole) or a brick size in voxels", value));
  return voxels;
}

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

void addRunOptions(CLI::App* command, RenderOptions& o) {
  command->add_option(
      "--checkpoint", o.checkpoint,
      "Write the accumulated image (exact sums), its frame count and a hash of the scene and\n"
      "settings to this file every --checkpoint-every frames and after the last, atomically;\n"
      "--resume continues from it");
  command->add_option("--checkpoint-every", o.checkpointEvery, "Frames between checkpoints")
      ->capture_default_str();
  command->add_option(
      "--resume", o.resume,
      "Continue the render a checkpoint holds (same scene, size, --spp, --max-depth, --seed\n"
      "and view; any rank count): frames after it up to --frames, with the image an\n"
      "uninterrupted render would give, bit for bit. May be the --checkpoint file itself.");
  command->add_option(
      "--aov", o.aov,
      "Also write these features of the surface each camera ray meets first, averaged over\n"
      "the pixel's samples like the colour (for denoisers): a comma list of albedo, normal,\n"
      "geometric-normal, depth, position, uv. As channels of an .exr output (Albedo.R,\n"
      "Ns.X, N.X, Z, P.X, u/v), or files beside a .pfm one (NAME.albedo.pfm); not for .png");
  command->add_option("--time-limit", o.timeLimit,
                      "Seconds: the frame that crosses it is the last (0: none); the image is\n"
                      "written as usual, with the frames done");
}

}  // namespace ferry
