// Volume bricks (shapes/volume_brick.h): a brick's lookups are the whole
// grid's, its collisions a function of the ray alone (whatever tfar a rank
// traces with) and distributed as delta tracking's, a volume cut into many
// bricks passes light as one does; a white furnace of bricks stays white;
// the image of bricks over surfaces is the same on 1, 2, 3, 4 and 8 ranks
// with either partitioner and exchange; part files store bricks.
#include "shapes/volume_brick.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "io/parts/part_file.h"
#include "io/scene_loader.h"
#include "partition/partitioner.h"
#include "render/render_test_util.h"
#include "scene/scene.h"
#include "session/render_session.h"
#include "session/session_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;
namespace fs = std::filesystem;

// A grid of n^3 samples, value(x, y, z) each.
template <typename Value>
std::shared_ptr<DensityGrid> makeGrid(int n, Value&& value) {
  std::vector<float> values;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) values.push_back(value(x, y, z));
  return std::make_shared<DensityGrid>(n, n, n, std::move(values));
}

std::shared_ptr<VolumeBrick::Volume> greyVolume(int n, const Box3f& box, float sigmaT,
                                                float albedo = 0.8f) {
  auto v = std::make_shared<VolumeBrick::Volume>();
  v->dims = {n, n, n};
  v->gridFromWorld = Affine3f::scale({1 / box.size().x, 1 / box.size().y, 1 / box.size().z}) *
                     Affine3f::translate(-box.lower);
  v->sigmaS = Vec3f(sigmaT * albedo);
  v->sigmaA = Vec3f(sigmaT) - v->sigmaS;
  return v;
}

// Bricks of `size` cells of `grid`.
std::vector<std::shared_ptr<VolumeBrick>> cutAll(std::shared_ptr<const VolumeBrick::Volume> v,
                                                 const DensityGrid& grid, int size) {
  std::vector<std::shared_ptr<VolumeBrick>> bricks;
  std::array<int, 3> lo, hi;
  for (lo[2] = 0; lo[2] < grid.nz(); lo[2] += size)
    for (lo[1] = 0; lo[1] < grid.ny(); lo[1] += size)
      for (lo[0] = 0; lo[0] < grid.nx(); lo[0] += size) {
        for (int a = 0; a < 3; ++a) hi[a] = std::min(lo[a] + size, v->dims[a]);
        bricks.push_back(VolumeBrick::cut(v, grid, lo, hi));
      }
  return bricks;
}

// The nearest collision over all bricks (what a trace over them finds).
bool nearest(const std::vector<std::shared_ptr<VolumeBrick>>& bricks, Vec3f o, Vec3f d, float tfar,
             float& t) {
  bool found = false;
  for (const auto& b : bricks) {
    float s;
    Vec2f uv;
    if (b->intersect(0, o, d, 0, tfar, s, uv)) {
      tfar = s;
      t = s;
      found = true;
    }
  }
  return found;
}

TEST(VolumeBrick, LooksUpWhatTheWholeGridHolds) {
  const int n = 13;
  auto grid = makeGrid(n, [](int x, int y, int z) { return float((x * 7 + y * 3 + z * 5) % 11); });
  auto volume = greyVolume(n, {{0, 0, 0}, {1, 1, 1}}, 1);
  TestRng rng(3);
  for (const auto& brick : cutAll(volume, *grid, 4)) {
    for (int k = 0; k < 200; ++k) {
      Vec3f p;
      for (int a = 0; a < 3; ++a)
        p[a] = (float(brick->lo()[a]) + rng.uniform() * float(brick->hi()[a] - brick->lo()[a])) /
               float(n);
      EXPECT_FLOAT_EQ(brick->lookup(p), grid->lookup(p)) << brick->describe();
    }
  }
}

