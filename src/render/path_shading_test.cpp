// The shading steps one vertex at a time (render/path_shading.h): what a path
// adds to its pixel and which rays it makes, into which slot, with which
// flags, for escaped paths, emitters, diffuse and delta vertices, the depth
// limit and the two-sided rule; and the shadow ray's tmax against the
// emitter's plane along the direction as stored.
#include "render/path_shading.h"
#include "material/models/conductor.h"
#include "trace/embree_backend.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

constexpr uint32_t kPixel = 5;
constexpr uint32_t kUntouched = 77;  // pixel of a slot shading must not write
constexpr uint32_t kMaxDepth = 4;

// A diffuse floor (y = 0, normal +y), a mirror wall (x = 3, facing -x), an
// emissive ceiling panel (y = 4, facing down), under a constant sky and a sun.
struct ShadingScene {
  Scene scene;
  std::unique_ptr<TraceBackend> geometry;
  std::unique_ptr<LightSampler> lights;
  std::unique_ptr<PathShading<Path8>> shading;
  Vec3f sky{0.2f, 0.3f, 0.5f};
  Vec3f emission{4, 3, 2};

  ShadingScene() {
    scene.name = "shading";
    const int32_t diffuse = scene.addMaterial(diffuseMaterial({0.5f, 0.6f, 0.7f}));
    Material mirror;
    mirror.name = "mirror";
    mirror.model = std::make_shared<ConductorModel>(0.0f);
    const int32_t mirrorId = scene.addMaterial(mirror);
    Material panel = diffuseMaterial({0.1f, 0.1f, 0.1f});
    panel.emission = emission;
    const int32_t panelId = scene.addMaterial(panel);
    scene.addSingleInstanceMesh(makeQuad({-2, 0, 2}, {4, 0, 0}, {0, 0, -4}, diffuse));
    scene.addSingleInstanceMesh(makeQuad({3, 0, -2}, {0, 0, 4}, {0, 3, 0}, mirrorId));
    scene.addSingleInstanceMesh(makeQuad({-1, 4, -1}, {0, 0, 2}, {2, 0, 0}, panelId));
    scene.environment.color = sky;
    SunLight sun;
    sun.direction = normalize(Vec3f{-0.3f, 1, 0.2f});
    scene.suns.push_back(sun);
    CameraView view;
    scene.views.push_back(view);
    geometry = makeEmbreeBackend(scene);
    lights = std::make_unique<LightSampler>(scene);
    shading = std::make_unique<PathShading<Path8>>(scene, *lights, kMaxDepth, 1);
  }

  // A path from `origin` along `direction`, traced as the traversal would:
  // its tmax and hit owner set when it hits, and its hit.
  Path8 path(Vec3f origin, Vec3f direction, Vec3f weight, uint32_t flags, TraceHit& hit) const {
    Path8 p{};
    makeRay(p, origin, normalize(direction), kInfinity, weight, kPixel, flags);
    hit = geometry->intersect(TraceRay{p.origin, p.dir(), 0, kInfinity});
    if (hit.valid()) {
      p.tmax = hit.t;
      p.setHit(0, 0);
    }
    return p;
  }

  struct Result {
    PathShading<Path8>::Spawned spawned;
    Path8 continuation{}, shadowRay{};
    Vec3f pixel;  // what the frame buffer got
  };
  Result shade(const Path8& p, const TraceHit& hit, uint32_t bounce) const {
    Result r;
    r.continuation.setPixelAndFlags(kUntouched, 0);
    r.shadowRay.setPixelAndFlags(kUntouched, 0);
    FrameBuffer fb(16, 1);
    r.spawned = shading->shadePath(p, hit, 3, bounce, fb, r.continuation, r.shadowRay);
    for (uint32_t i = 0; i < fb.pixelCount(); ++i)
      if (i != kPixel) {
        EXPECT_EQ(maxComponent(fb.sum()[i]), 0) << "pixel " << i;
      }
    r.pixel = fb.sum()[kPixel];
    // A slot is written exactly when its ray is made.
    EXPECT_EQ(r.continuation.pixel() == kUntouched, !r.spawned.continuation);
    EXPECT_EQ(r.shadowRay.pixel() == kUntouched, !r.spawned.shadowRay);
    return r;
  }
};

void expectNear(Vec3f a, Vec3f b) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-3f * std::abs(b[k]) + 1e-6f) << k;
}

