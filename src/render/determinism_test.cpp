// Every random number is a pure function of (pixel, sample, bounce, dimension,
// seed) and every stage writes each pixel at most once, so an image must not
// depend on the thread count, on the run, or on the path's rank-mask width;
// and must depend on the seed. Checked bit for bit on a scene with everything
// that branches: textures, alpha cut-outs, smooth and rough glass, a rough
// metal, an area light, a sun and an environment.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

Texture checker() {
  Texture t;
  t.name = "checker";
  t.width = t.height = 8;
  t.rgba.resize(8 * 8 * 4);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      uint8_t* p = &t.rgba[(y * 8 + x) * 4];
      bool dark = (x + y) % 2;
      p[0] = dark ? 40 : 220;
      p[1] = dark ? 90 : 200;
      p[2] = dark ? 30 : 160;
      p[3] = 255;
    }
  return t;
}

// Stripes of holes, as on a leaf card.
Texture stripes() {
  Texture t;
  t.name = "stripes";
  t.width = t.height = 16;
  t.srgb = false;
  t.rgba.assign(16 * 16 * 4, 255);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) t.rgba[(y * 16 + x) * 4 + 3] = (x / 2) % 2 ? 0 : 255;
  return t;
}

Scene busyScene() {
  Scene scene;
  scene.name = "busy";
  scene.textures = {checker(), stripes()};

  Material ground = diffuseMaterial(Vec3f(1));
  ground.baseColorTexture = 0;
  int32_t groundId = scene.addMaterial(ground);
  // Large enough that every camera ray hits something (so every pixel is noisy).
  scene.addSingleInstanceMesh(makeQuad({-40, 0, 40}, {80, 0, 0}, {0, 0, -80}, groundId));
  for (Vec2f& uv : scene.meshes.back().uvs) uv = uv * 60.0f;

  Material leaf = diffuseMaterial({0.2f, 0.6f, 0.1f});
  leaf.alphaTexture = 1;
  int32_t leafId = scene.addMaterial(leaf);
  scene.addSingleInstanceMesh(makeQuad({-1.5f, 0, -0.5f}, {1.2f, 0, 0}, {0, 1.5f, 0.2f}, leafId));

  Material glass;
  glass.name = "glass";
  glass.baseColor = Vec3f(1);
  glass.model = std::make_shared<DielectricModel>(1.5f, 0.0f);
  scene.addSingleInstanceMesh(
      makeSphere({0.4f, 0.5f, 0.3f}, 0.5f, 16, 32, scene.addMaterial(glass), true));

  Material frosted = glass;
  frosted.name = "frosted";
  frosted.model = std::make_shared<DielectricModel>(1.5f, 0.4f);
  frosted.baseColor = {0.9f, 0.95f, 1};
  scene.addSingleInstanceMesh(
      makeSphere({-0.6f, 0.35f, 0.8f}, 0.35f, 12, 24, scene.addMaterial(frosted)));

  Material metal;
  metal.name = "metal";
  metal.baseColor = {0.95f, 0.7f, 0.4f};
  metal.model = std::make_shared<ConductorModel>(0.3f);
  scene.addSingleInstanceMesh(
      makeSphere({1.3f, 0.4f, -0.4f}, 0.4f, 12, 24, scene.addMaterial(metal), true));

  Material lamp;
  lamp.name = "lamp";
  lamp.baseColor = Vec3f(0);
  lamp.emission = {6, 5, 4};
  scene.addSingleInstanceMesh(
      makeQuad({-0.5f, 2.2f, -0.5f}, {0, 0, 1}, {1, 0, 0}, scene.addMaterial(lamp)));

  SunLight sun;
  sun.direction = normalize(Vec3f{0.4f, 0.8f, 0.3f});
  sun.irradiance = {3, 2.8f, 2.5f};
  sun.angularRadius = 0.02f;
  scene.suns.push_back(sun);
  scene.environment.color = {0.2f, 0.3f, 0.5f};

  CameraView view;
  view.from = {0.5f, 1.6f, 3.5f};
  view.at = {0, 0.2f, 0};
  view.fovY = 45;
  scene.views.push_back(view);
  return scene;
}