TEST(VolumeBrick, ACollisionDependsOnTheRayNotOnTfar) {
  const int n = 16;
  auto grid = makeGrid(n, [](int x, int y, int z) { return float((x + y + z) % 4) * 0.5f; });
  auto volume = greyVolume(n, {{-1, -1, -1}, {1, 1, 1}}, 3);
  const auto brick = VolumeBrick::cut(volume, *grid, {0, 0, 0}, {16, 16, 16});
  TestRng rng(11);
  int found = 0;
  for (int k = 0; k < 500; ++k) {
    const Vec3f o{4 * rng.uniform() - 2, 4 * rng.uniform() - 2, -3};
    const Vec3f d = normalize(Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, 1));
    float t;
    Vec2f uv;
    if (!brick->intersect(0, o, d, 0, kInfinity, t, uv)) continue;
    ++found;
    float again;
    ASSERT_TRUE(brick->intersect(0, o, d, 0, t * 1.5f, again, uv));
    EXPECT_EQ(again, t);
    ASSERT_TRUE(brick->intersect(0, o, d, 0, std::nextafter(t, kInfinity), again, uv));
    EXPECT_EQ(again, t);
    EXPECT_FALSE(brick->intersect(0, o, d, 0, t, again, uv));
    EXPECT_FALSE(brick->intersect(0, o, d, 0, t * 0.999f, again, uv));
  }
  EXPECT_GT(found, 100);
}

// Rays through a slab of constant extinction pass it with probability
// exp(-sigma_t L), whether the slab is one brick or 64.
TEST(VolumeBrick, CollisionsAreDistributedAsDeltaTrackingsOverManyBricks) {
  const int n = 16;
  const float sigmaT = 0.7f;
  auto grid = makeGrid(n, [](int, int, int) { return 1.0f; });
  auto volume = greyVolume(n, {{0, 0, 0}, {4, 4, 4}}, sigmaT);
  // Inside the samples' centres the value is exactly 1: from z = 0.5 to 3.5
  // (an eighth of a cell of 0.25 from each face, past the half-cell fade).
  const float z0 = 0.2f, length = 3.6f;
  for (int size : {16, 4}) {
    const auto bricks = cutAll(volume, *grid, size);
    TestRng rng(5);
    const int rays = 20000;
    int passed = 0;
    for (int k = 0; k < rays; ++k) {
      const Vec3f o{0.5f + 3 * rng.uniform(), 0.5f + 3 * rng.uniform(), z0};
      const Vec3f d =
          normalize(Vec3f(0.1f * (rng.uniform() - 0.5f), 0.1f * (rng.uniform() - 0.5f), 1));
      float t;
      // Everything between 0.125 and 3.875 is value 1 (the centres of the
      // first and last samples); the fade below 0.125 lies before z0.
      if (!nearest(bricks, o, d, length, t)) ++passed;
    }
    // Along d the slab is a little longer than `length` in z: measure the t range.
    const double expected = std::exp(-double(sigmaT) * length);
    const double p = double(passed) / rays;
    const double se = std::sqrt(expected * (1 - expected) / rays);
    // The rays' ends stay within z <= 3.8 (length 3.6 from 0.2), where the
    // value is 1 up to z = 3.875: the expectation is exact.
    EXPECT_NEAR(p, expected, 4 * se) << size << "-voxel bricks";
  }
}

Scene volumeOverFloor(float albedo, bool floor) {
  Scene scene;
  scene.name = "bricks";
  scene.addMaterial(diffuseMaterial({0.6f, 0.5f, 0.4f}));
  if (floor) {
    scene.addSingleInstanceMesh(makeQuad({-3, 0, 3}, {6, 0, 0}, {0, 0, -6}, 0));
    scene.addSingleInstanceMesh(makeSphere({1.6f, 0.5f, 0.8f}, 0.5f, 12, 24, 0));
  }
  const Box3f box{{-1, 0.1f, -1}, {1, 1.5f, 1}};
  const int n = 24;
  std::vector<float> values;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) values.push_back(float((x / 3 + 2 * (y / 3) + z / 3) % 4) * 0.5f);
  scene.media.push_back(gridMedium("cloud", Vec3f(3 * (1 - albedo)), Vec3f(3 * albedo), 0.3f,
                                   std::make_shared<DensityGrid>(n, n, n, values),
                                   Affine3f::identity(), box));
  scene.mediumBoundaries.push_back({boxMesh(box, "box"), {0, kNoMedium}});
  scene.environment.color = {0.8f, 0.9f, 1.0f};
  CameraView view;
  view.from = {0, 2, 5};
  view.at = {0, 0.6f, 0};
  scene.views.push_back(view);
  return scene;
}

