#include "io/pbrt/pbrt_parser.h"
#include "shapes/curves.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.h"
#include "io/images/image_io.h"
#include "material/bsdf.h"
#include "material/models/coated_conductor.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"
#include "material/models/diffuse_transmission.h"
#include "material/models/fresnel_blend.h"
#include "material/models/layered.h"
#include "material/models/subsurface.h"
#include "material/models/thin_dielectric.h"
#include "media/medium_presets.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "pbrt";

std::string corpus(const std::string& name) {
  return (kCorpus / name).string();
}

struct Loaded {
  Scene scene;
  std::vector<std::string> warnings;
};

Loaded load(const std::string& path, bool envFallback = false) {
  Loaded out;
  LoadOptions options;
  options.envFallback = envFallback;
  options.warn = [&](const std::string& w) { out.warnings.push_back(w); };
  out.scene = loadPbrt(path, options);
  out.scene.validate();
  return out;
}

Scene fromText(const std::string& text, std::vector<std::string>* warnings = nullptr) {
  LoadOptions options;
  options.warn = [&](const std::string& w) {
    if (warnings) warnings->push_back(w);
  };
  Scene s = loadPbrtFromString(text, "text.pbrt", kCorpus.string(), options);
  s.validate();
  return s;
}

bool anyContains(const std::vector<std::string>& lines, const std::string& piece) {
  for (const std::string& l : lines)
    if (l.find(piece) != std::string::npos) return true;
  return false;
}

const Material& material(const Scene& s, const std::string& name) {
  for (const Material& m : s.materials)
    if (m.name == name) return m;
  throw std::runtime_error("no material " + name);
}

// The material's model if it is a T, else null.
template <class T>
const T* modelAs(const Material& m) {
  return dynamic_cast<const T*>(m.model.get());
}

// Meshes using the material called `name`.
std::vector<const Mesh*> meshesOf(const Scene& s, const std::string& name) {
  std::vector<const Mesh*> out;
  for (const Mesh& m : s.meshes)
    if (s.materials[size_t(m.material)].name == name) out.push_back(&m);
  return out;
}

int32_t objectOfMesh(const Scene& s, const Mesh* mesh) {
  for (size_t o = 0; o < s.objects.size(); ++o)
    for (int32_t m : s.objects[o].meshes)
      if (&s.meshes[size_t(m)] == mesh) return int32_t(o);
  return -1;
}

std::vector<const Instance*> instancesOf(const Scene& s, int32_t object) {
  std::vector<const Instance*> out;
  for (const Instance& i : s.instances)
    if (i.object == object) out.push_back(&i);
  return out;
}

// ------------------------------------------------------------------- pbrt-v3

class PbrtV3Features : public testing::Test {
 protected:
  static void SetUpTestSuite() { loaded_ = new Loaded(load(corpus("features_v3.pbrt"))); }
  static void TearDownTestSuite() { delete loaded_; }
  const Scene& scene() const { return loaded_->scene; }
  const std::vector<std::string>& warnings() const { return loaded_->warnings; }
  static Loaded* loaded_;
};
Loaded* PbrtV3Features::loaded_ = nullptr;

TEST_F(PbrtV3Features, CameraAndFilm) {
  ASSERT_EQ(scene().views.size(), 1u);
  const CameraView& v = scene().views[0];
  EXPECT_EQ(v.name, "camera");
  EXPECT_NEAR(v.from.x, 0, 1e-5);
  EXPECT_NEAR(v.from.y, -10, 1e-5);
  EXPECT_NEAR(v.from.z, 2, 1e-5);
  Vec3f dir = normalize(v.at - v.from);
  Vec3f expected = normalize(Vec3f(0, 10, -1));
  EXPECT_NEAR(dot(dir, expected), 1, 1e-5);
  EXPECT_GT(v.up.z, 0.9f);
  // `Scale -1 1 1` before LookAt makes the camera right-handed.
  EXPECT_FALSE(v.leftHanded);
  EXPECT_FLOAT_EQ(v.fovY, 40);  // a wide film: fov is vertical
  EXPECT_EQ(scene().filmWidth, 200);
  EXPECT_EQ(scene().filmHeight, 100);
  EXPECT_EQ(scene().filmFilename, "features.exr");
  EXPECT_EQ(scene().filmScale, 2);  // "float scale" [ 2 ]: the radiance written is doubled
  ASSERT_TRUE(scene().filmCrop.has_value());  // "float cropwindow" [ 0.25 0.75 0 0.5 ]
  EXPECT_EQ(*scene().filmCrop, (std::array<float, 4>{0.25f, 0.75f, 0, 0.5f}));
}

// The Integrator is named (light paths follow a bidirectional one) and
// otherwise skipped with a warning.
TEST_F(PbrtV3Features, IntegratorIsRecorded) {
  EXPECT_EQ(scene().integrator, "path");
  EXPECT_FALSE(integratorWantsLightPaths(scene().integrator));
  EXPECT_FALSE(scene().integratorMaxDepth.has_value());  // no "maxdepth": Ferry's default
}

TEST_F(PbrtV3Features, Lights) {
  EXPECT_EQ(scene().environment.color, Vec3f(1, 1, 1));  // 0.5 times "rgb scale" 2
  EXPECT_FALSE(scene().environment.image);
  ASSERT_EQ(scene().suns.size(), 1u);
  const SunLight& sun = scene().suns[0];
  EXPECT_NEAR(sun.direction.z, 1, 1e-6);
  // A 5500 K blackbody at 3 times its peak: warm, bright.
  EXPECT_GT(sun.irradiance.x, sun.irradiance.z);
  EXPECT_GT(luminance(sun.irradiance), 1.0f);
  EXPECT_LT(luminance(sun.irradiance), 3.0f);
  // The point light: a delta light at (1, 2, 3).
  ASSERT_EQ(scene().pointLights.size(), 1u);
  EXPECT_EQ(scene().pointLights[0].position, Vec3f(1, 2, 3));
  EXPECT_EQ(scene().pointLights[0].falloff, PointLight::Falloff::None);
  // The area light's quad emits L.
  bool area = false;
  for (const Material& m : scene().materials)
    if (m.emission == Vec3f(4, 4, 4)) area = true;
  EXPECT_TRUE(area);
}

TEST_F(PbrtV3Features, Materials) {
  EXPECT_EQ(material(scene(), "red matte").baseColor, Vec3f(0.8f, 0.1f, 0.1f));
  const Material& al = material(scene(), "aluminium");
  const auto* alModel = modelAs<ConductorModel>(al);
  ASSERT_NE(alModel, nullptr);
  // Aluminium from the .spd files: a bright, nearly neutral grey.
  EXPECT_GT(al.baseColor.x, 0.85f);
  EXPECT_LT(maxComponent(al.baseColor) -
                std::min(al.baseColor.x, std::min(al.baseColor.y, al.baseColor.z)),
            0.05f);
  // pbrt-v3's roughness remapping: 0.001 -> alpha 0.047, Ferry's roughness sqrt(alpha).
  EXPECT_NEAR(alModel->roughness, 0.217f, 0.01f);
  const auto* glass = modelAs<DielectricModel>(material(scene(), "glass"));
  ASSERT_NE(glass, nullptr);
  EXPECT_FLOAT_EQ(glass->ior, 1.33f);
  EXPECT_EQ(material(scene(), "leather").baseColor, Vec3f(0.5f));
  // mix: v3's amount weighs the first material: "red matte" shades with
  // probability 0.25, "black" with 0.75 (its mean colour is the v3 blend).
  const Material& mixed = material(scene(), "mixed");
  EXPECT_EQ(mixed.baseColor, Vec3f(0.8f, 0.1f, 0.1f));
  ASSERT_GE(mixed.mixedWith, 0);
  EXPECT_FLOAT_EQ(mixed.mixAmount, 0.75f);
  const Vec3f black = scene().materials.at(size_t(mixed.mixedWith)).baseColor;
  EXPECT_NEAR(mixed.baseColor.x * 0.25f + black.x * 0.75f, 0.2f, 1e-6);
  EXPECT_NEAR(mixed.baseColor.y * 0.25f + black.y * 0.75f, 0.025f, 1e-6);
  const Material& uber = material(scene(), "mirror-ish uber");
  EXPECT_NE(modelAs<ConductorModel>(uber), nullptr);
  EXPECT_FLOAT_EQ(uber.baseColor.x, 0.9f);
}

TEST_F(PbrtV3Features, Textures) {
  // The procedural checkerboard, baked: red where floor(4u) + floor(4v) is even.
  const Material& plastic = material(scene(), "plastic");
  ASSERT_NE(plastic.baseColorTexture, kNoTexture);
  const Texture& checks = scene().textures[size_t(plastic.baseColorTexture)];
  EXPECT_GE(checks.width, 128);
  Vec4f a = checks.sample({0.1f, 0.1f}), b = checks.sample({0.35f, 0.1f}),
        c = checks.sample({0.35f, 0.35f});
  EXPECT_GT(a.x, 0.9f);
  EXPECT_LT(a.z, 0.1f);
  EXPECT_GT(b.z, 0.9f);
  EXPECT_LT(b.x, 0.1f);
  EXPECT_GT(c.x, 0.9f);
  // "scale": the checker image at half brightness, texel for texel.
  const Mesh* tri = nullptr;
  for (const Mesh& m : scene().meshes)
    if (scene().materials[size_t(m.material)].alphaTexture != kNoTexture &&
        scene().materials[size_t(m.material)].baseColorTexture != kNoTexture)
      tri = &m;
  ASSERT_TRUE(tri);
  const Material& dim = scene().materials[size_t(tri->material)];
  const Texture& grid = scene().textures[size_t(dim.baseColorTexture)];
  ASSERT_EQ(grid.width, 4);
  ASSERT_EQ(grid.height, 4);
  EXPECT_NEAR(grid.rgba[0], 188, 1);  // sRGB of linear 0.5
  EXPECT_EQ(grid.rgba[2], 0);
  EXPECT_NEAR(grid.rgba[6], 188, 1);  // its right neighbour blue
  // The alpha texture from the grey mask: its top half opaque.
  const Texture& mask = scene().textures[size_t(dim.alphaTexture)];
  EXPECT_EQ(mask.sampleAlpha({0.5f, 0.7f}), 1.0f);
  EXPECT_EQ(mask.sampleAlpha({0.5f, 0.3f}), 0.0f);
}

TEST_F(PbrtV3Features, InstancingStaysInstancing) {
  // "pair": the tetrahedron and the subdivided one, placed three times.
  const Object* pair = nullptr;
  int32_t pairIndex = -1;
  for (size_t o = 0; o < scene().objects.size(); ++o)
    if (scene().objects[o].name == "pair") pair = &scene().objects[o], pairIndex = int32_t(o);
  ASSERT_TRUE(pair);
  ASSERT_EQ(pair->meshes.size(), 2u);
  const Mesh& tet = scene().meshes[size_t(pair->meshes[0])];
  const Mesh& subdivided = scene().meshes[size_t(pair->meshes[1])];
  EXPECT_EQ(tet.triangleCount(), 4u);
  EXPECT_EQ(subdivided.triangleCount(), 4u * 16u);  // two levels
  // Baked with the definition's transform (Translate 0 0 3).
  EXPECT_GE(subdivided.bounds().lower.z, 3.0f);
  EXPECT_LE(subdivided.bounds().upper.z, 4.0f);
  auto placed = instancesOf(scene(), pairIndex);
  ASSERT_EQ(placed.size(), 3u);
  std::set<std::tuple<float, float, float>> at;
  for (const Instance* i : placed)
    at.insert({i->transform.t.x, i->transform.t.y, i->transform.t.z});
  EXPECT_TRUE(at.count({5.f, 0.f, 0.f}));
  EXPECT_TRUE(at.count({0.f, 5.f, 0.f}));
  EXPECT_TRUE(at.count({0.f, 0.f, 0.f}));
  // The same PLY twice at the top level: one object, two instances.
  auto quads = meshesOf(scene(), "leather");
  ASSERT_EQ(quads.size(), 1u);
  EXPECT_EQ(instancesOf(scene(), objectOfMesh(scene(), quads[0])).size(), 2u);
}

