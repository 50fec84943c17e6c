// Analytic spheres, the first geometry kind beside triangle meshes, through
// every stage of the seam (scene/shape.h): exact crossings, both trace
// backends, shading (a Lambertian ball under a white sky shows its albedo),
// the partitioners and the distributed traversal (the same image on 1 and 3
// ranks), the memory model and part files (stored by kind name and read
// back through the registry).
#include "shapes/spheres.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "io/parts/part_file.h"
#include "io/scene_loader.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "partition/partitioner.h"
#include "partition/scene_split.h"
#include "render/render_test_util.h"
#include "scene/memory_cost.h"
#include "session/render_session.h"
#include "session/session_test_util.h"
#include "shapes/shape_kinds.h"
#include "trace/embree_backend.h"
#include "trace/reference_backend.h"

namespace ferry {
namespace {

using namespace ferry::testing;
namespace fs = std::filesystem;

TEST(Spheres, CrossingsAreExactAndRespectTheRange) {
  const Spheres s({{0, 0, 0}, {10, 0, 0}}, {1, 2});
  float t;
  Vec2f uv;
  ASSERT_TRUE(s.intersect(0, {0, 0, -5}, {0, 0, 1}, 0, kInfinity, t, uv));
  EXPECT_FLOAT_EQ(t, 4);
  const ShapeSurface front = s.surface(0, uv);
  EXPECT_NEAR(front.position.z, -1, 1e-6f);
  EXPECT_NEAR(front.geometricNormal.z, -1, 1e-6f);
  // From inside: the far side.
  ASSERT_TRUE(s.intersect(0, {0, 0, 0}, {0, 0, 1}, 0, kInfinity, t, uv));
  EXPECT_FLOAT_EQ(t, 1);
  // The range: tfar before the sphere, tnear past its front.
  EXPECT_FALSE(s.intersect(0, {0, 0, -5}, {0, 0, 1}, 0, 3.5f, t, uv));
  ASSERT_TRUE(s.intersect(0, {0, 0, -5}, {0, 0, 1}, 4.5f, kInfinity, t, uv));
  EXPECT_FLOAT_EQ(t, 6);
  // A miss, and a direction that is not unit.
  EXPECT_FALSE(s.intersect(0, {0, 1.01f, -5}, {0, 0, 1}, 0, kInfinity, t, uv));
  ASSERT_TRUE(s.intersect(1, {10, 0, -5}, {0, 0, 2}, 0, kInfinity, t, uv));
  EXPECT_FLOAT_EQ(t, 1.5f);
  // Far from the origin and grazing: the point found is on the sphere.
  TestRng rng(7);
  for (int k = 0; k < 1000; ++k) {
    const Vec3f o{1000 * rng.uniform() - 500, 1000 * rng.uniform() - 500, -1000};
    const Vec3f target{2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1};
    if (!s.intersect(0, o, normalize(target - o), 0, kInfinity, t, uv)) continue;
    const Vec3f p = s.surface(0, uv).position;
    EXPECT_NEAR(length(p), 1, 1e-4f);
    EXPECT_NEAR(length(o + normalize(target - o) * t - p), 0, 2e-3f);
  }
  EXPECT_EQ(s.bytes(), 2 * sizeof(Vec3f) + 2 * sizeof(float));
  EXPECT_THROW(Spheres({{0, 0, 0}}, {0}), InputError);
  EXPECT_THROW(Spheres({{0, 0, 0}}, {1, 2}), InputError);
}

// The Cornell box with 30 spheres of three materials: 20 placed once, and an
// object of 5 placed through three transformed instances.
Scene cornellWithSpheres() {
  Scene scene = loadScene("builtin:cornell");
  const int32_t white = scene.addMaterial(diffuseMaterial({0.7f, 0.7f, 0.7f}));
  Material glass = diffuseMaterial(Vec3f(1));
  glass.name = "glass";
  glass.model = std::make_shared<DielectricModel>(1.5f, 0.0f);
  Material metal = diffuseMaterial({0.9f, 0.6f, 0.3f});
  metal.name = "metal";
  metal.model = std::make_shared<ConductorModel>(0.2f);
  const int32_t glassId = scene.addMaterial(glass), metalId = scene.addMaterial(metal);
  const Box3f box = scene.worldBounds();
  TestRng rng(11);
  auto randomSpheres = [&](int n, float radius) {
    std::vector<Vec3f> centers;
    std::vector<float> radii;
    for (int k = 0; k < n; ++k) {
      const Vec3f u{rng.uniform(), rng.uniform(), rng.uniform()};
      centers.push_back(box.lower + box.size() * (u * 0.6f + Vec3f(0.2f)));
      radii.push_back(radius * (0.5f + rng.uniform()));
    }
    return std::make_shared<Spheres>(centers, radii);
  };
  const float r = 0.04f * maxComponent(box.size());
  scene.addSingleInstanceGeometry({"white spheres", white, randomSpheres(10, r)});
  scene.addSingleInstanceGeometry({"glass spheres", glassId, randomSpheres(10, r)});
  scene.geometries.push_back({"metal spheres", metalId, randomSpheres(5, r / 2)});
  Object metals;
  metals.name = "metal spheres";
  metals.geometries = {int32_t(scene.geometries.size() - 1)};
  scene.objects.push_back(metals);
  for (int k = 0; k < 3; ++k)
    scene.instances.push_back(
        {int32_t(scene.objects.size() - 1),
         Affine3f::translate(box.size() * Vec3f(0.05f * float(k - 1), 0.1f, 0))});
  scene.validate();
  return scene;
}

TEST(Spheres, BothBackendsFindTheSameSpheres) {
  const Scene scene = cornellWithSpheres();
  const auto embree = makeEmbreeBackend(scene), reference = makeReferenceBackend(scene);
  const Box3f box = scene.worldBounds();
  TestRng rng(3);
  int sphereHits = 0;
  for (int k = 0; k < 4000; ++k) {
    const Vec3f u{rng.uniform(), rng.uniform(), rng.uniform()};
    const Vec3f w{rng.uniform(), rng.uniform(), rng.uniform()};
    TraceRay ray;
    ray.origin = box.lower + box.size() * (u * 0.8f + Vec3f(0.1f));  // (not on a wall)
    ray.direction = normalize(box.lower + box.size() * w - ray.origin);
    const TraceHit a = embree->intersect(ray), b = reference->intersect(ray);
    ASSERT_EQ(a.valid(), b.valid()) << k;
    if (!a.valid()) continue;
    // (A grazing ray may meet two surfaces at the same t.)
    if (std::abs(a.t - b.t) > 1e-4f * std::max(1.0f, a.t))
      ADD_FAILURE() << k << ": " << a.t << " " << b.t << " inst " << a.instance << "/" << b.instance
                    << " slot " << a.slot << "/" << b.slot << " prim " << a.primitive << "/"
                    << b.primitive << " from " << ray.origin.x << "," << ray.origin.y << ","
                    << ray.origin.z;
    if (a.instance != b.instance || a.slot != b.slot) continue;
    EXPECT_EQ(a.primitive, b.primitive) << k;
    const Object& o = scene.objects[scene.instances[a.instance].object];
    sphereHits += size_t(a.slot) >= o.meshes.size();
    EXPECT_EQ(embree->occluded(ray), reference->occluded(ray));
  }
  EXPECT_GT(sphereHits, 100);
}

TEST(Spheres, ALambertianBallUnderAWhiteSkyShowsItsAlbedo) {
  Scene scene;
  const int32_t m = scene.addMaterial(diffuseMaterial({0.2f, 0.5f, 0.8f}));
  scene.addSingleInstanceGeometry(
      {"ball", m, std::make_shared<Spheres>(std::vector<Vec3f>{{0, 0, 0}}, std::vector<float>{1})});
  CameraView view;
  view.from = {0, 0, 10};
  view.at = {0, 0, 0};
  view.fovY = 5;  // only the ball
  const PixelStatistics stats = renderUnderWhiteSky(scene, view);
  const double z = twoSidedNormalQuantile(sidak(0.01, 3));
  const Vec3f albedo{0.2f, 0.5f, 0.8f};
  for (int k = 0; k < 3; ++k) {
    double mean, se;
    stats.imageMean(k, mean, se);
    EXPECT_NEAR(mean, albedo[k], z * se + 2 * kHalfRelativeError * albedo[k]) << k;
  }
}

const Communicator& oneRank() {
  static InProcessGroup group(1);
  return group.communicator(0);
}

std::vector<Vec3f> render(Scene scene, const SessionSettings& settings, const Communicator& comm) {
  return renderLinear(scene, settings, comm);
}

TEST(Spheres, TheImageIsTheSameOnOneAndThreeRanks) {
  const Scene scene = cornellWithSpheres();
  SessionSettings settings;
  settings.render.width = 48;
  settings.render.height = 40;
  settings.render.samplesPerPixel = 2;
  settings.render.maxDepth = 4;
  settings.render.frames = 1;
  const std::vector<Vec3f> one = render(scene, settings, oneRank());
  ASSERT_FALSE(one.empty());
  EXPECT_FALSE(render(loadScene("builtin:cornell"), settings, oneRank()) == one)
      << "the spheres are not in the picture";
  for (const Partitioner* partitioner : std::initializer_list<const Partitioner*>{
           &bestPartitioner(), &partitionerNamed("round-robin")}) {
    std::vector<Vec3f> three;
    runRanks(3, [&](const Communicator& comm) {
      SessionSettings s = settings;
      s.partitioner = partitioner;
      std::vector<Vec3f> image = render(scene, s, comm);
      if (comm.isRoot()) three = std::move(image);
    });
    EXPECT_TRUE(three == one) << partitioner->name();
  }
}

// Particles (builtin:particles): the best partitioner cuts the one large
// sphere set into spatial pieces that keep every sphere, and the image on 3
// ranks is the 1-rank image.
TEST(Spheres, ALargeSetIsCutIntoPiecesAndTheImageStaysTheSame) {
  const Scene scene = loadScene("builtin:particles?count=20000");
  Scene cut = scene;
  SceneSplitOptions options;
  options.maxPieceBytes = 20000 * 16 / 5;
  splitForPartitioning(cut, options);
  uint64_t spheres = 0, pieces = 0;
  for (const Geometry& g : cut.geometries)
    if (dynamic_cast<const Spheres*>(g.shape.get())) {
      spheres += g.shape->primitiveCount();
      ++pieces;
    }
  EXPECT_EQ(spheres, 20000u);
  EXPECT_GE(pieces, 5u);
  SessionSettings settings;
  settings.render.width = 40;
  settings.render.height = 30;
  settings.render.samplesPerPixel = 2;
  settings.render.maxDepth = 3;
  settings.render.frames = 1;
  const std::vector<Vec3f> one = render(scene, settings, oneRank());
  std::vector<Vec3f> three;
  runRanks(3, [&](const Communicator& comm) {
    SessionSettings s = settings;
    s.partitioner = &bestPartitioner();
    std::vector<Vec3f> image = render(scene, s, comm);
    if (comm.isRoot()) three = std::move(image);
  });
  EXPECT_TRUE(three == one);
}

// A rank searches only as far as the nearest hit the others found: a nearer
// tfar must give the same t or nothing, never another t.
TEST(Spheres, TheCrossingDoesNotDependOnHowFarTheRaySearches) {
  TestRng rng(5);
  int crossings = 0;
  for (int k = 0; k < 20000; ++k) {
    const Vec3f centre = Vec3f(rng.uniform(), rng.uniform(), rng.uniform()) * 200.0f;
    const float r = 0.01f + rng.uniform();
    const Spheres sphere({centre}, {r});
    const Vec3f origin = centre + normalize(Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f,
                                                  rng.uniform() - 0.5f)) *
                                      (50 * r);
    const Vec3f target =
        centre +
        Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * (2.2f * r);
    const Vec3f direction = target - origin;
    float t;
    Vec2f uv;
    if (!sphere.intersect(0, origin, direction, 0, kInfinity, t, uv)) continue;
    ++crossings;
    for (float tfar : {t * 0.9999f, t * 0.99999f, t * 0.999999f, t}) {
      float s;
      EXPECT_FALSE(sphere.intersect(0, origin, direction, 0, tfar, s, uv) && s != t)
          << k << ": t " << t << " searched to " << tfar << " gave " << s;
    }
    float s = 0;
    EXPECT_TRUE(sphere.intersect(0, origin, direction, 0, std::nextafter(t, kInfinity), s, uv));
    EXPECT_EQ(s, t);
  }
  EXPECT_GT(crossings, 5000);
}

TEST(Spheres, APartFileStoresThemByKindAndTheMemoryModelCountsThem) {
  const Scene scene = cornellWithSpheres();
  const Geometry& white = scene.geometries[0];
  const MemoryCost cost = geometryCost(white);
  EXPECT_EQ(cost.shapes, white.shape->bytes());
  EXPECT_GT(cost.accel, 0u);
  std::vector<RankSet> owners(scene.instances.size(), RankSet::single(0));
  std::vector<int32_t> all(scene.instances.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = int32_t(i);
  const fs::path path =
      fs::temp_directory_path() / fmt::format("ferry-spheres-{}.part", ::getpid());
  writePartFile(path.string(), scene, all, owners, 0, 1);
  const LoadedPart part = readPartFile(path.string());
  fs::remove(path);
  ASSERT_EQ(part.scene.geometries.size(), scene.geometries.size());
  for (size_t g = 0; g < scene.geometries.size(); ++g) {
    const auto* a = dynamic_cast<const Spheres*>(scene.geometries[g].shape.get());
    const auto* b = dynamic_cast<const Spheres*>(part.scene.geometries[g].shape.get());
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(a->centers(), b->centers());
    EXPECT_EQ(a->radii(), b->radii());
    EXPECT_EQ(scene.materials[scene.geometries[g].material].name,
              part.scene.materials[part.scene.geometries[g].material].name);
  }
  ASSERT_NE(shapeKind("spheres"), nullptr);
}

TEST(Spheres, AnEmissiveMaterialOnThemIsAnError) {
  Scene scene;
  Material lamp = diffuseMaterial(Vec3f(1));
  lamp.name = "lamp";
  lamp.emission = Vec3f(1);
  const int32_t m = scene.addMaterial(lamp);
  scene.addSingleInstanceGeometry(
      {"lamps", m,
       std::make_shared<Spheres>(std::vector<Vec3f>{{0, 0, 0}}, std::vector<float>{1})});
  try {
    scene.validate();
    FAIL() << "an emissive sphere was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("emits light"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ferry