RenderSettings busySettings(uint32_t seed) {
  RenderSettings s;
  s.width = 48;
  s.height = 32;
  s.samplesPerPixel = 3;
  s.frames = 2;
  s.maxDepth = 8;
  s.seed = seed;
  return s;
}

// Builds everything (Embree structures included) and renders, under a thread limit.
// LocalTraversal, except that it does not say it keeps every primary: the
// renderer then sends the whole image through one wavefront (as on many ranks).
template <typename Path>
struct WholeImageTraversal final : RayTraversal<Path> {
  explicit WholeImageTraversal(const TraceBackend& geometry) : local(geometry) {}
  void traverse(RayQueues<Path>& rays, std::vector<TraceHit>& pathHits, ExchangeCounters& e,
                FrameStats& s) override {
    local.traverse(rays, pathHits, e, s);
  }
  bool anyRaysLeft(size_t n) override { return n > 0; }
  LocalTraversal<Path> local;
};

// Builds everything (Embree structures included) and renders, under a thread
// limit; chunk > 0 sets the pixels per thread of a one-rank wavefront, -1
// sends the whole image through each wavefront.
template <typename Path>
std::vector<Vec3f> render(uint32_t seed, int threads, bool retraceAll = false, int chunk = 0,
                          bool lightPaths = false, CropWindow crop = {}) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  Scene scene = busyScene();
  RenderSettings s = busySettings(seed);
  s.retraceAll = retraceAll;
  s.lightPaths = lightPaths;
  s.crop = crop;
  if (chunk > 0) s.chunkPixels = uint32_t(chunk);
  const std::unique_ptr<TraceBackend> backend = makeEmbreeBackend(scene);
  const TraceBackend& geometry = *backend;
  LightSampler lights(scene);
  std::unique_ptr<RayTraversal<Path>> traversalHolder;
  if (chunk < 0)
    traversalHolder = std::make_unique<WholeImageTraversal<Path>>(geometry);
  else
    traversalHolder = std::make_unique<LocalTraversal<Path>>(geometry);
  RayTraversal<Path>& traversal = *traversalHolder;
  WavefrontRenderer<Path> renderer(scene, geometry, lights, traversal, s);
  FrameBuffer fb(s.imageWidth(), s.imageHeight());
  for (int f = 0; f < s.frames; ++f) {
    FrameStats stats = renderer.renderFrame(f, fb);
    EXPECT_EQ(stats.retraceMisses, 0u);
    // One rank keeps every hit it found: nothing to re-trace unless asked to.
    if (retraceAll)
      EXPECT_GT(stats.retraces, 0u);
    else
      EXPECT_EQ(stats.retraces, 0u);
  }
  return fb.sum();
}

bool bitIdentical(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3f)) == 0;
}

size_t differingPixels(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(Vec3f)) != 0;
  return n;
}

TEST(Determinism, ImageIsBitIdenticalAcrossThreadCountsRunsAndMaskWidths) {
  std::vector<Vec3f> one = render<Path8>(1, 1);
  std::vector<Vec3f> two = render<Path8>(1, 2);
  std::vector<Vec3f> again = render<Path8>(1, 2);
  std::vector<Vec3f> wide = render<Path64>(1, 2);

  // Not a trivial image: most pixels lit, and no non-finite values.
  size_t lit = 0;
  for (const Vec3f& v : one) {
    ASSERT_TRUE(isFinite(v));
    lit += maxComponent(v) > 0;
  }
  EXPECT_GT(lit, one.size() * 9 / 10);

  EXPECT_TRUE(bitIdentical(one, two))
      << differingPixels(one, two) << " pixels differ between 1 and 2 threads";
  EXPECT_TRUE(bitIdentical(two, again))
      << differingPixels(two, again) << " pixels differ between two runs";
  EXPECT_TRUE(bitIdentical(two, wide))
      << differingPixels(two, wide) << " pixels differ between Path8 and Path64";
}

