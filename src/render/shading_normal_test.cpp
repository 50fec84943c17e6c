// Bump maps and normal maps (render/surface.cpp, perturbShadingNormal), and
// the shading frame's treatment of shading normals that turn away from the
// viewer (path_shading.cpp, shadingFrame):
//  - a bump map's slope tilts the normal by atan(slope), as pbrt's Bump();
//  - a normal map's texel is read in the tangent frame of the uvs;
//  - a plane with strongly tilted shading normals under a white sky is
//    nowhere black and never brighter than its albedo (no blackening, no
//    light leaking).
#include <gtest/gtest.h>

#include <cmath>

#include "render/render_test_util.h"
#include "render/surface.h"

namespace ferry {
namespace {

using namespace ferry::testing;

// A flat 8-bit linear texture of `width` x 1 texels from a function of u.
template <typename F>
Texture rampTexture(int width, F value) {
  Texture t;
  t.name = "ramp";
  t.srgb = false;
  t.width = width;
  t.height = 1;
  t.wrap = WrapMode::Clamp;
  for (int x = 0; x < width; ++x) {
    const Vec3f v = value((x + 0.5f) / float(width));
    for (int k = 0; k < 3; ++k)
      t.rgba.push_back(uint8_t(std::lround(std::clamp(v[k], 0.0f, 1.0f) * 255)));
    t.rgba.push_back(255);
  }
  return t;
}

// A 4 x 4 square in the xz plane facing +y, u along +x and v along -z.
Scene texturedSquare(Material material) {
  Scene scene;
  scene.name = "square";
  const int32_t m = scene.addMaterial(material);
  scene.addSingleInstanceMesh(makeQuad({-2, 0, 2}, {4, 0, 0}, {0, 0, -4}, m));
  return scene;
}

SurfacePoint surfaceAtCentre(const Scene& scene) {
  TraceHit hit;
  hit.instance = 0;
  hit.slot = 0;
  hit.primitive = 0;  // corners 0, 1, 2: barycentrics put the point at uv (0.75, 0.25)
  hit.u = 0.5f;
  hit.v = 0.25f;
  return reconstructSurface(scene, hit);
}

TEST(ShadingNormals, ABumpRampTiltsTheNormalByItsSlope) {
  // Displacement 0.8 * u over 4 units of x: slope 0.2 along +x, so the
  // normal tilts towards -x by atan(0.2).
  Scene scene;
  Material material = diffuseMaterial(Vec3f(0.5f));
  material.bumpScale = 0.8f;
  material.bumpTexture = 0;
  scene = texturedSquare(material);
  scene.textures.push_back(rampTexture(256, [](float u) { return Vec3f(u); }));
  const SurfacePoint s = surfaceAtCentre(scene);
  EXPECT_NEAR(s.uv.x, 0.75f, 1e-5f);
  EXPECT_EQ(s.geometricNormal, Vec3f(0, 1, 0));
  const float expected = std::atan(0.2f);
  EXPECT_NEAR(std::atan2(-s.shadingNormal.x, s.shadingNormal.y), expected, 0.01f);
  EXPECT_NEAR(s.shadingNormal.z, 0, 1e-4f);
}

// A solid (3D) bump map, here an fbm times 0.025 on a square without
// uvs: the normal is tilted by the displacement's slope in space, the
// gradient of 0.025 fbm across the plane (estimated here by central
// differences at another step), as pbrt's Bump() tilts it.
TEST(ShadingNormals, ASolidBumpTiltsTheNormalByItsGradientWithoutUvs) {
  Material material = diffuseMaterial(Vec3f(0.5f));
  material.bumpScale = 0.025f;
  material.bumpTexture = 0;
  Scene scene = texturedSquare(material);
  scene.meshes[0].uvs = {};
  Texture fbm;
  fbm.name = "fbm";
  fbm.solid.kind = SolidTextureKind::Fbm;
  fbm.solid.worldToTexture = Affine3f::scale({10, 10, 10});
  // Two octaves: the finest wavelength (1/4 texture unit) far above the
  // step pbrt's Bump() takes without differentials (0.0005 of the uv range,
  // 0.02 texture units here), so that step's difference is the gradient.
  fbm.solid.octaves = 2;
  scene.textures.push_back(fbm);
  const SurfacePoint s = surfaceAtCentre(scene);
  ASSERT_NE(s.shadingNormal, s.geometricNormal) << "no bump without uvs";
  const Vec3f p = s.position;
  auto d = [&](Vec3f q) { return 0.025f * fbm.solid.evaluate(q).x; };
  const float h = 2e-4f;
  const float slopeX = (d(p + Vec3f{h, 0, 0}) - d(p - Vec3f{h, 0, 0})) / (2 * h);
  const float slopeZ = (d(p + Vec3f{0, 0, h}) - d(p - Vec3f{0, 0, h})) / (2 * h);
  const Vec3f expected = normalize(Vec3f{-slopeX, 1, -slopeZ});
  EXPECT_GT(length(Vec3f{slopeX, 0, slopeZ}), 0.05f) << "a visible bump";
  EXPECT_GT(dot(s.shadingNormal, expected), std::cos(0.05f));
}

TEST(ShadingNormals, ANormalMapIsReadInTheUvTangentFrame) {
  // Tangent-space (0.6, 0, 0.8): tilted towards +u (+x) by asin(0.6); then
  // (0, 0.6, 0.8): towards +v, which is -z here.
  for (const bool alongV : {false, true}) {
    Material material = diffuseMaterial(Vec3f(0.5f));
    material.normalTexture = 0;
    Scene scene = texturedSquare(material);
    const Vec3f n = alongV ? Vec3f(0, 0.6f, 0.8f) : Vec3f(0.6f, 0, 0.8f);
    scene.textures.push_back(rampTexture(4, [&](float) { return (n + Vec3f(1)) * 0.5f; }));
    const SurfacePoint s = surfaceAtCentre(scene);
    const Vec3f expected = alongV ? Vec3f(0, 0.8f, -0.6f) : Vec3f(0.6f, 0.8f, 0);
    EXPECT_NEAR(s.shadingNormal.x, expected.x, 0.01f) << alongV;
    EXPECT_NEAR(s.shadingNormal.y, expected.y, 0.01f) << alongV;
    EXPECT_NEAR(s.shadingNormal.z, expected.z, 0.01f) << alongV;
  }
}

TEST(ShadingNormals, TiltedShadingNormalsNeitherBlackenNorLeak) {
  // Shading normals tilted 70 degrees towards +x, seen from the +x side at a
  // grazing angle (where most of them face away from the viewer), under a
  // white sky, direct light only: every pixel lit, the mean at most the
  // albedo (the most a Lambertian surface can reflect of a unit sky).
  const float albedo = 0.5f;
  Material material = diffuseMaterial(Vec3f(albedo));
  material.normalTexture = 0;
  Scene scene = texturedSquare(material);
  const float tilt = 70 * kPi / 180;
  const Vec3f n{-std::sin(tilt), 0, std::cos(tilt)};  // towards -u: away from the camera
  scene.textures.push_back(rampTexture(4, [&](float) { return (n + Vec3f(1)) * 0.5f; }));
  CameraView view;
  view.from = {4, 1.5f, 0};  // 20 degrees above the plane: every pixel sees it
  view.at = {0, 0, 0};
  view.fovY = 10;
  const PixelStatistics stats = renderUnderWhiteSky(scene, view);
  double mean, se;
  stats.imageMean(0, mean, se);
  for (const MeanVariance& pixel : stats.channel[0]) EXPECT_GT(pixel.mean, 0.01);
  EXPECT_LE(mean, albedo + 4 * se + 1e-3);
  EXPECT_GT(mean, 0.05);
}

// A mix bends the normal by the map of the material it picks: a mix that
// always picks the normal-mapped material renders exactly as that material,
// and one that always picks the plain material from a normal-mapped first
// renders exactly as the plain one (pbrt's mix chooses the whole material,
// its bump map with it).
TEST(ShadingNormals, AMixBendsTheNormalByTheMaterialItPicks) {
  const float tilt = 60 * kPi / 180;
  const Vec3f n{-std::sin(tilt), 0, std::cos(tilt)};
  auto render = [&](const std::vector<Material>& materials, int32_t used) {
    Scene scene;
    scene.name = "square";
    for (const Material& m : materials) scene.addMaterial(m);
    scene.addSingleInstanceMesh(makeQuad({-2, 0, 2}, {4, 0, 0}, {0, 0, -4}, used));
    scene.textures.push_back(rampTexture(4, [&](float) { return (n + Vec3f(1)) * 0.5f; }));
    CameraView view;
    view.from = {4, 1.5f, 0};
    view.at = {0, 0, 0};
    view.fovY = 10;
    std::vector<double> means;
    for (const MeanVariance& pixel : renderUnderWhiteSky(scene, view).channel[0])
      means.push_back(pixel.mean);
    return means;
  };
  const Material plain = diffuseMaterial(Vec3f(0.5f));
  Material mapped = plain;
  mapped.normalTexture = 0;
  Material picksMapped = plain;  // materials[2] -> materials[1], always
  picksMapped.mixedWith = 1;
  picksMapped.mixAmount = 1;
  Material picksPlain = mapped;  // materials[3] -> materials[0], always
  picksPlain.mixedWith = 0;
  picksPlain.mixAmount = 1;
  const std::vector<Material> materials{plain, mapped, picksMapped, picksPlain};
  const std::vector<double> plainImage = render(materials, 0), mappedImage = render(materials, 1);
  ASSERT_NE(plainImage, mappedImage);  // the map matters from this view
  EXPECT_EQ(render(materials, 2), mappedImage);
  EXPECT_EQ(render(materials, 3), plainImage);
}

}  // namespace
}  // namespace ferry