TEST_F(PbrtV3Features, ShapesAndCounts) {
  EXPECT_EQ(scene().objects.size(), 10u);
  EXPECT_EQ(scene().instances.size(), 13u);
  // Each curve type its own curves geometry: 2 cylinder segments and 1 flat,
  // 8 pieces each (pbrt's splitdepth 3).
  std::vector<const Curves*> curves;
  std::vector<int32_t> curvesObjects;
  for (size_t o = 0; o < scene().objects.size(); ++o)
    for (int32_t g : scene().objects[o].geometries)
      if (auto c = dynamic_cast<const Curves*>(scene().geometries[size_t(g)].shape.get())) {
        curves.push_back(c);
        curvesObjects.push_back(int32_t(o));
        EXPECT_EQ(scene().materials[size_t(scene().geometries[size_t(g)].material)].name,
                  "mirror-ish uber");
      }
  ASSERT_EQ(curves.size(), 2u);
  EXPECT_EQ(curves[0]->type(), CurveType::Cylinder);
  EXPECT_EQ(curves[0]->primitiveCount(), 2u * 8u);
  EXPECT_EQ(curves[1]->type(), CurveType::Flat);
  EXPECT_EQ(curves[1]->primitiveCount(), 8u);
  // CoordSysTransform "here" went back to the world transform.
  auto inst = instancesOf(scene(), curvesObjects[0]);
  ASSERT_EQ(inst.size(), 1u);
  EXPECT_EQ(inst[0]->transform.t, Vec3f(0, 0, 0));
  // The sphere, tessellated: area near 4 pi r^2.
  auto spheres = meshesOf(scene(), "aluminium");
  ASSERT_EQ(spheres.size(), 1u);
  double area = 0;
  for (const Vec3i& t : spheres[0]->indices)
    area += 0.5 * length(cross(spheres[0]->positions[t.y] - spheres[0]->positions[t.x],
                               spheres[0]->positions[t.z] - spheres[0]->positions[t.x]));
  EXPECT_NEAR(area, 4 * kPi * 0.25, 0.02 * 4 * kPi * 0.25);
  // The included file's cylinder, from a directory with a space in its name.
  auto cylinder = meshesOf(scene(), "matte");
  bool found = false;
  for (const Mesh* m : cylinder)
    if (m->name == "cylinder") found = true;
  EXPECT_TRUE(found);
}

// pbrt-v3's fourier material reads its table (tests/corpus/bsdf), once per
// file; a file that is not there is a warning naming it and grey diffuse; a
// malformed one an error naming it and the line that names it.
TEST(PbrtFourier, LoadsTheTable) {
  std::vector<std::string> warnings;
  const Scene s = fromText(
      "WorldBegin\n"
      "MakeNamedMaterial \"a\" \"string type\" \"fourier\" \"string bsdffile\" "
      "\"../bsdf/valid.bsdf\"\n"
      "MakeNamedMaterial \"b\" \"string type\" \"fourier\" \"string bsdffile\" "
      "\"../bsdf/valid.bsdf\"\n"
      "NamedMaterial \"a\"\nShape \"sphere\"\n"
      "NamedMaterial \"b\"\nTranslate 3 0 0\nShape \"sphere\"\n",
      &warnings);
  ASSERT_EQ(s.bsdfTables.size(), 1u);
  EXPECT_EQ(s.bsdfTables[0]->nMu, 5);
  int named = 0;
  for (const Material& m : s.materials)
    if (m.bsdfTable() == 0) ++named;
  EXPECT_EQ(named, 2);
  EXPECT_FALSE(anyContains(warnings, "fourier")) << warnings.front();
}

// pbrt-v3 reads a table whose sides differ (paint.bsdf) in its shading
// frame, whose normal a mirror turns around when the mesh has normals
// (ReverseOrientation XOR the swap) and ReverseOrientation turns without:
// the loader turns the mesh's normals (and its winding after them) to match.
TEST(PbrtFourier, SidedTablesAreReadInPbrtV3sShadingFrame) {
  const std::string paint = std::string(FERRY_SHARED_SCENES) + "/breakfast/bsdfs/paint.bsdf";
  if (!std::filesystem::exists(paint)) GTEST_SKIP() << "paint.bsdf is not available";
  auto meshOf = [&](const std::string& before, const std::string& extra) {
    const Scene s = fromText("Film \"image\"\nWorldBegin\nAttributeBegin\n" + before +
                             "Material \"fourier\" \"string bsdffile\" \"" + paint +
                             "\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] "
                             "\"integer indices\" [0 1 2] " +
                             extra + "\nAttributeEnd\nWorldEnd\n");
    return s.meshes.at(0);
  };
  auto windingZ = [](const Mesh& m) {
    const Vec3i t = m.indices[0];
    return cross(m.positions[size_t(t.y)] - m.positions[size_t(t.x)],
                 m.positions[size_t(t.z)] - m.positions[size_t(t.x)])
        .z;
  };
  const std::string normals = "\"normal N\" [0 0 1 0 0 1 0 0 1]";
  const Mesh plain = meshOf("", normals);
  EXPECT_EQ(plain.normals[0].z, 1);
  const Mesh mirrored = meshOf("Scale -1 1 1\n", normals);
  EXPECT_EQ(mirrored.normals[0].z, -1);
  EXPECT_LT(windingZ(mirrored), 0);
  const Mesh both = meshOf("Scale -1 1 1\nReverseOrientation\n", normals);
  EXPECT_EQ(both.normals[0].z, 1);
  EXPECT_LT(windingZ(meshOf("ReverseOrientation\n", "")), 0);  // no normals: the winding
  EXPECT_GT(windingZ(meshOf("Scale -1 1 1\n", "")), 0);
}

TEST(PbrtFourier, AMissingTableIsAWarningAndGreyDiffuse) {
  std::vector<std::string> warnings;
  const Scene s = fromText(
      "WorldBegin\nMaterial \"fourier\" \"string bsdffile\" \"bsdfs/ceramic.bsdf\"\n"
      "Shape \"sphere\"\n",
      &warnings);
  EXPECT_TRUE(s.bsdfTables.empty());
  ASSERT_FALSE(s.materials.empty());
  EXPECT_EQ(s.materials.back().bsdfTable(), kNoBsdfTable);
  EXPECT_EQ(s.materials.back().baseColor, Vec3f(0.5f));
  std::string warning;
  for (const std::string& w : warnings)
    if (w.find("fourier material:") != std::string::npos) warning = w;
  ASSERT_FALSE(warning.empty());
  EXPECT_NE(warning.find("ceramic.bsdf"), std::string::npos) << warning;
  EXPECT_NE(warning.find("text.pbrt:2"), std::string::npos) << warning;
  EXPECT_NE(warning.find("rendered as diffuse (0.5, 0.5, 0.5)"), std::string::npos) << warning;
  std::printf("%s\n", warning.c_str());
}

