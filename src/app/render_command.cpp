#include "app/render_command.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <charconv>
#include <chrono>
#include <fstream>
#include <memory>

#include "app/image_output.h"
#include "app/progress.h"
#include "core/error.h"
#include "core/process_memory.h"
#include "io/image_io.h"
#include "io/scene_loader.h"
#include "render/lights.h"
#include "render/path.h"
#include "render/ray_traversal.h"
#include "render/wavefront_renderer.h"
#include "scene/scene_summary.h"
#include "trace/local_geometry.h"

namespace ferry {
namespace {

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void validate(const RenderOptions& o) {
  if (o.samplesPerPixel < 1) throw InputError(fmt::format("--spp {}: must be at least 1", o.samplesPerPixel));
  if (o.frames < 1) throw InputError(fmt::format("--frames {}: must be at least 1", o.frames));
  if (o.maxDepth < 0) throw InputError(fmt::format("--max-depth {}: must be 0 or more", o.maxDepth));
  if (o.threads < 0) throw InputError(fmt::format("--threads {}: must be 0 (all) or more", o.threads));
  checkOutputPath(o.output);
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
      "Path trace a scene and write the image.\n"
      "The image is the same whatever --threads (and, distributed, whatever the rank count).");
  render->add_option("scene", o.scene,
                     "Scene file (.obj) or built-in: builtin:island, builtin:landscape, builtin:cornell,\n"
                     "builtin:furnace, with parameters as builtin:island?scale=4&seed=7")
      ->capture_default_str();
  render->add_option("--size", o.size, "Image size WIDTHxHEIGHT")->capture_default_str();
  render->add_option("--spp", o.samplesPerPixel, "Samples (paths) per pixel in each frame")
      ->capture_default_str();
  render->add_option("--frames", o.frames, "Frames to render and accumulate progressively")
      ->capture_default_str();
  render->add_option("--max-depth", o.maxDepth,
                     "Maximum scattering events per path (1: direct light only, 0: emitters only)")
      ->capture_default_str();
  render->add_option("--view", o.view, "Named camera view of the scene (default: its first view)");
  render->add_option("--seed", o.seed, "Seed of every random number; same seed, same image")
      ->capture_default_str();
  render->add_option("--threads", o.threads, "Worker threads per process (0: all cores)")
      ->capture_default_str();
  render->add_option("-o,--output", o.output,
                     "Output image: .png (tone mapped), .exr or .pfm (linear radiance)")
      ->capture_default_str();
  render->add_option("--stats", o.statsPath, "Write counters, timings and memory as JSON to this file");
  render->add_option("--exposure", o.exposure, "Exposure in stops for the PNG tone mapping")
      ->capture_default_str();
  render->add_flag("-q,--quiet", o.quiet, "No progress and no summary on the terminal");
}

int runRender(const RenderOptions& o) {
  validate(o);
  RenderSettings settings;
  parseImageSize(o.size, settings.width, settings.height);
  settings.samplesPerPixel = o.samplesPerPixel;
  settings.frames = o.frames;
  settings.maxDepth = o.maxDepth;
  settings.seed = o.seed;
  settings.view = o.view;
  settings.toneMapping.exposure = o.exposure;

  std::unique_ptr<tbb::global_control> threadLimit;
  if (o.threads > 0)
    threadLimit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);

  auto start = std::chrono::steady_clock::now();
  Progress loading("load", 2, !o.quiet);
  loading.update(0, o.scene);
  Scene scene = loadScene(o.scene);
  scene.view(settings.view);  // fail on an unknown view before building anything
  double loadSeconds = secondsSince(start);
  loading.update(1, "building acceleration structures");
  auto buildStart = std::chrono::steady_clock::now();
  LocalGeometry geometry(scene);
  LightSampler lights(scene);
  double buildSeconds = secondsSince(buildStart);
  loading.finish(fmt::format("{:.2f} s load, {:.2f} s build", loadSeconds, buildSeconds));

  LocalTraversal<Path8> traversal(geometry);
  WavefrontRenderer<Path8> renderer(scene, geometry, lights, traversal, settings);
  FrameBuffer frameBuffer(settings.width, settings.height);
  RenderStats stats;
  Progress rendering("render", settings.frames * settings.samplesPerPixel, !o.quiet);
  for (int frame = 0; frame < settings.frames; ++frame) {
    stats.frames.push_back(renderer.renderFrame(frame, frameBuffer, [&](int done, int) {
      rendering.update(frame * settings.samplesPerPixel + done, fmt::format("frame {}", frame + 1));
    }));
  }
  rendering.finish();

  const float scale = 1.0f / float(settings.frames * settings.samplesPerPixel);
  std::vector<Vec3f> image(frameBuffer.sum());
  for (Vec3f& v : image) v = v * scale;
  writeRenderedImage(o.output, settings.width, settings.height, image, settings.toneMapping);

  SceneSummary summary = summarize(scene);
  ProcessMemory memory = readProcessMemory();
  if (!o.quiet) {
    fmt::print("{}", stats.summaryText(1));
    fmt::print("  {:<22}{} estimated, {} Embree (peak {}), {} resident (peak {})\n", "memory",
               formatBytes(summary.memory.total()), formatBytes(uint64_t(geometry.embreeBytes())),
               formatBytes(uint64_t(geometry.embreePeakBytes())), formatBytes(memory.residentBytes),
               formatBytes(memory.peakResidentBytes));
    fmt::print("  {:<22}{}\n", "wrote", o.output);
  }
  if (!o.statsPath.empty()) {
    nlohmann::json j;
    j["scene"] = summary.toJson();
    j["settings"] = {{"width", settings.width},     {"height", settings.height},
                     {"spp", settings.samplesPerPixel}, {"frames", settings.frames},
                     {"max_depth", settings.maxDepth},  {"seed", settings.seed},
                     {"view", o.view},                  {"threads", o.threads},
                     {"ranks", 1},                      {"output", o.output}};
    j["render"] = stats.toJson();
    j["memory"] = {{"estimated_bytes", summary.memory.total()},
                   {"embree_bytes", geometry.embreeBytes()},
                   {"embree_peak_bytes", geometry.embreePeakBytes()},
                   {"resident_bytes", memory.residentBytes},
                   {"peak_resident_bytes", memory.peakResidentBytes}};
    j["seconds"] = {{"load", loadSeconds}, {"build", buildSeconds}, {"total", secondsSince(start)}};
    writeFileAtomically(o.statsPath, [&](const std::string& tmp) {
      std::ofstream out(tmp);
      out << j.dump(2) << "\n";
      if (!out) throw InputError(fmt::format("{}: could not write", o.statsPath));
    });
  }
  return 0;
}

}  // namespace ferry