TEST(PathShading, EscapedPathAddsTheSkyOnlyAfterTheCameraOrADeltaVertex) {
  ShadingScene s;
  TraceHit hit;
  const Vec3f weight{0.5f, 1, 2};
  const Path8 afterCamera = s.path({0, 1, 0}, {0.3f, 1, -0.5f}, weight, kPathAfterSpecular, hit);
  ASSERT_FALSE(afterCamera.hasHit());
  const auto r = s.shade(afterCamera, hit, 1);
  EXPECT_FALSE(r.spawned.continuation || r.spawned.shadowRay);
  expectNear(r.pixel, weight * s.sky);

  const Path8 afterDiffuse = s.path({0, 1, 0}, {0.3f, 1, -0.5f}, weight, 0, hit);
  EXPECT_EQ(maxComponent(s.shade(afterDiffuse, hit, 1).pixel), 0);
}

TEST(PathShading, EmitterCountsOnlyAfterTheCameraOrADeltaVertex) {
  ShadingScene s;
  TraceHit hit;
  const Vec3f weight{1, 0.5f, 0.25f};
  const Path8 afterCamera = s.path({0, 1, 0}, {0.1f, 1, 0.1f}, weight, kPathAfterSpecular, hit);
  ASSERT_TRUE(afterCamera.hasHit());
  expectNear(s.shade(afterCamera, hit, 0).pixel, weight * s.emission);

  const Path8 afterDiffuse = s.path({0, 1, 0}, {0.1f, 1, 0.1f}, weight, 0, hit);
  EXPECT_EQ(maxComponent(s.shade(afterDiffuse, hit, 1).pixel), 0);
}

TEST(PathShading, DiffuseVertexMakesAContinuationAndAShadowRay) {
  ShadingScene s;
  TraceHit hit;
  const Path8 p = s.path({0.5f, 2, 0.5f}, {-0.2f, -1, 0.1f}, Vec3f(1), kPathAfterSpecular, hit);
  ASSERT_TRUE(hit.valid());
  const auto r = s.shade(p, hit, 0);
  EXPECT_EQ(maxComponent(r.pixel), 0);  // the floor does not emit
  ASSERT_TRUE(r.spawned.continuation);
  ASSERT_TRUE(r.spawned.shadowRay);
  const Path8& c = r.continuation;
  EXPECT_EQ(c.pixel(), kPixel);
  EXPECT_EQ(c.flags(), 0u);  // not a shadow ray, not after a delta lobe
  EXPECT_GT(c.dir().y, 0);
  EXPECT_GT(c.origin.y, 0);  // moved off the floor, on the arriving side
  EXPECT_LT(c.origin.y, 1e-3f);
  EXPECT_EQ(c.tmax, kInfinity);
  EXPECT_FALSE(c.hasHit());
  const Path8& sh = r.shadowRay;
  EXPECT_EQ(sh.pixel(), kPixel);
  EXPECT_EQ(sh.flags(), uint32_t(kPathShadow));
  EXPECT_GT(sh.dir().y, 0);
  EXPECT_GT(maxComponent(sh.weight()), 0);
  EXPECT_FALSE(sh.hasHit());
}

TEST(PathShading, TheDepthLimitStopsAVertexAfterItsEmission) {
  ShadingScene s;
  TraceHit hit;
  const Path8 floor = s.path({0.5f, 2, 0.5f}, {-0.2f, -1, 0.1f}, Vec3f(1), 0, hit);
  const auto r = s.shade(floor, hit, kMaxDepth);
  EXPECT_FALSE(r.spawned.continuation || r.spawned.shadowRay);
  EXPECT_TRUE(s.shade(floor, hit, 0).spawned.continuation);  // (0: before roulette)

  const Path8 panel = s.path({0, 1, 0}, {0.1f, 1, 0.1f}, Vec3f(1), kPathAfterSpecular, hit);
  expectNear(s.shade(panel, hit, kMaxDepth).pixel, s.emission);
}

TEST(PathShading, DeltaVertexContinuesAfterSpecularWithoutALightSample) {
  ShadingScene s;
  TraceHit hit;
  const Vec3f d = normalize(Vec3f{1, 0.1f, 0.2f});
  const Path8 p = s.path({0, 1, 0}, d, Vec3f(1), 0, hit);
  ASSERT_TRUE(hit.valid());
  const auto r = s.shade(p, hit, 0);  // (0: before roulette)
  ASSERT_TRUE(r.spawned.continuation);
  EXPECT_FALSE(r.spawned.shadowRay);
  EXPECT_EQ(r.continuation.flags(), uint32_t(kPathAfterSpecular));
  // Mirrored about the wall (x = 3, normal -x), to half precision.
  const Vec3f reflected{-d.x, d.y, d.z};
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.continuation.dir()[k], reflected[k], 2e-3f) << k;
  EXPECT_LT(r.continuation.origin.x, 3);
}