TEST(VolumeBrick, BrickingReplacesAMediumThatFillsItsBox) {
  Scene scene = volumeOverFloor(0.8f, true);
  const size_t meshes = scene.meshes.size();
  EXPECT_EQ(brickVolumes(scene, 8), 1u);
  EXPECT_TRUE(scene.media.empty());
  EXPECT_TRUE(scene.mediumBoundaries.empty());
  EXPECT_EQ(scene.meshes.size(), meshes);
  EXPECT_EQ(scene.geometries.size(), 27u);  // 24^3 in 8^3 bricks; none is empty
  EXPECT_TRUE(scene.hasVolumes());
  scene.validate();
  // A medium a surface bounds (glass with fog) stays whole.
  Scene glass = volumeOverFloor(0.8f, true);
  glass.meshes[1].media = {0, kNoMedium};
  EXPECT_EQ(brickVolumes(glass, 8), 0u);
  EXPECT_EQ(glass.media.size(), 1u);
}

// A white furnace of bricks: grey scattering of albedo 1 under a white sky
// leaves every pixel at 1.
TEST(VolumeBrick, AWhiteFurnaceOfBricksStaysWhite) {
  Scene scene = volumeOverFloor(1.0f, false);
  scene.environment.color = Vec3f(1);
  scene.views[0].from = {0, 0.8f, 4};
  scene.views[0].at = {0, 0.8f, 0};
  scene.views[0].fovY = 20;
  ASSERT_EQ(brickVolumes(scene, 6), 1u);
  RenderSettings settings;
  settings.width = settings.height = 12;
  settings.samplesPerPixel = 16;
  settings.maxDepth = 200;
  const PixelStatistics stats = renderStatistics(scene, settings, 6);
  const double z = twoSidedNormalQuantile(sidak(0.01, 3));
  for (int k = 0; k < 3; ++k) {
    double mean, se;
    stats.imageMean(k, mean, se);
    EXPECT_NEAR(mean, 1.0, z * se + 4 * kHalfRelativeError) << k;
  }
  // The trace counts the bricks' tracking with the media's counters.
  RenderSetup setup(scene, settings);
  FrameStats frame;
  setup.frameMean(0, &frame);
  EXPECT_GT(frame.mediumRealCollisions, 0u);
  EXPECT_GT(frame.mediumNullCollisions, 0u);
  EXPECT_GE(frame.mediumMajorantCells, frame.mediumRealCollisions);
  // The same bricks absorbing half of what they scatter are seen: darker.
  Scene grey = volumeOverFloor(0.5f, false);
  grey.environment.color = Vec3f(1);
  grey.views = scene.views;
  ASSERT_EQ(brickVolumes(grey, 6), 1u);
  const PixelStatistics absorbing = renderStatistics(grey, settings, 2);
  double mean, se;
  absorbing.imageMean(0, mean, se);
  EXPECT_LT(mean, 0.85);
}

std::vector<Vec3f> render(const Scene& scene, const SessionSettings& settings,
                          const Communicator& comm) {
  return renderLinear(scene, settings, comm);
}

