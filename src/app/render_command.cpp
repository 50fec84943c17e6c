#include "app/render_command.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <memory>
#include <optional>

#include "api/session_on.h"
#include "app/partition_command.h"
#include "app/progress.h"
#include "comm/communicator.h"
#include "core/clock.h"
#include "core/error.h"
#include "io/images/image_io.h"
#include "session/image_file_sink.h"
#include "session/session_stats.h"

namespace ferry {
namespace {

// The library's options for the command line: the flags with a field of
// their own, and every other rendering flag given by name (Options::settings).
api::Options libraryOptions(const RenderOptions& o) {
  api::Options options;
  if (o.sizeGiven) parseImageSize(o.size, options.width, options.height);
  options.samplesPerPixel = o.samplesPerPixel;
  options.maxDepth = o.maxDepthGiven ? o.maxDepth : -1;
  options.seed = o.seed;
  options.threads = o.threads;
  options.partitioner = o.partition.partitioner;
  static const char* const own[] = {"scene", "size",    "spp",         "max-depth",
                                    "seed",  "threads", "frames",      "output",
                                    "stats", "quiet",   "partitioner", "show-partition"};
  for (const auto& [name, value] : o.given)
    if (std::find(std::begin(own), std::end(own), name) == std::end(own))
      options.settings[name] = value;
  return options;
}

// The file the image goes to: -o, else the scene's own (pbrt's Film
// "filename") when it is a format Ferry writes.
std::string outputFile(const RenderOptions& o, const std::string& film) {
  if (o.outputGiven || film.empty()) return o.output;
  if (imageFormatOf(film)) {
    checkOutputPath(film);
    return film;
  }
  fmt::print(stderr,
             "ferry: warning: the scene's output file {} has an unsupported format; writing {}\n",
             film, o.output);
  return o.output;
}

// Progress on rank 0's terminal: loading in tenths, rendering as a bar.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(const RenderOptions& o, bool talk)
      : loading_("load", 1, talk), talk_(talk), frames_(o.frames), spp_(o.samplesPerPixel) {
    loading_.update(0, o.scene);
  }
  void operator()(const api::Progress& p) {
    if (!talk_) return;
    if (p.stage == "load") {
      if (p.finished) return loading_.finish(p.what + " s");
      const int tenth = p.total ? int(10 * p.done / p.total) : 10;
      if (tenth == lastTenth_) return;
      lastTenth_ = tenth;
      fmt::print(stderr, "load: {}% of {}\n", tenth * 10, p.what);
      return;
    }
    if (!rendering_) rendering_.emplace("render", frames_ * spp_, talk_);
    if (p.finished) return rendering_->finish();
    rendering_->update(int(p.done), p.secondsLeft < 0 ? fmt::format("frame {}", p.frame + 1)
                                                      : fmt::format("frame {}, {:.0f} s left",
                                                                    p.frame + 1, p.secondsLeft));
  }

 private:
  Progress loading_;
  std::optional<Progress> rendering_;
  bool talk_;
  int frames_, spp_;
  int lastTenth_ = -1;
};

}  // namespace

void addRenderCommand(CLI::App& app, RenderOptions& o) {
  CLI::App* render = app.add_subcommand(
      "render",
      "Path trace a scene and write the image. Run under mpirun to spread the scene over ranks:\n"
      "  mpirun -np 4 ferry render builtin:island -o island.png\n"
      "The image is the same whatever the rank count, --threads, --partition, --forwarding,\n"
      "--exchange or --chunk (the frame buffer sums in fixed point).");
  addRenderingOptions(render, o);
  render->add_option("--frames", o.frames, "Frames to render and accumulate progressively")
      ->capture_default_str();
  render
      ->add_option("-o,--output", o.output,
                   "Output image: .png (tone mapped), .exr or .pfm (linear radiance)")
      ->capture_default_str();
  render->add_option(
      "--stats", o.statsPath,
      "Write counters (rays traced, forwarded, bytes sent, rounds per bounce), timings and\n"
      "memory per rank as JSON to this file");
  addRunOptions(render, o);
  render->add_flag(
      "--show-partition{-1}", o.showPartition,
      "Instead of rendering, draw what each rank owns (replicated content checkerboarded)\n"
      "and the proxies as box outlines, to -o (PNG); =N: for N ranks (default: the MPI ranks)");
  render->callback([&o, render]() {
    o.sizeGiven = render->get_option("--size")->count() > 0;
    o.maxDepthGiven = render->get_option("--max-depth")->count() > 0;
    o.outputGiven = render->get_option("--output")->count() > 0;
    for (const CLI::Option* option : render->get_options())
      if (option->count() > 0 && !option->get_lnames().empty()) {
        std::string value;
        for (const std::string& part : option->results()) value += part;
        o.given[option->get_lnames().front()] = value;
      }
  });
}

int runRender(const RenderOptions& o, const Communicator& comm) {
  if (o.showPartition != 0) return runShowPartition(o, comm);
  const auto start = Clock::now();
  auto printer = std::make_shared<ProgressPrinter>(o, comm.isRoot() && !o.quiet);
  std::optional<api::Session> session;
  std::string error;
  try {
    if (o.frames < 1) throw InputError(fmt::format("--frames {}: must be at least 1", o.frames));
    checkOutputPath(o.output);
    api::Options options = libraryOptions(o);
    options.progress = [printer](const api::Progress& p) { (*printer)(p); };
    session.emplace(sessionOn(comm, nullptr, options));
    session->load(o.scene);
  } catch (const std::exception& e) {
    error = e.what();
  }
  // Errors while setting up are usually the same on every rank: report once, exit cleanly.
  if (comm.agreeOnFailure(!error.empty(), error)) return 1;
  std::string output;
  try {
    session->prepare();  // collective; an error is thrown on every rank
    output = outputFile(o, session->filmFilename());
    if (!o.aov.empty() && imageFormatOf(output) == ImageFormat::Png)
      throw InputError(
          fmt::format("--aov {} with -o {}: a PNG holds no AOVs; write .exr (AOVs as "
                      "channels) or .pfm (AOVs as files beside it)",
                      o.aov, output));
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (comm.agreeOnFailure(!error.empty(), error)) return 1;

  // An error while rendering ends every rank (the library aborts the job);
  // alone, or while writing files after the last collective, only this rank.
  try {
    const api::Image image = session->render(o.frames);
    if (!comm.isRoot()) return 0;
    api::writeImage(output, image, o.exposure);
    const api::Stats& stats = session->stats();
    if (!o.quiet) fmt::print("{}  {:<22}{}\n", stats.summary, "wrote", output);
    if (!o.statsPath.empty()) {
      nlohmann::json json = nlohmann::json::parse(stats.json);
      json["settings"]["output"] = output;
      json["seconds"]["total"] = secondsSince(start);
      writeStatsFile(o.statsPath, json);
    }
    return 0;
  } catch (const std::exception& e) {
    // The library's errors are thrown on every rank alike: said once.
    if (comm.isRoot()) fmt::print(stderr, "ferry: error: {}\n", e.what());
    return 1;
  }
}

}  // namespace ferry