TEST(PbrtFourier, AMalformedTableIsAnErrorNamingItAndTheLine) {
  try {
    fromText(
        "WorldBegin\n\nMaterial \"fourier\" \"string bsdffile\" "
        "\"../bsdf/offset_out_of_range.bsdf\"\nShape \"sphere\"\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("text.pbrt:3"), std::string::npos) << what;
    EXPECT_NE(what.find("offset_out_of_range.bsdf: entry (2, 1)"), std::string::npos) << what;
  }
}

TEST_F(PbrtV3Features, WarnsOnceAboutWhatItSkips) {
  EXPECT_TRUE(anyContains(warnings(), "Sampler ignored"));
  EXPECT_TRUE(anyContains(warnings(), "Integrator ignored"));
  // leather.bsdf is not there: a warning naming it, and grey diffuse.
  EXPECT_TRUE(anyContains(warnings(), "fourier material:"));
  EXPECT_TRUE(anyContains(warnings(), "leather.bsdf"));
  std::set<std::string> unique(warnings().begin(), warnings().end());
  EXPECT_EQ(unique.size(), warnings().size());
}

// ------------------------------------------------------------------- pbrt-v4

class PbrtV4Features : public testing::Test {
 protected:
  static void SetUpTestSuite() { loaded_ = new Loaded(load(corpus("features_v4.pbrt"))); }
  static void TearDownTestSuite() { delete loaded_; }
  const Scene& scene() const { return loaded_->scene; }
  const std::vector<std::string>& warnings() const { return loaded_->warnings; }
  static Loaded* loaded_;
};
Loaded* PbrtV4Features::loaded_ = nullptr;

TEST_F(PbrtV4Features, LeftHandedCameraAndPortraitFov) {
  const CameraView& v = scene().views.at(0);
  EXPECT_TRUE(v.leftHanded);
  // fov 60 spans the shorter (horizontal) side of a 100 x 200 film.
  float expected = 2 * std::atan(std::tan(30 * kPi / 180) * 2) * 180 / kPi;
  EXPECT_NEAR(v.fovY, expected, 1e-3);
  EXPECT_EQ(scene().filmFilename, "v4.png");
  EXPECT_EQ(scene().filmScale, 4);  // "float iso" 400: pbrt-v4's imaging ratio at 1 s
  // The thin lens, in world units (the camera transform does not scale).
  EXPECT_NEAR(v.lensRadius, 0.1f, 1e-6f);
  EXPECT_NEAR(v.focalDistance, 5.0f, 1e-5f);
}

TEST_F(PbrtV4Features, BidirectionalIntegratorAsksForLightPaths) {
  EXPECT_EQ(scene().integrator, "bdpt");
  EXPECT_TRUE(integratorWantsLightPaths(scene().integrator));
  EXPECT_EQ(scene().integratorMaxDepth, 7);  // "integer maxdepth" 7
}

TEST_F(PbrtV4Features, Materials) {
  const Material& gold = material(scene(), "gold");
  const auto* goldModel = modelAs<ConductorModel>(gold);
  ASSERT_NE(goldModel, nullptr);
  EXPECT_GT(gold.baseColor.x, 0.8f);
  EXPECT_LT(gold.baseColor.z, 0.5f);                                // yellow
  EXPECT_NEAR(goldModel->roughness, std::pow(0.01f, 0.25f), 1e-4);  // v4: alpha = sqrt(r)
  const auto* bk7 = modelAs<DielectricModel>(material(scene(), "bk7"));
  ASSERT_NE(bk7, nullptr);
  EXPECT_NEAR(bk7->ior, 1.5185f, 1e-3);
  const auto* sheet = modelAs<ThinDielectricModel>(material(scene(), "sheet"));
  ASSERT_NE(sheet, nullptr);
  EXPECT_NEAR(sheet->ior, 1.5f, 1e-6);  // pbrt-v4's default eta
  EXPECT_EQ(material(scene(), "coated").baseColor, Vec3f(0.1f, 0.5f, 0.1f));
  const Material& copper = material(scene(), "car");
  ASSERT_NE(modelAs<LayeredModel>(copper), nullptr);
  EXPECT_TRUE(modelAs<LayeredModel>(copper)->conductorBase);
  EXPECT_GT(copper.baseColor.x, copper.baseColor.y);
  EXPECT_GT(copper.baseColor.y, copper.baseColor.z);
  // diffusetransmission: reflectance and transmittance kept apart.
  const Material& leaf = material(scene(), "leaf");
  EXPECT_EQ(leaf.baseColor, Vec3f(0.2f, 0.4f, 0.1f));
  const auto* leafModel = modelAs<DiffuseTransmissionModel>(leaf);
  ASSERT_NE(leafModel, nullptr);
  EXPECT_EQ(leafModel->transmittance, Vec3f(0.1f, 0.3f, 0.05f));
  const Material& portal = material(scene(), "portal");
  ASSERT_NE(portal.alphaTexture, kNoTexture);
  EXPECT_EQ(scene().textures[size_t(portal.alphaTexture)].sampleAlpha({0.5f, 0.5f}), 0.0f);
  // A mix shades with the second material with probability "amount" (v4).
  const Material& mostly = material(scene(), "mostly gold");
  const auto* mostlyModel = modelAs<LayeredModel>(mostly);  // the first: coateddiffuse
  ASSERT_NE(mostlyModel, nullptr);
  EXPECT_FALSE(mostlyModel->conductorBase);
  ASSERT_GE(mostly.mixedWith, 0);
  EXPECT_FLOAT_EQ(mostly.mixAmount, 0.75f);
  EXPECT_NE(modelAs<ConductorModel>(scene().materials.at(size_t(mostly.mixedWith))),
            nullptr);  // gold
  // v4's displacement texture bumps the shading normal.
  const Material& leafMaterial = leaf;
  EXPECT_NE(leafMaterial.bumpTexture, kNoTexture);
  EXPECT_NEAR(leafMaterial.bumpScale, 1.0f, 1e-6f);
  EXPECT_FALSE(anyContains(warnings(), "displacement"));
  EXPECT_TRUE(anyContains(warnings(), "Shape \"nurbs\" is not supported"));
}

TEST_F(PbrtV4Features, ShapesLightsAttributesAndImport) {
  // Attribute "shape" "float radius" 0.25 reached the sphere without a radius.
  auto gold = meshesOf(scene(), "gold");
  ASSERT_EQ(gold.size(), 1u);
  EXPECT_NEAR(gold[0]->bounds().upper.x, 0.25f, 1e-4);
  // A curved bilinear patch is sampled 8 x 8; a flat one is two triangles.
  EXPECT_EQ(meshesOf(scene(), "bk7").at(0)->triangleCount(), 128u);
  EXPECT_EQ(meshesOf(scene(), "sheet").at(0)->triangleCount(), 2u);
  // A ribbon: one curves geometry of 8 pieces (pbrt's splitdepth 3).
  size_t ribbons = 0;
  for (const Geometry& g : scene().geometries)
    if (auto c = dynamic_cast<const Curves*>(g.shape.get())) {
      EXPECT_EQ(scene().materials[size_t(g.material)].name, "mostly gold");
      EXPECT_EQ(c->type(), CurveType::Ribbon);
      EXPECT_EQ(c->primitiveCount(), 8u);
      ++ribbons;
    }
  EXPECT_EQ(ribbons, 1u);
  // Import: its triangle is there, its Translate did not leak out.
  auto diffuse = meshesOf(scene(), "diffuse");
  ASSERT_EQ(diffuse.size(), 2u);
  Box3f sphere;
  for (const Mesh* m : diffuse)
    if (m->name == "sphere")
      for (const Instance* i : instancesOf(scene(), objectOfMesh(scene(), m)))
        sphere.extend(i->transform.transformBox(m->bounds()));
  EXPECT_NEAR(sphere.center().y, 0, 1e-4);
  // Blackbody 6500 K at luminance 1, times scale 1.5.
  EXPECT_NEAR(luminance(scene().environment.color), 1.5f, 0.05f);
  // The spot: a delta light with pbrt-v4's smoothstep falloff.
  ASSERT_EQ(scene().pointLights.size(), 1u);
  const PointLight& spot = scene().pointLights[0];
  EXPECT_EQ(spot.falloff, PointLight::Falloff::SmoothStep);
  EXPECT_EQ(spot.position, Vec3f(0, 4, 0));
  EXPECT_NEAR(spot.direction.y, -1, 1e-6);
  EXPECT_EQ(spot.falloffTowards(Vec3f(0, -1, 0)), 1.0f);
  EXPECT_EQ(spot.falloffTowards(Vec3f(0, 1, 0)), 0.0f);
}

// ------------------------------------------------------------------ details

// pbrt-v4's "float power" (watts) scales a light as pbrt-v4's Create
// functions do: by power / k_e, k_e what a unit light emits.
Vec3f brightestEmission(const Scene& s) {
  Vec3f out(0);
  for (const Material& m : s.materials)
    if (luminance(m.emission) > luminance(out)) out = m.emission;
  return out;
}

TEST(PbrtParser, V4PointAndSpotPowerScaleTheIntensity) {
  auto intensity = [](const std::string& light) {
    const Scene s = fromText("WorldBegin\nShape \"sphere\"\n" + light + "\n");
    EXPECT_EQ(s.pointLights.size(), 1u);
    return s.pointLights.empty() ? Vec3f(0) : s.pointLights[0].intensity;
  };
  const Vec3f point = intensity(R"(LightSource "point" "rgb I" [ 1 1 1 ])");
  const Vec3f pointPower = intensity(R"(LightSource "point" "rgb I" [ 1 1 1 ] "float power" 100)");
  EXPECT_NEAR(pointPower.y / point.y, 100 / (4 * kPi), 1e-3);
  const std::string spot = R"(LightSource "spot" "rgb I" [ 1 1 1 ] "float coneangle" 20 )";
  const Vec3f spotPlain = intensity(spot);
  const Vec3f spotPower = intensity(spot + R"("float conedeltaangle" 5 "float power" 100)");
  const float cosEnd = std::cos(20 * kPi / 180), cosStart = std::cos(15 * kPi / 180);
  EXPECT_NEAR(spotPower.y / spotPlain.y,
              100 / (2 * kPi * ((1 - cosStart) + (cosStart - cosEnd) / 2)), 1e-2);
}

// pbrt-v3's spot falls off as a quartic between the cone's edge and
// coneangle - conedeltaangle, pbrt-v4's as a smoothstep.
TEST(PbrtParser, SpotFalloffFollowsEachVersion) {
  auto spot = [](const std::string& film) {
    const Scene s = fromText(film +
                             "WorldBegin\nLightSource \"spot\" \"point from\" [0 0 0] "
                             "\"point to\" [0 0 1] \"float coneangle\" 30 \"float "
                             "conedeltaangle\" 10\nShape \"sphere\"\n");
    EXPECT_EQ(s.pointLights.size(), 1u);
    return s.pointLights.empty() ? PointLight{} : s.pointLights[0];
  };
  const PointLight v3 = spot("Film \"image\"\n"), v4 = spot("Film \"rgb\"\n");
  EXPECT_EQ(v3.falloff, PointLight::Falloff::Quartic);
  EXPECT_EQ(v4.falloff, PointLight::Falloff::SmoothStep);
  const float c = 0.5f * (std::cos(20 * kPi / 180) + std::cos(30 * kPi / 180));
  const Vec3f w(std::sqrt(1 - c * c), 0, c);  // halfway through the falloff
  EXPECT_NEAR(v3.falloffTowards(w), 0.0625f, 1e-4f);
  EXPECT_NEAR(v4.falloffTowards(w), 0.5f, 1e-4f);
  EXPECT_EQ(v3.falloffTowards({0, 0, 1}), 1.0f);
  EXPECT_EQ(v3.falloffTowards({0, 1, 0}), 0.0f);
}

TEST(PbrtParser, V4AreaPowerIsPerPbrtShape) {
  auto emission = [](const std::string& shape, std::vector<std::string>* warnings = nullptr) {
    return brightestEmission(fromText(
        "WorldBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ] \"float power\" 10\n" + shape +
            "\n",
        warnings));
  };
  // A sphere of radius 2: pbrt's area phi_max r (z_max - z_min) = 16 pi.
  EXPECT_NEAR(emission(R"(Shape "sphere" "float radius" 2)").y, 10 / (16 * kPi * kPi), 1e-5);
  // A disk of radius 1 under Scale 3: pbrt takes the disk's own area, pi.
  EXPECT_NEAR(emission("Scale 3 3 3 Shape \"disk\"").y, 10 / (kPi * kPi), 1e-4);
  // A 2 x 2 quad of two triangles: each triangle (area 2) emits the power.
  std::vector<std::string> warnings;
  EXPECT_NEAR(emission(R"(Shape "trianglemesh" "point3 P" [ 0 0 0 2 0 0 2 2 0 0 2 0 ]
                          "integer indices" [ 0 1 2 0 2 3 ])",
                       &warnings)
                  .y,
              10 / (2 * kPi), 1e-4);
  EXPECT_FALSE(anyContains(warnings, "power"));
  // Triangles of unequal area: the same total power, with a warning.
  EXPECT_NEAR(emission(R"(Shape "trianglemesh" "point3 P" [ 0 0 0 2 0 0 2 2 0 0 4 0 ]
                          "integer indices" [ 0 1 2 0 2 3 ])",
                       &warnings)
                  .y,
              10 / (3 * kPi), 1e-4);  // mean area (2 + 4) / 2
  EXPECT_TRUE(anyContains(warnings, "each piece that power"));
}

TEST(PbrtParser, TransformsComposeAsInPbrt) {
  Scene s = fromText(R"(WorldBegin
Translate 1 0 0
Rotate 90 0 0 1
Scale 2 2 2
Shape "trianglemesh" "point3 P" [ 1 0 0 0 1 0 0 0 1 ]
ConcatTransform [ 1 0 0 0  0 1 0 0  0 0 1 0  0 0 7 1 ]
Shape "trianglemesh" "point3 P" [ 1 0 0 0 1 0 0 0 1 ]
Transform [ 2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 2 ]
Shape "trianglemesh" "point3 P" [ 1 0 0 0 1 0 0 0 1 ]
)");
  ASSERT_EQ(s.instances.size(), 3u);
  // Translate * Rotate * Scale applied to (1, 0, 0): scaled to 2, turned to +y, moved +x.
  Vec3f p = s.instances[0].transform.transformPoint({1, 0, 0});
  EXPECT_NEAR(p.x, 1, 1e-5);
  EXPECT_NEAR(p.y, 2, 1e-5);
  // The column-major matrix's translation (0, 0, 7) is in the object's space.
  Vec3f q = s.instances[1].transform.transformPoint({0, 0, 0});
  EXPECT_NEAR(q.x, 1, 1e-5);
  EXPECT_NEAR(q.z, 14, 1e-5);
  // Transform replaces; w = 2 divides.
  EXPECT_EQ(s.instances[2].transform.transformPoint({1, 2, 3}), Vec3f(1, 2, 3));
}

TEST(PbrtParser, AttributeAndTransformBlocksRestore) {
  Scene s = fromText(R"(WorldBegin
AttributeBegin
  Translate 5 0 0
  Material "matte" "rgb Kd" [ 0 1 0 ]
  TransformBegin
    Translate 0 5 0
  TransformEnd
  Shape "sphere"
AttributeEnd
Shape "sphere"
)");
  ASSERT_EQ(s.instances.size(), 2u);
  EXPECT_EQ(s.instances[0].transform.t, Vec3f(5, 0, 0));
  EXPECT_EQ(s.instances[1].transform.t, Vec3f(0, 0, 0));
  EXPECT_EQ(s.materials[size_t(s.meshes[0].material)].baseColor, Vec3f(0, 1, 0));
  EXPECT_EQ(s.materials[size_t(s.meshes[1].material)].baseColor, Vec3f(0.5f));  // the default
}

TEST(PbrtParser, ImageEnvironmentIsResampledToYUp) {
  // A 2:1 lat-long map (v3 "mapname", z up): the top half red (+z), the bottom blue.
  fs::path dir = fs::temp_directory_path() / ("ferry_env_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  LinearImage img;
  img.width = 16;
  img.height = 8;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) img.rgb.push_back(y < 4 ? Vec3f(1, 0, 0) : Vec3f(0, 0, 1));
  writeExr((dir / "sky.exr").string(), img);
  Scene s = loadPbrtFromString(
      "WorldBegin\nLightSource \"infinite\" \"string mapname\" \"sky.exr\" \"rgb L\" [ 2 2 2 ]\n"
      "Shape \"sphere\"\n",
      "env.pbrt", dir.string());
  fs::remove_all(dir);
  ASSERT_TRUE(s.environment.image);
  const HdrImage& env = *s.environment.image;
  // Ferry's map is y up: pbrt's +z is now at v = 0.5 (the horizon); +y is
  // pbrt's horizon too, so red and blue meet along a great circle through the
  // poles. Pixels facing +z are red, facing -z blue, times L = 2.
  auto at = [&](Vec3f d) {
    float theta = std::acos(d.y), phi = std::atan2(d.z, d.x);
    if (phi < 0) phi += 2 * kPi;
    int x = std::min(env.width - 1, int(phi / (2 * kPi) * env.width));
    int y = std::min(env.height - 1, int(theta / kPi * env.height));
    return env.at(x, y);
  };
  EXPECT_NEAR(at(normalize(Vec3f(0.1f, 0.1f, 1))).x, 2, 0.05);
  EXPECT_NEAR(at(normalize(Vec3f(0.1f, 0.1f, -1))).z, 2, 0.05);
}