TEST(VolumeBrick, TheImageIsTheSameOnOneToEightRanks) {
  Scene scene = volumeOverFloor(0.8f, true);
  ASSERT_EQ(brickVolumes(scene, 6), 1u);  // 64 bricks: rays cross many ranks
  SessionSettings settings;
  settings.render.width = 40;
  settings.render.height = 30;
  settings.render.samplesPerPixel = 2;
  settings.render.maxDepth = 5;
  std::vector<Vec3f> one;
  runRanks(1, [&](const Communicator& comm) { one = render(scene, settings, comm); });
  ASSERT_FALSE(one.empty());
  // The bricks are in the picture: without them it differs.
  Scene empty = volumeOverFloor(0.8f, true);
  empty.media.clear();
  empty.mediumBoundaries.clear();
  std::vector<Vec3f> without;
  runRanks(1, [&](const Communicator& comm) { without = render(empty, settings, comm); });
  EXPECT_FALSE(without == one);
  struct Case {
    int ranks;
    const char* partitioner;
    ExchangeMode exchange;
  };
  for (const Case& c :
       {Case{2, "best", ExchangeMode::Auto}, Case{3, "round-robin", ExchangeMode::Auto},
        Case{4, "best", ExchangeMode::Bulk}, Case{8, "best", ExchangeMode::Auto}}) {
    std::vector<Vec3f> image;
    runRanks(c.ranks, [&](const Communicator& comm) {
      SessionSettings s = settings;
      s.partitioner = &partitionerNamed(c.partitioner);
      s.exchange = c.exchange;
      std::vector<Vec3f> mine = render(scene, s, comm);
      if (comm.isRoot()) image = std::move(mine);
    });
    EXPECT_TRUE(image == one) << c.ranks << " ranks, " << c.partitioner;
  }
}

