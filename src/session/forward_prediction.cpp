#include "session/forward_prediction.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

#include "comm/in_process_communicator.h"
#include "core/clock.h"
#include "core/error.h"
#include "io/parts/manifest.h"
#include "session/render_session.h"

namespace ferry {
namespace {

// Counts only: the image is not wanted.
class DiscardingSink final : public FrameSink {
 public:
  Frames frames() const override { return Frames::Last; }
  Pixels pixels() const override { return Pixels::Linear; }
  void receive(const FrameImage&) override {}
};

nlohmann::json vectorJson(const Vec3f& v) {
  return {v.x, v.y, v.z};
}

}  // namespace

double ForwardPrediction::forwardsPerPath() const {
  return cameraPaths ? double(raysForwarded) / double(cameraPaths) : 0.0;
}

nlohmann::json ForwardPrediction::toJson() const {
  return {{"view", view},
          {"camera",
           {{"from", vectorJson(camera.from)},
            {"at", vectorJson(camera.at)},
            {"up", vectorJson(camera.up)},
            {"fov", camera.fovY}}},
          {"sample_size", {sampleWidth, sampleHeight}},
          {"camera_paths", cameraPaths},
          {"rays_forwarded", raysForwarded},
          {"shadow_rays_forwarded", shadowRaysForwarded},
          {"forwarded_to_shade", forwardedToShade},
          {"visits_without_hit", visitsWithoutHit},
          {"bytes_sent", bytesSent},
          {"forwards_per_path", forwardsPerPath()},
          {"seconds", seconds}};
}

void predictionSampleSize(const ForwardPredictionOptions& o, int& width, int& height) {
  if (o.width < 1 || o.height < 1 || o.samplePaths < 1)
    throw InputError(
        fmt::format("predicting forwards for a {}x{} image from {} paths: expected "
                    "a positive size and path count",
                    o.width, o.height, o.samplePaths));
  const double aspect = double(o.width) / double(o.height);
  const double paths = double(std::min<uint64_t>(o.samplePaths, uint64_t(o.width) * o.height));
  width = std::clamp(int(std::lround(std::sqrt(paths * aspect))), 1, o.width);
  height = std::clamp(int(std::lround(paths / double(width))), 1, o.height);
}

std::vector<ForwardPrediction> predictForwards(const std::string& directory,
                                               const std::vector<PredictionView>& views,
                                               const ForwardPredictionOptions& o) {
  const Manifest manifest = readManifest(directory);
  SessionSettings settings;
  settings.scene = directory;
  predictionSampleSize(o, settings.render.width, settings.render.height);
  settings.render.samplesPerPixel = 1;
  settings.render.frames = 1;
  settings.render.maxDepth = o.maxDepth;
  settings.render.seed = o.seed;
  std::vector<ForwardPrediction> predictions(views.size());
  runRanks(manifest.ranks, [&](const Communicator& comm) {
    RenderSession session(settings, comm);
    for (size_t v = 0; v < views.size(); ++v) {
      session.setView(views[v].name, views[v].camera);
      const auto start = Clock::now();
      DiscardingSink sink;
      const SessionReport report = session.run(sink);
      if (!comm.isRoot()) continue;
      ForwardPrediction& p = predictions[v];
      p.camera = views[v].camera ? *views[v].camera : session.scene().view(views[v].name);
      p.view = views[v].camera ? views[v].name : p.camera.name;
      p.sampleWidth = settings.render.width;
      p.sampleHeight = settings.render.height;
      const FrameStats total = report.stats.total();
      const ExchangeCounters exchange = total.exchangeTotal();
      p.cameraPaths = total.cameraPaths;
      p.raysForwarded = exchange.raysForwarded;
      p.shadowRaysForwarded = exchange.shadowRaysForwarded;
      p.forwardedToShade = exchange.forwardedToShade;
      p.visitsWithoutHit = exchange.visitsWithoutHit;
      p.bytesSent = exchange.bytesSent;
      p.seconds = secondsSince(start);
    }
  });
  return predictions;
}

}  // namespace ferry