TEST(PbrtParser, ParameterListsGoOnAfterAnIncludedFileEnds) {
  // pbrt-v3 reads an included file and its includer as one token stream (its
  // smoke scene's medium takes "sigma_a" after the included grid); an Import
  // is parsed on its own, so its list ends with it.
  fs::path dir = fs::temp_directory_path() / ("ferry_include_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "points.pbrt") << "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\n";
  std::ofstream(dir / "nested.pbrt") << "Include \"points.pbrt\"\n";
  const std::string rest = "  \"integer indices\" [0 1 2]\n";
  Scene s =
      loadPbrtFromString("WorldBegin\nInclude \"points.pbrt\"\n" + rest, "main.pbrt", dir.string());
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].triangleCount(), 1u);
  // Through two levels of includes.
  s = loadPbrtFromString("WorldBegin\nInclude \"nested.pbrt\"\n" + rest, "main.pbrt", dir.string());
  ASSERT_EQ(s.meshes.size(), 1u);
  try {
    loadPbrtFromString("WorldBegin\nImport \"points.pbrt\"\n" + rest, "main.pbrt", dir.string());
    ADD_FAILURE() << "an Import's list went on in its importer";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("main.pbrt:3:3: expected a directive"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

TEST(PbrtParser, MediaAsPbrtDefinesThem) {
  // A grid medium placed by the CTM, bounded by a Material "" box; a sphere
  // of glass with fog inside; the camera in a haze.
  const Scene s = fromText(R"(
MakeNamedMedium "haze" "string type" "homogeneous" "rgb sigma_a" [0.01 0.02 0.03]
  "rgb sigma_s" [0.1 0.1 0.1] "float scale" 2
MediumInterface "" "haze"
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective"
WorldBegin
Translate 10 0 0
MakeNamedMedium "smoke" "string type" "heterogeneous" "integer nx" 2 "integer ny" 1 "integer nz" 1
  "point p0" [0 0 0] "point p1" [2 1 1] "float density" [0.5 1.5] "float g" 0.3
  "color sigma_a" [1 1 1] "color sigma_s" [4 4 4]
AttributeBegin
  Material ""
  MediumInterface "smoke" "haze"
  Shape "trianglemesh" "point P" [0 0 0 2 0 0 2 1 0 0 1 0] "integer indices" [0 1 2 0 2 3]
AttributeEnd
MakeNamedMedium "fog" "string type" "homogeneous" "string preset" "Wholemilk"
AttributeBegin
  Material "glass"
  MediumInterface "fog" "haze"
  Shape "sphere"
AttributeEnd
)");
  ASSERT_EQ(s.media.size(), 3u);
  EXPECT_EQ(s.cameraMedium, 0);
  EXPECT_TRUE(s.media[0].homogeneous());
  EXPECT_EQ(s.media[0].sigmaA, Vec3f(0.02f, 0.04f, 0.06f));
  EXPECT_EQ(s.media[0].sigmaS, Vec3f(0.2f));
  const Medium& smoke = s.media[1];
  ASSERT_FALSE(smoke.homogeneous());
  EXPECT_EQ(smoke.density->nx(), 2);
  EXPECT_FLOAT_EQ(smoke.g, 0.3f);
  // World (11.5, 0.5, 0.5) is the grid's second sample: the CTM (x + 10)
  // and the p0-p1 box place it.
  const Vec3f unit = smoke.gridFromWorld.transformPoint({11.5f, 0.5f, 0.5f});
  EXPECT_NEAR(unit.x, 0.75f, 1e-6f);
  EXPECT_FLOAT_EQ(smoke.density->lookup(unit), 1.5f);
  EXPECT_EQ(s.media[2].sigmaS, Vec3f(2.55f, 3.21f, 3.77f));  // pbrt's Wholemilk
  // The Material "" quad bounds media only: not a mesh, a boundary, in world space.
  ASSERT_EQ(s.mediumBoundaries.size(), 1u);
  EXPECT_EQ(s.mediumBoundaries[0].media, (MediumInterface{1, 0}));
  EXPECT_EQ(s.mediumBoundaries[0].mesh.positions[0], Vec3f(10, 0, 0));
  // The glass sphere is a surface with fog inside.
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].media, (MediumInterface{2, 0}));
}

// pbrt's subsurface materials: a dielectric surface enclosing a medium of
// the named, given or inverted coefficients, times scale.
TEST(PbrtParser, SubsurfaceEnclosesItsMedium) {
  std::vector<std::string> w;
  const Scene s = fromText(R"(WorldBegin
MakeNamedMedium "haze" "string type" "homogeneous" "rgb sigma_s" [0.1 0.1 0.1]
MediumInterface "" "haze"
AttributeBegin
  Material "subsurface" "string name" "Ketchup" "float scale" 10 "float g" 0.5 "float eta" 1.4
  Shape "sphere"
AttributeEnd
AttributeBegin
  Material "kdsubsurface" "rgb Kd" [0.5 0.5 0.5] "rgb mfp" [0.1 0.2 0.4] "rgb Kr" [0.5 0.5 0.5]
  Shape "sphere"
AttributeEnd
Material "matte"
Shape "sphere"
)",
                           &w);
  EXPECT_TRUE(w.empty()) << w.front();
  ASSERT_EQ(s.media.size(), 3u);
  ASSERT_EQ(s.meshes.size(), 3u);
  EXPECT_EQ(s.meshes[0].media, (MediumInterface{1, 0}));
  EXPECT_EQ(s.meshes[1].media, (MediumInterface{2, 0}));
  EXPECT_EQ(s.meshes[2].media, (MediumInterface{kNoMedium, 0}));
  const Medium& ketchup = s.media[1];
  EXPECT_TRUE(ketchup.subsurface);
  Vec3f sa, ss;
  ASSERT_TRUE(mediumPreset("Ketchup", sa, ss));
  EXPECT_EQ(ketchup.sigmaA, sa * 10.0f);
  EXPECT_EQ(ketchup.sigmaS, ss * 10.0f);
  EXPECT_EQ(ketchup.g, 0.0f);  // named: pbrt sets g to 0
  const auto* surface = modelAs<SubsurfaceModel>(s.materials.at(size_t(s.meshes[0].material)));
  ASSERT_NE(surface, nullptr);
  EXPECT_FLOAT_EQ(surface->ior, 1.4f);
  EXPECT_EQ(surface->roughness, 0.0f);
  // kdsubsurface: extinction 1 / mfp, the albedo whose diffusion reflectance is Kd.
  const Medium& kd = s.media[2];
  EXPECT_NEAR(kd.sigmaT().x, 10.0f, 1e-4f);
  EXPECT_NEAR(kd.sigmaT().z, 2.5f, 1e-4f);
  const float albedo = kd.sigmaS.x / kd.sigmaT().x;
  EXPECT_NEAR(photonBeamDiffusionReflectance(albedo, 0, 1.33f), 0.5f, 1e-3f);
  EXPECT_EQ(modelAs<SubsurfaceModel>(s.materials.at(size_t(s.meshes[1].material)))->reflectTint,
            Vec3f(0.5f));
}

TEST(PbrtParser, PbrtV4GridsCloudsAndEmission) {
  std::vector<std::string> w;
  const Scene s = fromText(R"(WorldBegin
MakeNamedMedium "rgb" "string type" "rgbgrid" "integer nx" 2 "float scale" 3
  "rgb sigma_a" [1 0 0  0 1 0] "rgb Le" [2 2 2  0 0 0] "float Lescale" 5
MakeNamedMedium "cloud" "string type" "cloud" "float wispiness" 0 "point3 p0" [0 0 0]
  "point3 p1" [2 1 1] "rgb sigma_s" [4 4 4]
MakeNamedMedium "glow" "string type" "uniformgrid" "integer nx" 2 "float density" [1 1]
  "rgb Le" [1 2 3] "float Lescale" [1 0]
MakeNamedMedium "fire" "string type" "uniformgrid" "float density" [1]
  "float temperature" [1000] "float temperaturecutoff" 500 "float temperaturescale" 10
MakeNamedMedium "lamp" "string type" "uniformgrid" "float density" [1] "rgb Le" [1 1 1]
Shape "sphere"
)",
                           &w);
  EXPECT_TRUE(w.empty()) << w.front();
  ASSERT_EQ(s.media.size(), 5u);
  // rgbgrid: voxel colours times the scale, sigma_s 1 where none is given.
  const Medium& rgb = s.media[0];
  ASSERT_TRUE(rgb.rgb);
  Vec3f sa, ss;
  rgb.coefficients({0.25f, 0.5f, 0.5f}, sa, ss);
  EXPECT_EQ(sa, Vec3f(3, 0, 0));
  EXPECT_EQ(ss, Vec3f(3));
  EXPECT_EQ(rgb.emittedAt({0.25f, 0.5f, 0.5f}), Vec3f(10));
  EXPECT_EQ(rgb.density->maxValue(), 6);  // (1 + 1) x 3: the majorants' source
  // cloud: pbrt-v4's procedural density, in the medium's space (x from 0 to 2).
  const Medium& cloud = s.media[1];
  ASSERT_TRUE(cloud.cloud);
  EXPECT_FALSE(cloud.homogeneous());
  EXPECT_EQ(cloud.cloud->box.upper.x, 2);
  cloud.coefficients({0.5f, 0, 0.5f}, sa, ss);  // at the bottom: density 1
  EXPECT_EQ(ss, Vec3f(4));
  // uniformgrid: Le times the Lescale grid.
  EXPECT_EQ(s.media[2].emittedAt({0.25f, 0.5f, 0.5f}), Vec3f(1, 2, 3));
  EXPECT_EQ(s.media[2].emittedAt({0.75f, 0.5f, 0.5f}), Vec3f(0));
  // temperature: a blackbody at (1000 - 500) x 10 = 5000 K, reddish white.
  const Vec3f fire = s.media[3].emittedAt({0.5f, 0.5f, 0.5f});
  EXPECT_GT(fire.x, fire.z);
  EXPECT_GT(fire.z, 0);
  // Le alone: pbrt-v4's Lescale default is one voxel of 1, which fades
  // towards the box's corners as its lookup does.
  EXPECT_EQ(s.media[4].emittedAt({0.5f, 0.5f, 0.5f}), Vec3f(1));
  EXPECT_FLOAT_EQ(s.media[4].emittedAt({0.0f, 0.0f, 0.0f}).x, 0.125f);
}

TEST(PbrtParser, MissingEnvironmentMapFailsOrFallsBack) {
  std::string path = corpus("missing_envmap.pbrt");
  try {
    load(path);
    FAIL() << "loaded without its environment map";
  } catch (const InputError& e) {
    std::string m = e.what();
    EXPECT_NE(m.find("missing_envmap.pbrt:2:1: environment map \"textures/sky.exr\" not found"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("env-fallback"), std::string::npos) << m;
  }
  Loaded fallback = load(path, true);
  EXPECT_EQ(fallback.scene.environment.color, Vec3f(1));
  EXPECT_TRUE(anyContains(fallback.warnings, "textures/sky.exr\" not found: using a constant"));
}

TEST(PbrtParser, PerpendicularNormalsAreDropped) {
  std::vector<std::string> w;
  Scene s = fromText(R"(WorldBegin
Shape "trianglemesh" "integer indices" [ 0 1 2 ] "point3 P" [ 0 0 0 1 0 0 0 1 0 ]
    "normal N" [ 0 1 0 0 1 0 0 1 0 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 ] "point3 P" [ 0 0 0 1 0 0 0 1 0 ]
    "normal N" [ 0 0 1 0 0 1 0 0.1 1 ]
)",
                     &w);
  EXPECT_TRUE(s.meshes[0].normals.empty());
  EXPECT_EQ(s.meshes[1].normals.size(), 3u);
  EXPECT_TRUE(anyContains(w, "normals all lie in its faces' planes"));
}

TEST(PbrtParser, MismatchedBlockEndsAreAcceptedWithAWarning) {
  Loaded l = load(corpus("mismatched_end.pbrt"));
  EXPECT_TRUE(anyContains(l.warnings, "closes the AttributeBegin"));
}