TEST(VolumeBrick, APartFileStoresBricks) {
  Scene scene = volumeOverFloor(0.8f, false);
  ASSERT_EQ(brickVolumes(scene, 8), 1u);
  std::vector<RankSet> owners(scene.instances.size(), RankSet::single(0));
  std::vector<int32_t> all(scene.instances.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = int32_t(i);
  const fs::path path = fs::temp_directory_path() / fmt::format("ferry-bricks-{}.part", ::getpid());
  writePartFile(path.string(), scene, all, owners, 0, 1);
  const LoadedPart part = readPartFile(path.string());
  fs::remove(path);
  ASSERT_EQ(part.scene.geometries.size(), scene.geometries.size());
  TestRng rng(2);
  for (size_t g = 0; g < scene.geometries.size(); ++g) {
    const auto* a = dynamic_cast<const VolumeBrick*>(scene.geometries[g].shape.get());
    const auto* b = dynamic_cast<const VolumeBrick*>(part.scene.geometries[g].shape.get());
    ASSERT_NE(b, nullptr);
    EXPECT_TRUE(b->samplesShared()) << "a brick read from a part file is not copied";
    EXPECT_EQ(a->lo(), b->lo());
    EXPECT_EQ(a->hi(), b->hi());
    EXPECT_EQ(a->majorant(), b->majorant());
    for (int k = 0; k < 20; ++k) {
      const Vec3f o{4 * rng.uniform() - 2, 4 * rng.uniform() - 2, -4};
      const Vec3f d =
          normalize(Vec3f(0.5f * (rng.uniform() - 0.5f), 0.5f * (rng.uniform() - 0.5f), 1));
      float ta = -1, tb = -1;
      Vec2f uv;
      EXPECT_EQ(a->intersect(0, o, d, 0, kInfinity, ta, uv),
                b->intersect(0, o, d, 0, kInfinity, tb, uv));
      EXPECT_EQ(ta, tb);
    }
  }
}

// --volume-bricks auto: large grids only, about a sixteenth of the largest
// side, 32 to 128 voxels, a multiple of 8; a function of the grid alone.
TEST(VolumeBrick, AutomaticSizeDependsOnTheGridAlone) {
  EXPECT_EQ(autoBrickVoxels({64, 64, 64}), 0);
  EXPECT_EQ(autoBrickVoxels({255, 256, 256}), 0);  // just under 2^24 samples
  EXPECT_EQ(autoBrickVoxels({256, 256, 256}), 32);
  EXPECT_EQ(autoBrickVoxels({512, 512, 512}), 32);
  EXPECT_EQ(autoBrickVoxels({1024, 1024, 1024}), 64);
  EXPECT_EQ(autoBrickVoxels({1400, 1024, 700}), 80);
  EXPECT_EQ(autoBrickVoxels({4096, 4096, 4096}), 128);
  EXPECT_EQ(autoBrickVoxels({16777216, 1, 1}), 128);
}

// Auto leaves small grids whole and bricks large ones at their size.
TEST(VolumeBrick, AutomaticBrickingSkipsSmallGrids) {
  for (const auto& [n, bricked] : {std::pair{32, false}, std::pair{256, true}}) {
    Scene scene = loadScene(fmt::format("builtin:volume?size={}", n));
    const size_t geometries = scene.geometries.size();
    EXPECT_EQ(brickVolumes(scene, kAutoBricks), bricked ? 1u : 0u) << n;
    size_t bricks = 0;
    for (const Geometry& g : scene.geometries) bricks += g.shape && g.shape->isVolume();
    if (bricked) {
      EXPECT_GT(bricks, 0u);
      EXPECT_LE(bricks, 8u * 8u * 8u);  // 32^3 bricks of a 256^3 grid, empty ones left out
      EXPECT_TRUE(scene.media.empty()) << "the bricked medium is gone";
    } else {
      EXPECT_EQ(scene.geometries.size(), geometries);
      ASSERT_EQ(scene.media.size(), 1u);
      EXPECT_TRUE(scene.media[0].density) << "a medium left whole is left as it was";
    }
  }
}

// A brick restyled after it is made crosses rays as a brick made with the
// restyled transfer function: the same majorants (from the kept value
// ranges) and the same collisions.
TEST(VolumeBrick, RestyledEqualsMadeRestyled) {
  const int n = 16;
  std::vector<float> values(size_t(n * n * n));
  TestRng fill(3);
  for (float& v : values) v = fill.uniform();
  const DensityGrid grid(n, n, n, values);
  auto plain = std::make_shared<VolumeBrick::Volume>();
  plain->dims = {n, n, n};
  plain->transfer = std::make_shared<const TransferFunction>(TransferFunction::standard());
  auto styled = std::make_shared<VolumeBrick::Volume>(*plain);
  styled->transfer = std::make_shared<const TransferFunction>(
      restyled(TransferFunction::standard(), VolumeLook{3, "inferno"}));
  const std::array<int, 3> lo{4, 0, 8}, hi{12, 9, 16};
  std::shared_ptr<VolumeBrick> a = VolumeBrick::cut(plain, grid, lo, hi);
  const std::shared_ptr<VolumeBrick> b = VolumeBrick::cut(styled, grid, lo, hi);
  ASSERT_NE(a->majorant(), b->majorant());
  a->restyle(styled);
  EXPECT_EQ(a->majorant(), b->majorant());
  TestRng rng(4);
  for (int k = 0; k < 200; ++k) {
    const Vec3f o{rng.uniform(), rng.uniform(), -1};
    const Vec3f d =
        normalize(Vec3f(0.3f * (rng.uniform() - 0.5f), 0.3f * (rng.uniform() - 0.5f), 1));
    float ta = -1, tb = -1;
    Vec2f uv;
    EXPECT_EQ(a->intersect(0, o, d, 0, kInfinity, ta, uv),
              b->intersect(0, o, d, 0, kInfinity, tb, uv));
    EXPECT_EQ(ta, tb);
    const Vec3f p{0.25f + 0.5f * rng.uniform(), 0.5f * rng.uniform(), 0.5f + 0.5f * rng.uniform()};
    EXPECT_EQ(a->volumeAlbedo(0, p), b->volumeAlbedo(0, p));
  }
  auto other = std::make_shared<VolumeBrick::Volume>(*styled);
  other->dims = {n, n, n + 1};
  EXPECT_THROW(a->restyle(other), InputError);
}

}  // namespace
}  // namespace ferry
