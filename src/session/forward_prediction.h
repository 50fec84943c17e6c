// The bandwidth predictor (`ferry partition ... --predict-forwards`): how many
// rays a partition forwards per camera path, for a view, without MPI.
//
// It is the renderer itself on a sample: every rank of the part directory
// runs as a thread of this process (the in-process communicator), loads its
// part and renders the view once, 1 path per pixel, at a resolution of the
// requested image's aspect holding about `samplePaths` pixels. The rays go
// through the real forwarding operator (proxies, each part's geometry, the
// same layout and modes as `ferry render DIR`), and the counts come from the
// renderer's counters. A sample of pixels spread evenly over the image is a
// sample of the full image's camera paths: forwards per camera path do not
// depend on the resolution but through which paths are sampled, so the
// prediction's error is the sampling error of a ratio (docs/evaluation.md,
// "The bandwidth predictor", has the measured error).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "scene/scene.h"

namespace ferry {

struct ForwardPredictionOptions {
  int width = 2560;  // the image predicted for (its aspect shapes the sample): the paper's
  int height = 1080;
  uint64_t samplePaths = 16384;  // camera paths sampled (about: a whole grid of pixels)
  int maxDepth = 5;
  uint32_t seed = 1;
};

// A view to predict for: a named view of the scene, or a camera given outright.
struct PredictionView {
  std::string name;  // the named view (empty: the scene's first) or a label for `camera`
  std::optional<CameraView> camera;
};

struct ForwardPrediction {
  std::string view;
  CameraView camera;  // as rendered
  int sampleWidth = 0, sampleHeight = 0;
  uint64_t cameraPaths = 0;
  uint64_t raysForwarded = 0;
  uint64_t shadowRaysForwarded = 0;  // of raysForwarded
  uint64_t forwardedToShade = 0;     // of raysForwarded: sent to a hit owner only to be shaded
  uint64_t visitsWithoutHit = 0;     // of raysForwarded: found nothing where they were sent
  uint64_t bytesSent = 0;
  double seconds = 0;  // rendering the sample (the parts are loaded once for all views)

  double forwardsPerPath() const;
  nlohmann::json toJson() const;
};

// The sample's resolution: the aspect of width x height, about `paths` pixels.
void predictionSampleSize(const ForwardPredictionOptions& options, int& width, int& height);

// Predicts for every view, from the part directory `directory` (every rank
// loaded once). Throws InputError for an unknown view or a bad directory.
std::vector<ForwardPrediction> predictForwards(const std::string& directory,
                                               const std::vector<PredictionView>& views,
                                               const ForwardPredictionOptions& options);

}  // namespace ferry