TEST(PathShading, OpaqueSurfacesAreShadedOnTheSideThePathArrivesFrom) {
  ShadingScene s;
  TraceHit hit;
  const Path8 p = s.path({0.5f, -2, 0.5f}, {0.2f, 1, -0.1f}, Vec3f(1), 0, hit);
  ASSERT_TRUE(hit.valid());
  const auto r = s.shade(p, hit, 0);  // (0: before roulette)
  ASSERT_TRUE(r.spawned.continuation);
  EXPECT_LT(r.continuation.dir().y, 0);
  EXPECT_LT(r.continuation.origin.y, 0);
  // Light from below only (the sky surrounds the scene; the sun is above).
  if (r.spawned.shadowRay) {
    EXPECT_LT(r.shadowRay.dir().y, 0);
    EXPECT_LT(r.shadowRay.origin.y, 0);
  }
}

// The shadow ray as stored (its direction in half precision) must stop before
// the emitter's plane, or the emitter shadows itself; and close to it.
TEST(PathShading, ShadowRayStopsShortOfTheEmitterPlaneAlongItsStoredDirection) {
  struct Point {
    double x, y, z;
  };
  auto toDouble = [](Vec3f v) { return Point{v.x, v.y, v.z}; };
  auto dotD = [](Point a, Point b) { return a.x * b.x + a.y * b.y + a.z * b.z; };
  int checked = 0, planeDecides = 0;
  for (uint32_t i = 0; i < 20000; ++i) {
    RandomStream random(RandomKey{i, 0, 0, 9});
    const Vec3f position{random(RandomDim::BsdfU) * 20 - 10, random(RandomDim::BsdfV) * 2,
                         random(RandomDim::BsdfLobe) * 20 - 10};
    // A point on a light plane tilted up to grazing (emitters are two-sided).
    const float tilt = random(RandomDim::LightSelect) * 1.55f;
    LightSample light;
    light.normal = normalize(Vec3f{std::sin(tilt), -std::cos(tilt), 0});
    const Vec3f onLight{random(RandomDim::LightSampleU) * 40 - 20, 30,
                        random(RandomDim::LightSampleV) * 40 - 20};
    const Vec3f toLight = onLight - position;
    light.distance = length(toLight);
    light.direction = toLight * (1 / light.distance);
    // Nearer grazing the plane's distance itself is below float precision.
    const float cosLight = std::abs(dot(light.direction, light.normal));
    if (cosLight < 0.01f) continue;
    ++checked;
    const Vec3f origin = offsetRayOrigin(position, {0, 1, 0});
    Path8 ray{};
    const Vec3f stored =
        makeRay(ray, origin, light.direction, kInfinity, Vec3f(1), 0, uint32_t(kPathShadow));
    const float tmax = shadowRayTmax(position, origin, stored, light);
    planeDecides += tmax < length(onLight - origin) / length(stored) * (1 - 1e-4f);
    // Where the stored ray ends, exactly (in double), against the plane.
    const Point o = toDouble(origin), d = toDouble(stored), q = toDouble(onLight);
    const Point n = toDouble(light.normal);
    const Point end{o.x + d.x * tmax, o.y + d.y * tmax, o.z + d.z * tmax};
    const double originSide = dotD({o.x - q.x, o.y - q.y, o.z - q.z}, n);
    const double endSide = dotD({end.x - q.x, end.y - q.y, end.z - q.z}, n);
    ASSERT_GT(endSide * originSide, 0) << "ray " << i << " reaches the emitter's plane";
    const double reach = tmax * std::sqrt(dotD(d, d));
    ASSERT_LT(reach, light.distance) << "ray " << i;
    // Short by the direction's rounding (< 5e-4 rad) over the cosine at the light.
    ASSERT_GT(reach, light.distance * (1 - 1e-3 / cosLight)) << "ray " << i;
  }
  EXPECT_GT(checked, 15000);
  EXPECT_GT(planeDecides, 1000);  // cases where the plane, not the distance, stops the ray
}

}  // namespace
}  // namespace ferry
