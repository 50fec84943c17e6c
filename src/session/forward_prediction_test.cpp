// The bandwidth predictor on a scene whose forwarding is known by
// construction, and the sample's shape.
#include "session/forward_prediction.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/error.h"
#include "io/parts/part_directory.h"
#include "render/render_test_util.h"
#include "scene/light_scene.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;
using testing::diffuseMaterial;
using testing::makeQuad;

// Rank 0 holds a wall at z = 0 facing the camera at z = 5. Rank 1 holds two
// specks far outside the view whose box, z in [2, 4], spans the whole view
// in front of the wall. Every camera ray enters rank 1's box first, so its
// path starts on rank 1, misses there, and is forwarded to rank 0 (whose box
// lies ahead), which finds the wall: one forward per camera path, exactly.
// At depth 0 no other ray is made. A camera between the two (at z = 1) meets
// rank 0's box first and finds the wall at once: no forward.
// With `wallBoxTop` 4.5 rank 0's box reaches past rank 1's: every camera ray
// starts on rank 0, finds the wall, is forwarded to rank 1 (whose box it
// enters before the wall), misses there, and is sent back to rank 0 only to
// be shaded: two forwards per camera path, one of them to be shaded.
struct KnownForwarding {
  fs::path dir = fs::temp_directory_path() / ("ferry-prediction-test-" + std::to_string(getpid()));

  explicit KnownForwarding(float wallBoxTop = 0.01f) {
    fs::remove_all(dir);
    Scene scene;
    const int32_t material = scene.addMaterial(diffuseMaterial({0.5f, 0.5f, 0.5f}));
    scene.addSingleInstanceMesh(makeQuad({-10, -10, 0}, {20, 0, 0}, {0, 20, 0}, material));
    Mesh specks;
    specks.name = "specks";
    specks.material = material;
    specks.positions = {{-20, -20, 2}, {-19.9f, -20, 2}, {-20, -19.9f, 2},
                        {20, 20, 4},   {19.9f, 20, 4},   {20, 19.9f, 4}};
    specks.indices = {{0, 1, 2}, {3, 4, 5}};
    scene.addSingleInstanceMesh(std::move(specks));
    CameraView view;
    view.name = "front";
    view.from = {0, 0, 5};
    view.at = {0, 0, 0};
    view.fovY = 30;
    scene.views.push_back(view);

    Partition partition;
    partition.ranks = 2;
    partition.instanceOwners = {RankSet::single(0), RankSet::single(1)};
    Box3f wall = scene.objectBounds(0);
    wall.lower.z -= 0.01f;
    wall.upper.z += wallBoxTop;
    partition.proxies = {{wall, RankSet::single(0)}, {scene.objectBounds(1), RankSet::single(1)}};
    partition.checkCovers(scene);
    PartDirectoryInfo info;
    info.scene = "known forwarding";
    info.partitioner = "by hand";
    info.summary = summarize(scene).toJson();
    writePartDirectory(dir.string(), scene, partition, lightScene(scene), info);
  }
  ~KnownForwarding() { fs::remove_all(dir); }
};

// 512 camera paths of 32x16, no bounce: every count is known.
ForwardPredictionOptions knownOptions() {
  ForwardPredictionOptions options;
  options.width = 64;
  options.height = 32;
  options.samplePaths = 512;
  options.maxDepth = 0;
  return options;
}

TEST(ForwardPrediction, ExactWhereTheForwardingIsKnownByConstruction) {
  KnownForwarding scene;
  CameraView between;
  between.from = {0, 0, 1};
  between.at = {0, 0, 0};
  between.fovY = 30;
  const ForwardPredictionOptions options = knownOptions();
  const std::vector<ForwardPrediction> p =
      predictForwards(scene.dir.string(), {{"front", std::nullopt}, {"between", between}}, options);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].view, "front");
  EXPECT_EQ(p[0].sampleWidth, 32);
  EXPECT_EQ(p[0].sampleHeight, 16);
  EXPECT_EQ(p[0].cameraPaths, 512u);
  EXPECT_EQ(p[0].raysForwarded, 512u);
  EXPECT_EQ(p[0].forwardsPerPath(), 1.0);
  EXPECT_EQ(p[0].shadowRaysForwarded, 0u);
  EXPECT_EQ(p[0].forwardedToShade, 0u);
  EXPECT_EQ(p[0].visitsWithoutHit, 0u);  // rank 0 finds the wall every ray is sent for
  EXPECT_GT(p[0].bytesSent, 0u);
  EXPECT_EQ(p[1].view, "between");
  EXPECT_EQ(p[1].camera.from.z, 1.0f);
  EXPECT_EQ(p[1].cameraPaths, 512u);
  EXPECT_EQ(p[1].raysForwarded, 0u);
  EXPECT_THROW(predictForwards(scene.dir.string(), {{"nowhere", std::nullopt}}, options),
               InputError);
}

// The forward to rank 1 finds nothing there (a visit without a hit, the
// proxy's looseness), and the ray goes back to be shaded.
TEST(ForwardPrediction, ARaySentBackToItsHitIsCountedAsSentToShade) {
  KnownForwarding scene(4.5f);
  const std::vector<ForwardPrediction> p =
      predictForwards(scene.dir.string(), {{"front", std::nullopt}}, knownOptions());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].cameraPaths, 512u);
  EXPECT_EQ(p[0].raysForwarded, 1024u);
  EXPECT_EQ(p[0].forwardedToShade, 512u);
  EXPECT_EQ(p[0].shadowRaysForwarded, 0u);
  EXPECT_EQ(p[0].visitsWithoutHit, 512u);
  EXPECT_EQ(p[0].toJson().at("forwarded_to_shade"), 512u);
  EXPECT_EQ(p[0].toJson().at("visits_without_hit"), 512u);
}

TEST(ForwardPrediction, SampleKeepsTheImagesAspectAndNeverExceedsIt) {
  ForwardPredictionOptions o;
  int w = 0, h = 0;
  predictionSampleSize(o, w, h);  // 2560x1080, 16384 paths
  EXPECT_EQ(w, 197);
  EXPECT_EQ(h, 83);
  o.width = 40;
  o.height = 30;
  predictionSampleSize(o, w, h);  // more paths than pixels: the image itself
  EXPECT_EQ(w, 40);
  EXPECT_EQ(h, 30);
  o.samplePaths = 0;
  EXPECT_THROW(predictionSampleSize(o, w, h), InputError);
}

}  // namespace
}  // namespace ferry