TEST(PbrtParser, UnknownNamedSpectraGetAStandIn) {
  std::vector<std::string> w;
  Scene s = fromText(R"(WorldBegin
Material "conductor" "spectrum eta" "metal-CuZn-eta" "spectrum k" "metal-CuZn-k"
Shape "sphere"
)",
                     &w);
  EXPECT_NE(modelAs<ConductorModel>(s.materials.at(0)), nullptr);
  EXPECT_GT(s.materials.at(0).baseColor.z, 0.85f);  // aluminium's neutral grey
  EXPECT_TRUE(anyContains(w, "\"metal-CuZn-eta\" is not known to Ferry: using \"metal-Al-eta\""));
}

TEST(PbrtParser, WarningsAreDeduplicated) {
  std::vector<std::string> w;
  std::string text = "WorldBegin\n";
  for (int i = 0; i < 100; ++i) text += "Shape \"sphere\" \"float shininess\" 3\n";
  fromText(text, &w);
  int count = 0;
  for (const std::string& line : w) count += line.find("shininess") != std::string::npos;
  EXPECT_EQ(count, 1);
}

TEST(PbrtParser, ObjectsOfManyCurvesShareOneGeometry) {
  std::string text = "WorldBegin\nObjectBegin \"hair\"\n";
  for (int i = 0; i < 50; ++i)
    text += "Shape \"curve\" \"point3 P\" [ 0 0 " + std::to_string(i) +
            " 1 0 0 2 1 0 3 1 1 ] \"float width\" 0.01\n";
  text += "ObjectEnd\nObjectInstance \"hair\"\nTranslate 1 0 0\nObjectInstance \"hair\"\n";
  Scene s = fromText(text);
  ASSERT_EQ(s.objects.size(), 1u);
  ASSERT_EQ(s.objects[0].geometries.size(), 1u);
  EXPECT_EQ(s.geometries[0].shape->primitiveCount(), 50u * 8u);
  EXPECT_EQ(s.instances.size(), 2u);
}

// pbrt-v3: curves moving inside ObjectBegin are a part of their own, which
// each instance places moving by the part's motion, then its own.
TEST(PbrtParser, CurvesMovingInsideAnObjectMoveWithEachInstance) {
  const std::string text =
      "WorldBegin\nObjectBegin \"tuft\"\n"
      "Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"float width\" 0.1\n"
      "ActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n"
      "Shape \"curve\" \"point3 P\" [0 0 0 0 1 0 0 2 0 0 3 0] \"float width\" 0.1\n"
      "ObjectEnd\n"
      "ObjectInstance \"tuft\"\nTranslate 0 0 5\nScale 2 2 2\nObjectInstance \"tuft\"\n";
  std::vector<std::string> warnings;
  Scene s = fromText(text, &warnings);
  for (const std::string& w : warnings)
    EXPECT_EQ(w.find("start transform"), std::string::npos) << w;
  int moving = 0, still = 0;
  for (const Instance& instance : s.instances) {
    const Object& o = s.objects[size_t(instance.object)];
    ASSERT_EQ(o.geometries.size(), 1u);
    if (!instance.motion) {
      ++still;
      continue;
    }
    ++moving;
    // The curve's first control point (the origin) at the start and end of the shutter.
    const Vec3f start = instance.motion->at(0).transformPoint(Vec3f(0)),
                end = instance.motion->at(1).transformPoint(Vec3f(0));
    const bool second = start.z > 1;  // under Translate 0 0 5, Scale 2
    EXPECT_NEAR(end.x - start.x, second ? 2.0f : 1.0f, 1e-4f);
    EXPECT_NEAR(start.z, second ? 5.0f : 0.0f, 1e-4f);
  }
  EXPECT_EQ(moving, 2);
  EXPECT_EQ(still, 2);
}