// Keeping the hit (the default) or re-tracing every shaded path (--retrace
// all, the paper) must give the same image, bit for bit.
TEST(Determinism, KeepingHitsOrRetracingGivesTheSameImage) {
  std::vector<Vec3f> kept = render<Path8>(1, 2, false);
  std::vector<Vec3f> retraced = render<Path8>(1, 2, true);
  EXPECT_TRUE(bitIdentical(kept, retraced))
      << differingPixels(kept, retraced)
      << " pixels differ between --retrace remote and --retrace all";
  std::vector<Vec3f> retracedOneThread = render<Path64>(1, 1, true);
  EXPECT_TRUE(bitIdentical(kept, retracedOneThread))
      << differingPixels(kept, retracedOneThread)
      << " pixels differ (--retrace all, 1 thread, Path64)";
}

// One rank sends its pixels through the wavefront in chunks (for the cache);
// the chunk size must not show in the image.
TEST(Determinism, PixelChunksDoNotChangeTheImage) {
  std::vector<Vec3f> whole = render<Path8>(1, 2, false, -1);
  for (int chunk : {100, 700}) {  // 48 x 32 pixels: many chunks, and chunks that split rows
    std::vector<Vec3f> chunked = render<Path8>(1, 2, false, chunk);
    EXPECT_TRUE(bitIdentical(whole, chunked))
        << differingPixels(whole, chunked) << " pixels differ, chunk " << chunk;
  }
}

// Light paths add to any pixel from any thread (atomically, in fixed
// point): the image still must not depend on threads, chunks, the whole-image
// wavefront, re-tracing or the mask width; and they must change it.
TEST(Determinism, LightPathsAreBitIdenticalAcrossThreadsChunksAndLayouts) {
  std::vector<Vec3f> one = render<Path8>(1, 1, false, 0, true);
  EXPECT_FALSE(bitIdentical(one, render<Path8>(1, 1))) << "light paths changed nothing";
  std::vector<Vec3f> two = render<Path8>(1, 2, false, 0, true);
  EXPECT_TRUE(bitIdentical(one, two)) << differingPixels(one, two) << " pixels differ (threads)";
  for (int chunk : {-1, 100}) {
    std::vector<Vec3f> other = render<Path8>(1, 2, false, chunk, true);
    EXPECT_TRUE(bitIdentical(one, other))
        << differingPixels(one, other) << " differ, chunk " << chunk;
  }
  std::vector<Vec3f> wide = render<Path64>(1, 2, true, 0, true);
  EXPECT_TRUE(bitIdentical(one, wide)) << differingPixels(one, wide) << " differ (Path64, retrace)";
  std::vector<Vec3f> replay = render<PathReplay>(1, 2, false, 0, true);
  EXPECT_TRUE(bitIdentical(one, replay)) << differingPixels(one, replay) << " differ (replay)";
}

// A crop window (--crop, pbrt's cropwindow) renders the whole image's
// pixels there, bit for bit: random numbers are keyed by the film's pixel.
TEST(Determinism, ACropIsThePartOfTheWholeImage) {
  const std::vector<Vec3f> whole = render<Path8>(1, 2);
  const RenderSettings settings = busySettings(1);
  const CropWindow crop{0.25f, 0.8f, 0.3f, 0.6f};
  const FilmWindow w = filmWindow(settings.width, settings.height, crop);
  ASSERT_LT(w.width, settings.width);
  ASSERT_LT(w.height, settings.height);
  const std::vector<Vec3f> part = render<Path8>(1, 2, false, 0, false, crop);
  ASSERT_EQ(part.size(), size_t(w.width) * size_t(w.height));
  std::vector<Vec3f> expected;
  for (int y = w.y0; y < w.y0 + w.height; ++y)
    for (int x = w.x0; x < w.x0 + w.width; ++x)
      expected.push_back(whole[size_t(y) * size_t(settings.width) + size_t(x)]);
  EXPECT_TRUE(bitIdentical(part, expected)) << differingPixels(part, expected) << " pixels differ";
}

TEST(Determinism, DifferentSeedsGiveDifferentImages) {
  std::vector<Vec3f> a = render<Path8>(1, 2);
  std::vector<Vec3f> b = render<Path8>(2, 2);
  // Noise differs nearly everywhere (a pixel seeing only a constant
  // environment through nothing could agree, but this view has none).
  EXPECT_GT(differingPixels(a, b), a.size() * 9 / 10);
}

}  // namespace
}  // namespace ferry