TEST(PbrtParser, ExponentialTextureTreesFailInsteadOfHanging) {
  // Each level mixes the level below with itself: 2^30 evaluations per texel.
  std::string text = "WorldBegin\nTexture \"t0\" \"spectrum\" \"checkerboard\"\n";
  for (int i = 1; i <= 30; ++i)
    text += "Texture \"t" + std::to_string(i) + "\" \"spectrum\" \"mix\" \"texture tex1\" \"t" +
            std::to_string(i - 1) + "\" \"texture tex2\" \"t" + std::to_string(i - 1) + "\"\n";
  text += "Material \"diffuse\" \"texture reflectance\" \"t30\"\nShape \"sphere\"\n";
  try {
    fromText(text);
    FAIL() << "baked a texture of 2^30 evaluations per texel";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("too expensive to bake"), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------ malformed files

struct BadPbrt {
  std::string file;     // loaded
  std::string errorIn;  // the file the error names
  int line;
  int column;  // 0: not checked
  std::string contains;
};

std::ostream& operator<<(std::ostream& os, const BadPbrt& b) {
  return os << b.file;
}

class PbrtCorpusError : public testing::TestWithParam<BadPbrt> {};

TEST_P(PbrtCorpusError, NamesFileLineAndColumn) {
  const BadPbrt& bad = GetParam();
  try {
    load(corpus(bad.file));
    FAIL() << bad.file << " loaded without error";
  } catch (const InputError& e) {
    std::string message = e.what();
    SCOPED_TRACE(message);
    EXPECT_EQ(fs::path(e.where().file).filename().string(), bad.errorIn);
    EXPECT_EQ(e.where().line, bad.line);
    if (bad.column > 0) {
      EXPECT_EQ(e.where().column, bad.column);
    }
    EXPECT_NE(message.find(bad.errorIn + ":" + std::to_string(bad.line) + ":"), std::string::npos);
    EXPECT_NE(message.find(bad.contains), std::string::npos) << "expected: " << bad.contains;
  }
}

// pbrt's area lights emit only in front unless "twosided"; the front is the
// winding normal, reversed by ReverseOrientation, or the side of the vertex
// normals: the loader orients a one-sided emitter's winding to match.
// The coated materials and matte's sigma: what each pbrt
// parameter becomes.
TEST(PbrtParser, CoatsAndOrenNayarFollowPbrt) {
  auto only = [](const std::string& material) {
    const Scene scene = fromText("WorldBegin\n" + material +
                                 "\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] "
                                 "\"integer indices\" [0 1 2]\nWorldEnd\n");
    return scene.materials.at(size_t(scene.meshes.at(0).material));
  };
  // v3 plastic: Kd + Ks with FresnelDielectric(1.5, 1); roughness remapped.
  const Material plastic = only(
      "Material \"plastic\" \"rgb Kd\" [0.1 0.2 0.3] \"rgb Ks\" [0.4 0.5 0.6] "
      "\"float roughness\" 0.2 \"bool remaproughness\" false");
  EXPECT_EQ(plastic.baseColor, Vec3f(0.1f, 0.2f, 0.3f));
  const auto* plasticCoat = modelAs<CoatedDiffuseModel>(plastic);
  ASSERT_NE(plasticCoat, nullptr);
  EXPECT_EQ(plasticCoat->specular, Vec3f(0.4f, 0.5f, 0.6f));
  EXPECT_FLOAT_EQ(plasticCoat->roughness, std::sqrt(0.2f));  // alpha 0.2
  EXPECT_FLOAT_EQ(plasticCoat->eta, 1 / 1.5f);
  EXPECT_FALSE(plasticCoat->layered);
  const Material defaults = only("Material \"plastic\"");
  EXPECT_EQ(defaults.baseColor, Vec3f(0.25f));
  const auto* defaultCoat = modelAs<CoatedDiffuseModel>(defaults);
  ASSERT_NE(defaultCoat, nullptr);
  EXPECT_EQ(defaultCoat->specular, Vec3f(0.25f));
  // Remapped as pbrt-v3's RoughnessToAlpha(0.1) = 0.4615.
  EXPECT_NEAR(defaultCoat->roughness * defaultCoat->roughness, 0.4615f, 1e-3f);
  // v3 translucent: Kd split by reflect and transmit (its glossy Ks dropped).
  const Material translucent = only(
      "Material \"translucent\" \"rgb Kd\" [0.5 0.5 0.5] \"rgb reflect\" [0.2 0.2 0.2] "
      "\"rgb transmit\" [0.6 0.6 0.6]");
  EXPECT_NEAR(translucent.baseColor.x, 0.1f, 1e-6f);
  const auto* translucentModel = modelAs<DiffuseTransmissionModel>(translucent);
  ASSERT_NE(translucentModel, nullptr);
  EXPECT_NEAR(translucentModel->transmittance.x, 0.3f, 1e-6f);
  // matte: sigma in degrees.
  const Material rough = only("Material \"matte\" \"float sigma\" 20");
  const auto* orenNayar = modelAs<DiffuseModel>(rough);
  ASSERT_NE(orenNayar, nullptr);
  EXPECT_EQ(orenNayar->sigmaDegrees, 20.0f);
  const Material smooth = only("Material \"matte\"");
  const auto* lambertian = modelAs<DiffuseModel>(smooth);
  ASSERT_NE(lambertian, nullptr);
  EXPECT_EQ(lambertian->sigmaDegrees, 0.0f);
  // uber: Ks with FresnelDielectric(1, eta).
  const Material uber = only("Material \"uber\" \"rgb Ks\" [0.3 0.3 0.3] \"float eta\" 1.7");
  const auto* uberCoat = modelAs<CoatedDiffuseModel>(uber);
  ASSERT_NE(uberCoat, nullptr);
  EXPECT_EQ(uberCoat->specular, Vec3f(0.3f));
  EXPECT_FLOAT_EQ(uberCoat->eta, 1.7f);
  EXPECT_FALSE(uberCoat->layered);
  // uber's "index" is its eta (pbrt-v3 reads "eta", else "index"); 1 leaves
  // no specular to speak of; "opacity" below 1 lets that share through.
  const Material indexed = only("Material \"uber\" \"rgb Ks\" [0.3 0.3 0.3] \"float index\" 1.7");
  EXPECT_FLOAT_EQ(modelAs<CoatedDiffuseModel>(indexed)->eta, 1.7f);
  const Material clear = only("Material \"uber\" \"float index\" 1");
  EXPECT_LT(fresnelDielectric(1, modelAs<CoatedDiffuseModel>(clear)->eta), 1e-4f);
  const Material seeThrough = only("Material \"uber\" \"rgb opacity\" [0.4 0.4 0.4]");
  EXPECT_NE(seeThrough.alphaTexture, kNoTexture);
  // v4 coateddiffuse: pbrt-v4's layered walk under an interface of that eta
  // and alpha (v4: alpha = sqrt(roughness)), its slab and walk parameters.
  const Material coated = only(
      "Material \"coateddiffuse\" \"rgb reflectance\" [0.7 0.6 0.5] \"float roughness\" 0.04 "
      "\"float eta\" 1.4 \"float thickness\" 0.2 \"rgb albedo\" [0.5 0.5 0.5] \"float g\" 0.3 "
      "\"integer maxdepth\" 7 \"integer nsamples\" 2");
  EXPECT_EQ(coated.baseColor, Vec3f(0.7f, 0.6f, 0.5f));
  const auto* coat = modelAs<LayeredModel>(coated);
  ASSERT_NE(coat, nullptr);
  EXPECT_FALSE(coat->conductorBase);
  EXPECT_FLOAT_EQ(coat->eta, 1.4f);
  EXPECT_NEAR(coat->alpha, 0.2f, 1e-6f);
  EXPECT_FLOAT_EQ(coat->thickness, 0.2f);
  EXPECT_EQ(coat->albedo, Vec3f(0.5f));
  EXPECT_FLOAT_EQ(coat->g, 0.3f);
  EXPECT_EQ(coat->maxDepth, 7);
  EXPECT_EQ(coat->samples, 2);
  // Its defaults: a smooth interface of 1.5, a thin clear slab, 10 deep.
  const auto* plainCoat = modelAs<LayeredModel>(only("Material \"coateddiffuse\""));
  ASSERT_NE(plainCoat, nullptr);
  EXPECT_EQ(plainCoat->alpha, 0.0f);
  EXPECT_FLOAT_EQ(plainCoat->eta, 1.5f);
  EXPECT_FLOAT_EQ(plainCoat->thickness, 0.01f);
  EXPECT_EQ(plainCoat->albedo, Vec3f(0));
  EXPECT_EQ(plainCoat->maxDepth, 10);
  // v4 coatedconductor: the conductor base under the interface.
  const Material coatedMetal = only(
      "Material \"coatedconductor\" \"float interface.eta\" 1.6 \"float "
      "interface.roughness\" 0.09 \"float conductor.roughness\" 0.25");
  const auto* metal = modelAs<LayeredModel>(coatedMetal);
  ASSERT_NE(metal, nullptr);
  EXPECT_TRUE(metal->conductorBase);
  EXPECT_FLOAT_EQ(metal->eta, 1.6f);
  EXPECT_NEAR(metal->alpha, 0.3f, 1e-5f);
  EXPECT_NEAR(metal->baseAlpha, 0.5f, 1e-5f);
  // substrate: Ashikhmin-Shirley, Ks the coat's reflectance at normal incidence.
  const Material substrate = only("Material \"substrate\" \"rgb Ks\" [0.04 0.05 0.06]");
  const auto* blend = modelAs<FresnelBlendModel>(substrate);
  ASSERT_NE(blend, nullptr);
  EXPECT_EQ(blend->specular, Vec3f(0.04f, 0.05f, 0.06f));
  EXPECT_EQ(substrate.baseColor, Vec3f(0.5f));
}

// Rough glass as each pbrt remaps it: v3's polynomial, v4's square root,
// none with remaproughness false; u and v combined as sqrt(alpha_u alpha_v);
// Ferry's roughness is sqrt(alpha).
TEST(PbrtParser, RoughGlassFollowsEachVersionsRemapping) {
  auto glass = [](const std::string& header, const std::string& material) {
    const Scene scene = fromText(header + "WorldBegin\n" + material +
                                 "\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] "
                                 "\"integer indices\" [0 1 2]\nWorldEnd\n");
    const auto* d =
        modelAs<DielectricModel>(scene.materials.at(size_t(scene.meshes.at(0).material)));
    EXPECT_NE(d, nullptr);
    return d ? d->roughness : -1.0f;
  };
  const float v3Alpha =
      1.62142f + 0.819955f * std::log(0.1f) + 0.1734f * std::pow(std::log(0.1f), 2.0f) +
      0.0171201f * std::pow(std::log(0.1f), 3.0f) + 0.000640711f * std::pow(std::log(0.1f), 4.0f);
  EXPECT_NEAR(glass("Film \"image\"\n",
                    "Material \"glass\" \"float uroughness\" 0.1 \"float vroughness\" 0.1"),
              std::sqrt(v3Alpha), 1e-5f);
  EXPECT_NEAR(glass("Film \"rgb\"\n", "Material \"dielectric\" \"float roughness\" 0.1"),
              std::sqrt(std::sqrt(0.1f)), 1e-6f);
  EXPECT_NEAR(glass("Film \"rgb\"\n",
                    "Material \"dielectric\" \"float uroughness\" 0.04 \"float vroughness\" 0.16 "
                    "\"bool remaproughness\" false"),
              std::sqrt(std::sqrt(0.04f * 0.16f)), 1e-6f);
}

// pbrt-v3's glass is smooth when uroughness and vroughness are both 0,
// tested before any remapping (its default); its other models remap 0 to a
// small width. A regression: 0 was remapped to alpha 0.047, rough glass.
TEST(PbrtParser, V3GlassWithoutRoughnessIsSmooth) {
  auto model = [](const std::string& material) {
    const Scene scene = fromText("Film \"image\"\nWorldBegin\n" + material +
                                 "\nShape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] "
                                 "\"integer indices\" [0 1 2]\nWorldEnd\n");
    return scene.materials.at(size_t(scene.meshes.at(0).material));
  };
  const Material plain = model("Material \"glass\" \"float index\" 1.5");
  const auto* glass = modelAs<DielectricModel>(plain);
  ASSERT_NE(glass, nullptr);
  EXPECT_EQ(glass->roughness, 0.0f);
  const Material zeros = model("Material \"glass\" \"float uroughness\" 0 \"float vroughness\" 0");
  const auto* zero = modelAs<DielectricModel>(zeros);
  ASSERT_NE(zero, nullptr);
  EXPECT_EQ(zero->roughness, 0.0f);
  // One direction rough: remapped, not smooth.
  const Material oneRough =
      model("Material \"glass\" \"float uroughness\" 0 \"float vroughness\" 0.1");
  const auto* half = modelAs<DielectricModel>(oneRough);
  ASSERT_NE(half, nullptr);
  EXPECT_GT(half->roughness, 0.0f);
  // v3 metal remaps 0 (no smooth test in pbrt-v3's MetalMaterial).
  const Material metalMaterial = model("Material \"metal\" \"float roughness\" 0");
  const auto* metal = modelAs<ConductorModel>(metalMaterial);
  ASSERT_NE(metal, nullptr);
  EXPECT_GT(metal->roughness, 0.1f);
}

TEST(PbrtParser, SolidTexturesAreEvaluatedInTheirSpace) {
  const Scene scene = fromText(
      "WorldBegin\nTransformBegin\nTranslate 0 2 0\nTexture \"m\" \"color\" \"marble\" \"float "
      "scale\" 4 \"float variation\" 0.3 \"integer octaves\" 5 \"float roughness\" 0.6\n"
      "TransformEnd\nTexture \"w\" \"spectrum\" \"wrinkled\"\n"
      "Material \"matte\" \"texture Kd\" \"m\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 "
      "0 1 0] \"integer indices\" [0 1 2]\nMaterial \"matte\" \"texture Kd\" \"w\"\nShape "
      "\"trianglemesh\" \"point3 P\" [0 0 1 1 0 1 0 1 1] \"integer indices\" [0 1 2]\nWorldEnd\n");
  ASSERT_EQ(scene.meshes.size(), 2u);
  const Texture& marble = scene.textures.at(
      size_t(scene.materials.at(size_t(scene.meshes[0].material)).baseColorTexture));
  EXPECT_EQ(marble.solid.kind, SolidTextureKind::Marble);
  EXPECT_EQ(marble.solid.scale, 4.0f);
  EXPECT_EQ(marble.solid.variation, 0.3f);
  EXPECT_EQ(marble.solid.octaves, 5);
  EXPECT_EQ(marble.solid.omega, 0.6f);
  EXPECT_EQ(marble.solid.worldToTexture.transformPoint({0, 2, 0}), Vec3f(0, 0, 0));
  EXPECT_EQ(marble.texelCount(), 0u);
  const Texture& wrinkled = scene.textures.at(
      size_t(scene.materials.at(size_t(scene.meshes[1].material)).baseColorTexture));
  EXPECT_EQ(wrinkled.solid.kind, SolidTextureKind::Wrinkled);
  EXPECT_EQ(wrinkled.solid.octaves, 8);
}

// A solid texture as a bump map, alone or scaled by constants (the
// bathroom's towels: scale of fbm by 0.025), is displaced in 3D; its space
// is the CTM at its definition in pbrt-v3 (which applies it) and its
// inverse in pbrt-v4.
TEST(PbrtParser, ScaledSolidBumpMapsAreEvaluatedInTheirSpace) {
  auto bumped = [](const std::string& header) {
    std::vector<std::string> warnings;
    const Scene scene = fromText(
        header +
            "WorldBegin\nTransformBegin\nScale 10 10 10\nTexture \"base\" \"float\" \"fbm\"\n"
            "Texture \"bump\" \"float\" \"scale\" \"texture tex1\" \"base\" \"float tex2\" 0.025\n"
            "TransformEnd\nMaterial \"matte\" \"texture bumpmap\" \"bump\"\nShape "
            "\"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
            "WorldEnd\n",
        &warnings);
    EXPECT_FALSE(anyContains(warnings, "constant 0.5"));
    const Material& m = scene.materials.at(size_t(scene.meshes.at(0).material));
    EXPECT_FLOAT_EQ(m.bumpScale, 0.025f);
    const Texture& t = scene.textures.at(size_t(m.bumpTexture));
    EXPECT_EQ(t.solid.kind, SolidTextureKind::Fbm);
    return t.solid.worldToTexture.transformPoint({1, 0, 0}).x;
  };
  EXPECT_FLOAT_EQ(bumped("Film \"image\"\n"), 10);  // v3: the CTM
  EXPECT_FLOAT_EQ(bumped("Film \"rgb\"\n"), 0.1f);  // v4: its inverse
}

// Solid textures inside other textures and on scalars are evaluated in
// space, not the constant 0.5: a mix of two colours by an fbm, a scale of
// wrinkled by an image-free checkerboard, a bump map mixing two solids, and
// Oren-Nayar's sigma averaged over space.
TEST(PbrtParser, SolidTexturesInsideOtherTexturesAreEvaluatedInSpace) {
  std::vector<std::string> warnings;
  const Scene scene = fromText(
      "WorldBegin\nTexture \"n\" \"float\" \"fbm\" \"integer octaves\" 3\n"
      "Texture \"w\" \"float\" \"wrinkled\"\n"
      "Texture \"c\" \"spectrum\" \"mix\" \"texture amount\" \"n\" \"rgb tex1\" [1 0 0] "
      "\"rgb tex2\" [0 0 1]\n"
      "Texture \"k\" \"float\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 4 "
      "\"float tex1\" 0.25 \"float tex2\" 0.75\n"
      "Texture \"s\" \"float\" \"scale\" \"texture tex1\" \"w\" \"texture tex2\" \"k\"\n"
      "Texture \"b\" \"float\" \"mix\" \"texture tex1\" \"n\" \"texture tex2\" \"w\" "
      "\"float amount\" 0.25\n"
      "Texture \"sigma\" \"float\" \"scale\" \"texture tex1\" \"w\" \"float tex2\" 20\n"
      "Material \"plastic\" \"texture Kd\" \"c\" \"texture bumpmap\" \"b\"\nShape \"trianglemesh\" "
      "\"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer "
      "indices\" [0 1 2]\n"
      "Material \"matte\" \"texture Kd\" \"s\" \"texture sigma\" \"sigma\"\nShape \"trianglemesh\" "
      "\"point3 P\" [0 0 1 1 "
      "0 1 0 1 1] \"integer indices\" [0 1 2]\nWorldEnd\n",
      &warnings);
  EXPECT_FALSE(anyContains(warnings, "constant 0.5"));
  ASSERT_EQ(scene.meshes.size(), 2u);
  const Material& plastic = scene.materials.at(size_t(scene.meshes[0].material));
  const Material& matte = scene.materials.at(size_t(scene.meshes[1].material));

  SolidTexture fbm;
  fbm.kind = SolidTextureKind::Fbm;
  fbm.octaves = 3;
  SolidTexture wrinkled;
  wrinkled.kind = SolidTextureKind::Wrinkled;
  const Texture& mix = scene.textures.at(size_t(plastic.baseColorTexture));
  EXPECT_EQ(mix.combination, TextureCombination::Mix);
  const Texture& scaled = scene.textures.at(size_t(matte.baseColorTexture));
  EXPECT_EQ(scaled.combination, TextureCombination::Scale);
  const Texture& bump = scene.textures.at(size_t(plastic.bumpTexture));
  EXPECT_EQ(bump.combination, TextureCombination::Mix);
  EXPECT_EQ(plastic.bumpScale, 1.0f);
  float lowest = 1, highest = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3f p{0.37f * float(i), 0.11f * float(i % 17), 0.05f * float(i % 5)};
    const Vec2f uv{float(i % 10) / 10 + 0.01f, float(i / 10 % 10) / 10 + 0.02f};
    const float n = fbm.evaluate(p).x, w = wrinkled.evaluate(p).x;
    const Vec3f c = mix.value(uv, p);
    EXPECT_NEAR(c.x, 1 - n, 1e-5f);
    EXPECT_NEAR(c.z, n, 1e-5f);
    lowest = std::min(lowest, n);
    highest = std::max(highest, n);
    const float check = checkerboardEven(uv * 4) ? 0.25f : 0.75f;
    EXPECT_NEAR(scaled.value(uv, p).x, w * check, 0.005f * w);  // the checkerboard baked in 8 bits
    EXPECT_NEAR(bump.value(uv, p).x, 0.75f * n + 0.25f * w, 1e-5f);
  }
  EXPECT_GT(highest - lowest, 0.3f);
  // Oren-Nayar's sigma is 20 times turbulence's mean over space, not 20 x 0.5.
  double sum = 0;
  constexpr int kPoints = 20000;
  for (int i = 0; i < kPoints; ++i)
    sum += wrinkled.evaluate(Vec3f(float(i % 97), float(i % 89), float(i % 83)) * 0.6597f).x;
  const float mean = float(sum / kPoints);
  EXPECT_GT(std::abs(mean - 0.5f), 0.05f);
  const auto* diffuse = modelAs<DiffuseModel>(matte);
  ASSERT_NE(diffuse, nullptr);
  EXPECT_NEAR(diffuse->sigmaDegrees, 20 * mean, 0.4f);
}

// A solid texture as a shape's alpha is kept solid, evaluated at the hit in
// space (trace/alpha_cutout.h), alone or inside a combination; no warning.
TEST(PbrtParser, SolidAlphaTexturesStaySolid) {
  std::vector<std::string> warnings;
  const Scene scene = fromText(
      "WorldBegin\nTexture \"n\" \"float\" \"fbm\" \"integer octaves\" 3\n"
      "Texture \"s\" \"float\" \"scale\" \"texture tex1\" \"n\" \"float tex2\" 2\n"
      "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] "
      "\"texture alpha\" \"n\"\n"
      "Shape \"trianglemesh\" \"point3 P\" [0 0 1 1 0 1 0 1 1] \"integer indices\" [0 1 2] "
      "\"texture alpha\" \"s\"\nWorldEnd\n",
      &warnings);
  EXPECT_FALSE(anyContains(warnings, "constant 0.5"));
  EXPECT_FALSE(anyContains(warnings, "not supported"));
  ASSERT_EQ(scene.meshes.size(), 2u);
  const Texture& fbm =
      scene.textures.at(size_t(scene.materials.at(size_t(scene.meshes[0].material)).alphaTexture));
  EXPECT_EQ(fbm.solid.kind, SolidTextureKind::Fbm);
  EXPECT_EQ(fbm.solid.octaves, 3);
  const Texture& scaled =
      scene.textures.at(size_t(scene.materials.at(size_t(scene.meshes[1].material)).alphaTexture));
  EXPECT_EQ(scaled.combination, TextureCombination::Scale);
  const Vec3f p{0.3f, 1.7f, 0.2f};
  EXPECT_NEAR(scaled.value({0, 0}, p).x, 2 * fbm.value({0, 0}, p).x, 1e-6f);
  EXPECT_NO_THROW(scene.validate());
}

// Cut-outs as each pbrt has them. v4: "alpha" below 1 is a hole with
// probability 1 - alpha for every ray. v3: "alpha" cuts paths and
// "shadowalpha" shadow rays, each only where it is 0; uber's opacity passes
// paths through stochastically and stops shadow rays.
TEST(PbrtParser, CutOutsFollowEachVersionsAlphaSemantics) {
  const std::string triangle =
      "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] ";
  struct Cut {
    bool any;
    AlphaTest test;
    AlphaRays rays;
    float alpha;  // the texture's alpha at uv (0.5, 0.5)
  };
  auto cutOf = [&](const std::string& header, const std::string& shape,
                   std::vector<std::string>* warnings = nullptr) {
    const Scene scene =
        fromText(header +
                     "WorldBegin\nTexture \"mask\" \"float\" \"constant\" \"float value\" 0\n"
                     "Texture \"other\" \"float\" \"constant\" \"float value\" 0.25\n" +
                     shape + "\nWorldEnd\n",
                 warnings);
    const Material& m = scene.materials.at(size_t(scene.meshes.at(0).material));
    if (m.alphaTexture == kNoTexture) return Cut{false, m.alphaTest, m.alphaRays, 1};
    return Cut{true, m.alphaTest, m.alphaRays,
               scene.textures.at(size_t(m.alphaTexture)).sampleAlpha({0.5f, 0.5f})};
  };
  const std::string v3 = "Film \"image\"\n", v4 = "Film \"rgb\"\n";

  Cut c = cutOf(v4, triangle + "\"float alpha\" 0.25");
  EXPECT_TRUE(c.any);
  EXPECT_EQ(c.test, AlphaTest::Stochastic);
  EXPECT_EQ(c.rays, AlphaRays::All);
  EXPECT_NEAR(c.alpha, 0.25f, 0.5f / 255);
  EXPECT_FALSE(cutOf(v4, triangle + "\"float alpha\" 1").any);

  EXPECT_FALSE(cutOf(v3, triangle + "\"float alpha\" 0.25").any);  // only 0 counts
  c = cutOf(v3, triangle + "\"float alpha\" 0");
  EXPECT_TRUE(c.any);
  EXPECT_EQ(c.test, AlphaTest::Zero);
  EXPECT_EQ(c.rays, AlphaRays::NotShadowRays);
  EXPECT_EQ(c.alpha, 0.0f);
  c = cutOf(v3, triangle + "\"texture alpha\" \"mask\" \"texture shadowalpha\" \"mask\"");
  EXPECT_EQ(c.test, AlphaTest::Zero);
  EXPECT_EQ(c.rays, AlphaRays::All);
  c = cutOf(v3, triangle + "\"texture shadowalpha\" \"mask\"");
  EXPECT_EQ(c.rays, AlphaRays::ShadowRaysOnly);
  std::vector<std::string> warnings;
  c = cutOf(v3, triangle + "\"texture alpha\" \"mask\" \"texture shadowalpha\" \"other\"",
            &warnings);
  EXPECT_EQ(c.rays, AlphaRays::All);
  EXPECT_TRUE(anyContains(warnings, "\"shadowalpha\" differs from \"alpha\""));

  c = cutOf(v3, "Material \"uber\" \"rgb opacity\" [0.25 0.25 0.25]\n" + triangle);
  EXPECT_EQ(c.test, AlphaTest::Stochastic);
  EXPECT_EQ(c.rays, AlphaRays::NotShadowRays);
  EXPECT_NEAR(c.alpha, 0.25f, 0.5f / 255);
  EXPECT_FALSE(cutOf(v3, "Material \"uber\" \"rgb opacity\" [1 1 1]\n" + triangle).any);
}

// The scene the distributed test renders on several ranks (cutouts_v4): its
// sheet and its instanced leaves are stochastic cut-outs for every ray.
TEST(PbrtParser, TheStochasticCutOutSceneHasItsCutOuts) {
  const Loaded loaded = load(corpus("cutouts_v4.pbrt"));
  EXPECT_TRUE(loaded.warnings.empty()) << loaded.warnings.front();
  const Scene& scene = loaded.scene;
  int sheets = 0, leaves = 0;
  for (const Material& m : scene.materials) {
    if (m.alphaTexture == kNoTexture) continue;
    EXPECT_EQ(m.alphaTest, AlphaTest::Stochastic);
    EXPECT_EQ(m.alphaRays, AlphaRays::All);
    (scene.textures.at(size_t(m.alphaTexture)).isSolid() ? leaves : sheets)++;
  }
  EXPECT_EQ(sheets, 1);
  EXPECT_EQ(leaves, 1);
  EXPECT_EQ(scene.instances.size(), 6u);  // light, ground, sheet, three leaves
}

TEST(PbrtParser, DotsAreBakedAsPbrtV3Draws) {
  const Scene scene = fromText(
      "WorldBegin\nTexture \"d\" \"color\" \"dots\" \"rgb inside\" [1 0 0] \"rgb outside\" [0 0 1] "
      "\"float uscale\" 8 \"float vscale\" 8\nMaterial \"matte\" \"texture Kd\" \"d\"\nShape "
      "\"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nWorldEnd\n");
  const Material& m = scene.materials.at(size_t(scene.meshes.at(0).material));
  ASSERT_NE(m.baseColorTexture, kNoTexture);
  const Texture& t = scene.textures.at(size_t(m.baseColorTexture));
  // Both colours appear, and dots (at most pi 0.35^2 = 38% of the area) are the minority.
  int red = 0, blue = 0;
  for (float v = 0.01f; v < 1; v += 0.02f)
    for (float u = 0.01f; u < 1; u += 0.02f) {
      const Vec4f c = t.sample({u, v});
      red += c.x > 0.5f;
      blue += c.z > 0.5f;
    }
  EXPECT_GT(red, 0);
  EXPECT_GT(blue, red);
  EXPECT_LT(red, 0.4 * (red + blue));
}

TEST(PbrtParser, BumpMapsAreBakedWithTheirRange) {
  const Scene scene = fromText(
      "WorldBegin\nTexture \"b\" \"float\" \"checkerboard\" \"float tex1\" 0.2 \"float tex2\" "
      "0.7 \"float uscale\" 4 \"float vscale\" 4\nTexture \"flat\" \"float\" \"constant\" \"float "
      "value\" 0.3\nMaterial \"matte\" \"texture bumpmap\" \"b\"\nShape \"trianglemesh\" \"point3 "
      "P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nMaterial \"coateddiffuse\" \"texture "
      "displacement\" \"flat\"\nShape \"trianglemesh\" \"point3 P\" [0 0 1 1 0 1 0 1 1] "
      "\"integer indices\" [0 1 2]\nWorldEnd\n");
  const Material& bumped = scene.materials.at(size_t(scene.meshes.at(0).material));
  ASSERT_NE(bumped.bumpTexture, kNoTexture);
  EXPECT_NEAR(bumped.bumpScale, 0.5f, 1e-6f);
  const Texture& t = scene.textures.at(size_t(bumped.bumpTexture));
  EXPECT_FALSE(t.srgb);
  // Linear texels spanning the range: 0 where 0.2, 255 where 0.7.
  EXPECT_EQ(*std::min_element(t.rgba.begin(), t.rgba.end()), 0);
  // A flat displacement (pbrt-v4's "displacement") bends nothing.
  EXPECT_EQ(scene.materials.at(size_t(scene.meshes.at(1).material)).bumpTexture, kNoTexture);
}

TEST(PbrtParser, AreaLightsAreOneSidedAndOriented) {
  auto emitterOf = [](const std::string& before, const std::string& light,
                      const std::string& extra) {
    const Scene scene = fromText(
        "WorldBegin\nAttributeBegin\n" + before + "AreaLightSource \"diffuse\" " + light +
        "\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] " +
        extra + "\nAttributeEnd\nWorldEnd\n");
    for (const Mesh& m : scene.meshes)
      if (scene.materials[size_t(m.material)].isEmissive()) return m;
    ADD_FAILURE() << "no emitter";
    return Mesh{};
  };
  auto normalZ = [](const Mesh& m) {
    const Vec3i t = m.indices[0];
    return cross(m.positions[size_t(t.y)] - m.positions[size_t(t.x)],
                 m.positions[size_t(t.z)] - m.positions[size_t(t.x)])
        .z;
  };
  const Scene oneSided = fromText(
      "WorldBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\nShape \"trianglemesh\" "
      "\"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nWorldEnd\n");
  bool found = false;
  for (const Material& m : oneSided.materials)
    if (m.isEmissive()) {
      EXPECT_FALSE(m.emitsBackSide);
      found = true;
    }
  EXPECT_TRUE(found);
  EXPECT_GT(normalZ(emitterOf("", "\"rgb L\" [1 1 1]", "")), 0);  // as written: +z
  EXPECT_LT(normalZ(emitterOf("ReverseOrientation\n", "\"rgb L\" [1 1 1]", "")), 0);
  // Vertex normals decide, whatever the winding.
  EXPECT_LT(normalZ(emitterOf("", "\"rgb L\" [1 1 1]", "\"normal N\" [0 0 -1 0 0 -1 0 0 -1]")), 0);
  // Two-sided: as written, and emitting on both sides.
  const Mesh twoSided =
      emitterOf("ReverseOrientation\n", "\"rgb L\" [1 1 1] \"bool twosided\" true", "");
  EXPECT_GT(normalZ(twoSided), 0);
}

// pbrt-v3 (known by its Film "image" or its material names) under a
// transform that swaps handedness sees a one-sided emitter on one side and
// samples its light leaving the other (Material::lightSampledOnBackSide);
// with vertex normals the seen side is the normals' turned by
// ReverseOrientation XOR the mirror. pbrt-v4 and unmirrored v3 are as before.
TEST(PbrtParser, PbrtV3MirroredEmittersAreSampledFromTheOtherSide) {
  struct Case {
    const char* header;  // before WorldBegin
    const char* before;  // inside the attribute block, before the light
    const char* extra;   // shape parameters
    bool flagged;
    float windingZ;  // sign of the object-space winding normal's z
  };
  const Case cases[] = {
      {"Film \"image\"\n", "Scale -1 1 1\n", "", true, 1},
      {"Film \"image\"\n", "Scale -1 1 1\n", "\"normal N\" [0 0 1 0 0 1 0 0 1]", true, -1},
      {"Film \"image\"\n", "Scale -1 1 1\nReverseOrientation\n", "\"normal N\" [0 0 1 0 0 1 0 0 1]",
       true, 1},
      {"", "Material \"matte\"\nScale -1 1 1\n", "", true, 1},
      {"Film \"image\"\n", "", "\"normal N\" [0 0 1 0 0 1 0 0 1]", false, 1},
      {"Film \"rgb\"\n", "Scale -1 1 1\n", "\"normal N\" [0 0 1 0 0 1 0 0 1]", false, 1},
      {"", "Scale -1 1 1\n", "", false, 1},
  };
  for (const Case& c : cases) {
    const Scene scene = fromText(
        std::string(c.header) + "WorldBegin\nAttributeBegin\n" + c.before +
        "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\nShape \"trianglemesh\" \"point3 P\" "
        "[0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] " +
        c.extra + "\nAttributeEnd\nWorldEnd\n");
    int emitters = 0;
    for (const Mesh& m : scene.meshes) {
      const Material& material = scene.materials[size_t(m.material)];
      if (!material.isEmissive()) continue;
      ++emitters;
      EXPECT_EQ(material.lightSampledOnBackSide, c.flagged) << c.header << c.before << c.extra;
      const Vec3i t = m.indices[0];
      const float z = cross(m.positions[size_t(t.y)] - m.positions[size_t(t.x)],
                            m.positions[size_t(t.z)] - m.positions[size_t(t.x)])
                          .z;
      EXPECT_GT(z * c.windingZ, 0) << c.header << c.before << c.extra;
    }
    EXPECT_EQ(emitters, 1);
  }
}

// Blackbody emitters: pbrt-v3's [T scale] is Planck's spectrum over its
// peak (Wien) times the scale, pbrt-v4's [T] is normalised to luminance 1.
// Analytically, at 6500 K the visible band lies near the peak (relative
// luminance about 0.9); at 2700 K the peak is at 1073 nm and 555 nm is at
// 0.26 of it (B(555) / B(1073) = (1073/555)^5 (e^4.966 - 1) / (e^9.602 - 1)).
TEST(PbrtParser, BlackbodyEmittersAreNormalisedAsEachPbrt) {
  auto emission = [](const std::string& header, const std::string& light) {
    const Scene s = fromText(header + "WorldBegin\nAreaLightSource \"diffuse\" " + light +
                             "\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] "
                             "\"integer indices\" [0 1 2]\nWorldEnd\n");
    for (const Material& m : s.materials)
      if (m.isEmissive()) return m.emission;
    ADD_FAILURE() << "no emitter";
    return Vec3f(0);
  };
  const Vec3f window = emission("Film \"image\"\n", "\"blackbody L\" [6500 100]");
  EXPECT_GT(luminance(window), 85.0f);
  EXPECT_LT(luminance(window), 100.0f);
  const Vec3f lamp = emission("Film \"image\"\n", "\"blackbody L\" [2700 10]");
  EXPECT_GT(luminance(lamp), 10 * 0.15f);
  EXPECT_LT(luminance(lamp), 10 * 0.35f);
  EXPECT_GT(lamp.x, lamp.z);  // warm
  const Vec3f v4 = emission("Film \"rgb\"\n", "\"blackbody L\" [2700]");
  EXPECT_NEAR(luminance(v4), 1.0f, 1e-3f);
  // The same colour either way.
  EXPECT_NEAR(v4.x / v4.z, lamp.x / lamp.z, 1e-3f * lamp.x / lamp.z);
}

// Film clamps: v3's maxsampleluminance, v4's maxcomponentvalue (0: none).
TEST(PbrtParser, FilmClampsEachSampleAsPbrt) {
  const char* shape =
      "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" "
      "[0 1 2]\nWorldEnd\n";
  const Scene v3 =
      fromText(std::string("Film \"image\" \"float maxsampleluminance\" 20\n") + shape);
  EXPECT_EQ(v3.filmMaxSampleLuminance, 20.0f);
  EXPECT_EQ(v3.filmMaxComponentValue, 0.0f);
  const Scene v4 = fromText(std::string("Film \"rgb\" \"float maxcomponentvalue\" 10\n") + shape);
  EXPECT_EQ(v4.filmMaxComponentValue, 10.0f);
  const Scene none = fromText(shape);
  EXPECT_EQ(none.filmMaxSampleLuminance, 0.0f);
  EXPECT_THROW(fromText(std::string("Film \"image\" \"float maxsampleluminance\" -1\n") + shape),
               InputError);
}

const std::vector<BadPbrt> kBadPbrt = {
    {"unknown_directive.pbrt", "unknown_directive.pbrt", 3, 1, "unknown directive 'Shpae'"},
    {"unterminated_string.pbrt", "unterminated_string.pbrt", 3, 35,
     "string not closed before the end of its line"},
    {"bad_escape.pbrt", "bad_escape.pbrt", 2, 39, "unknown escape '\\q'"},
    {"unbalanced_attribute.pbrt", "unbalanced_attribute.pbrt", 2, 1,
     "AttributeBegin is never closed"},
    {"extra_attribute_end.pbrt", "extra_attribute_end.pbrt", 4, 1,
     "AttributeEnd without a matching AttributeBegin"},
    {"object_end_without_begin.pbrt", "object_end_without_begin.pbrt", 2, 1,
     "ObjectEnd without ObjectBegin"},
    {"object_crossing_attribute.pbrt", "object_crossing_attribute.pbrt", 4, 1,
     "this closes the AttributeBegin"},
    {"include_loop_a.pbrt", "include_loop_b.pbrt", 2, 1, "include loop"},
    {"missing_include.pbrt", "missing_include.pbrt", 2, 1,
     "Include \"no such file.pbrt\" not found"},
    {"missing_ply.pbrt", "missing_ply.pbrt", 2, 1, "PLY file \"geometry/missing.ply\" not found"},
    {"missing_texture.pbrt", "missing_texture.pbrt", 2, 1, "file \"textures/wood.png\" not found"},
    {"index_out_of_range.pbrt", "index_out_of_range.pbrt", 2, 22,
     "index 3 (entry 5) is out of range: 3 points"},
    {"nan_value.pbrt", "nan_value.pbrt", 3, 24, "value 'nan' is not finite"},
    {"wrong_count.pbrt", "wrong_count.pbrt", 3, 3, "8 numbers is not a multiple of 3"},
    {"bad_param_type.pbrt", "bad_param_type.pbrt", 2, 16, "unknown parameter type 'float128'"},
    {"translate_args.pbrt", "translate_args.pbrt", 3, 1,
     "Translate: expected a number, found 'Shape'"},
    {"unknown_named_material.pbrt", "unknown_named_material.pbrt", 2, 1,
     "no material named \"nothing\""},
    {"unknown_object.pbrt", "unknown_object.pbrt", 2, 1, "no object named \"nobody\""},
    {"singular.pbrt", "singular.pbrt", 3, 1, "singular"},
    {"projective.pbrt", "projective.pbrt", 2, 1, "projective transforms are not supported"},
    {"huge_film.pbrt", "huge_film.pbrt", 1, 1, "Film: resolution 1000000 x 10"},
    {"bad_film_scale.pbrt", "bad_film_scale.pbrt", 1, 1, "\"float scale\" -2 must be positive"},
    {"bad_transform_times.pbrt", "bad_transform_times.pbrt", 1, 1,
     "TransformTimes: start 1 must not be after end 0.5"},
    {"bad_shutter.pbrt", "bad_shutter.pbrt", 1, 1,
     "\"float shutterclose\" 0.25 must not be before \"float shutteropen\" 0.5"},
    {"singular_end_transform.pbrt", "singular_end_transform.pbrt", 6, 1,
     "the end transform is singular"},
    {"bad_cropwindow.pbrt", "bad_cropwindow.pbrt", 1, 1, "\"float cropwindow\" expects four"},
    {"bad_maxdepth.pbrt", "bad_maxdepth.pbrt", 1, 1, "\"integer maxdepth\" -1 must be 0 or more"},
    {"binary.pbrt", "binary.pbrt", 3, 1, "unexpected byte 0x00"},
    {"absurd_subdivision.pbrt", "absurd_subdivision.pbrt", 2, 1, "30 levels of subdivision"},
    {"missing_envmap.pbrt", "missing_envmap.pbrt", 2, 1,
     "environment map \"textures/sky.exr\" not found"},
    {"bad_ply.pbrt", "bad_ply.pbrt", 2, 1,
     "lying_header.ply:3: element 'vertex' with 2000000000 entries"},
    {"mix_cycle.pbrt", "mix_cycle.pbrt", 2, 1, "material \"a\" mixes itself"},
    {"string_for_number.pbrt", "string_for_number.pbrt", 2, 34,
     "expected a number, found the string \"abc\""},
    {"unclosed_bracket.pbrt", "unclosed_bracket.pbrt", 2, 33, "'[' never closed"},
    {"repeated_param.pbrt", "repeated_param.pbrt", 2, 0, "parameter 'P' given twice"},
    {"degenerate_lookat.pbrt", "degenerate_lookat.pbrt", 1, 1,
     "the eye and the look-at point are the same"},
    {"huge_number.pbrt", "huge_number.pbrt", 2, 31, "value '1e39' is too large for a float"},
    {"huge_integer.pbrt", "huge_integer.pbrt", 2, 0,
     "integer '3000000000' does not fit in 32 bits"},
    {"curve_count.pbrt", "curve_count.pbrt", 2, 1,
     "a degree-3 Bezier curve needs 4 + 3k control points, found 3"},
    {"medium_density_count.pbrt", "medium_density_count.pbrt", 3, 3,
     "3 values for nx * ny * nz = 2 x 1 x 1 = 2"},
    {"medium_negative_density.pbrt", "medium_negative_density.pbrt", 3, 3,
     "density sample 1 (x 1, y 0, z 0) is -1"},
    {"medium_undefined.pbrt", "medium_undefined.pbrt", 2, 1, "no medium named \"fog\""},
    {"medium_nanovdb.pbrt", "medium_nanovdb.pbrt", 1, 1, "volume file \"cloud.nvdb\" not found"},
    {"medium_bad_g.pbrt", "medium_bad_g.pbrt", 2, 1, "\"g\" 1.5 must be in (-1, 1)"},
    {"medium_rgbgrid_count.pbrt", "medium_rgbgrid_count.pbrt", 3, 3,
     "3 values for 3 x nx * ny * nz = 2 x 1 x 1 = 6"},
    {"medium_rgbgrid_le_alone.pbrt", "medium_rgbgrid_le_alone.pbrt", 2, 1,
     "\"Le\" needs \"sigma_a\" too"},
    {"medium_temperature_and_le.pbrt", "medium_temperature_and_le.pbrt", 2, 1,
     "both \"Le\" and \"temperature\" are given"},
    {"medium_lescale_count.pbrt", "medium_lescale_count.pbrt", 3, 20,
     "3 values for nx * ny * nz = 2 x 1 x 1 = 2"},
};

INSTANTIATE_TEST_SUITE_P(Corpus, PbrtCorpusError, testing::ValuesIn(kBadPbrt));

TEST(PbrtParser, EveryCorpusFileIsCovered) {
  std::set<std::string> tested = {"features_v3.pbrt", "features_v4.pbrt",    "cutouts_v4.pbrt",
                                  "imported.pbrt",    "include_loop_b.pbrt", "mismatched_end.pbrt"};
  for (const BadPbrt& b : kBadPbrt) tested.insert(b.file);
  for (const auto& entry : fs::directory_iterator(kCorpus))
    if (entry.path().extension() == ".pbrt") {
      EXPECT_TRUE(tested.count(entry.path().filename().string())) << entry.path();
    }
}

}  // namespace
}  // namespace ferry
