#include "io/gltf/gltf_loader.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "io/images/image_io.h"
#include "material/bsdf.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "gltf";

std::string corpus(const std::string& name) {
  return (kCorpus / name).string();
}

// The material's model if it is a T, else null.
template <class T>
const T* modelAs(const Material& m) {
  return dynamic_cast<const T*>(m.model.get());
}

Scene load(const std::string& name, std::vector<std::string>* warnings = nullptr) {
  LoadOptions options;
  options.warn = [&](const std::string& w) {
    if (warnings) warnings->push_back(w);
  };
  Scene s = loadGltf(corpus(name), options);
  s.validate();
  return s;
}

const Object* object(const Scene& s, const std::string& name, int32_t* index = nullptr) {
  for (size_t i = 0; i < s.objects.size(); ++i)
    if (s.objects[i].name == name) {
      if (index) *index = int32_t(i);
      return &s.objects[i];
    }
  return nullptr;
}

std::vector<Affine3f> placements(const Scene& s, int32_t object) {
  std::vector<Affine3f> out;
  for (const Instance& i : s.instances)
    if (i.object == object) out.push_back(i.transform);
  return out;
}

const Material& material(const Scene& s, const std::string& name) {
  for (const Material& m : s.materials)
    if (m.name == name) return m;
  throw std::runtime_error("no material " + name);
}

void expectCorpusScene(const Scene& s) {
  // "card": one glTF mesh used by two nodes: one object, two instances.
  int32_t card = -1, glass = -1;
  ASSERT_TRUE(object(s, "card", &card));
  ASSERT_TRUE(object(s, "glass", &glass));
  EXPECT_EQ(s.objects.size(), 2u + 2u);  // + the point and the spot emitters
  auto cards = placements(s, card);
  ASSERT_EQ(cards.size(), 2u);
  EXPECT_EQ(cards[0].t, Vec3f(10, 0, 1));        // root then child translation
  Vec3f p = cards[1].transformPoint({1, 0, 0});  // scaled 2, turned 90 degrees about z
  EXPECT_NEAR(p.x, 10, 1e-5);
  EXPECT_NEAR(p.y, 2, 1e-5);
  // EXT_mesh_gpu_instancing: three placements with their own scales.
  auto crowd = placements(s, glass);
  ASSERT_EQ(crowd.size(), 3u);
  EXPECT_EQ(crowd[2].t, Vec3f(10, 7, 0));
  EXPECT_NEAR(crowd[2].determinant(), 27, 1e-4);

  // Materials.
  const Material& masked = material(s, "masked");
  ASSERT_NE(masked.baseColorTexture, kNoTexture);
  EXPECT_EQ(masked.alphaTexture, masked.baseColorTexture);
  // A dielectric base: the specular layer takes the material's roughness.
  const auto* maskedCoat = modelAs<CoatedDiffuseModel>(masked);
  ASSERT_NE(maskedCoat, nullptr);
  EXPECT_FLOAT_EQ(maskedCoat->roughness, 0.8f);
  const Texture& tex = s.textures[size_t(masked.baseColorTexture)];
  ASSERT_EQ(tex.width, 2);
  EXPECT_EQ(tex.wrap, WrapMode::Clamp);
  // glTF's v runs down the image: uv (0.25, 0.75) in Ferry is the top-left texel, red.
  EXPECT_GT(tex.sample({0.25f, 0.75f}).x, 0.99f);
  EXPECT_EQ(tex.sampleAlpha({0.75f, 0.75f}), 0.0f);  // top right: transparent green
  const auto* glassModel = modelAs<DielectricModel>(material(s, "glass"));
  ASSERT_NE(glassModel, nullptr);
  EXPECT_FLOAT_EQ(glassModel->ior, 1.33f);

  // The emissive texture glows in its top-left texel only: of the glowing
  // quad's two triangles, the upper-left one emits most, orange.
  float best = 0;
  Vec3f bestEmission(0);
  Vec3f bestCentroid(0);
  for (int32_t m : s.objects[size_t(card)].meshes) {
    const Mesh& mesh = s.meshes[size_t(m)];
    const Material& mat = s.materials[size_t(mesh.material)];
    EXPECT_FLOAT_EQ(mat.baseColor.x, mat.name.rfind("glowing", 0) == 0 ? 0.2f : 1.0f);
    if (maxComponent(mat.emission) > best) {
      best = maxComponent(mat.emission);
      bestEmission = mat.emission;
      ASSERT_EQ(mesh.triangleCount(), 1u);
      const Vec3i& t = mesh.indices[0];
      bestCentroid = (mesh.positions[t.x] + mesh.positions[t.y] + mesh.positions[t.z]) / 3.0f;
    }
  }
  EXPECT_GT(best, 1.0f);  // strength 4 times part of a texel of 1
  EXPECT_GT(bestEmission.x, bestEmission.y);
  EXPECT_NEAR(bestEmission.z, 0, 1e-4);
  EXPECT_LT(bestCentroid.x, 0.5f);
  EXPECT_GT(bestCentroid.y, 0.5f);

  // Cameras: by name, or camera<i>.
  ASSERT_EQ(s.views.size(), 2u);
  EXPECT_EQ(s.views[0].name, "front");
  EXPECT_EQ(s.views[0].from, Vec3f(0, 0, 20));
  EXPECT_NEAR(s.views[0].fovY, 0.6f * 180 / kPi, 1e-3);
  EXPECT_NEAR(normalize(s.views[0].at - s.views[0].from).z, -1, 1e-6);
  EXPECT_EQ(s.views[1].name, "camera1");
  EXPECT_NEAR(normalize(s.views[1].at - s.views[1].from).y, -1, 1e-5);
  EXPECT_NO_THROW(s.view("camera1"));

  // Lights: the sun shines down (it lies towards +y), the lamps are emitters.
  ASSERT_EQ(s.suns.size(), 1u);
  EXPECT_NEAR(s.suns[0].direction.y, 1, 1e-5);
  EXPECT_NEAR(s.suns[0].irradiance.x, 3, 1e-5);
  int emitters = 0;
  for (const Material& m : s.materials) emitters += m.name == "light1" || m.name == "light2";
  EXPECT_EQ(emitters, 2);
  EXPECT_TRUE(s.environment.isBlack());  // the file brings its own lights
}

TEST(GltfLoader, TextWithBinAndImageFiles) {
  std::vector<std::string> w;
  Scene s = load("scene.gltf", &w);
  expectCorpusScene(s);
  EXPECT_EQ(s.name, "scene");
}

TEST(GltfLoader, BinaryGlbIsTheSameScene) {
  expectCorpusScene(load("scene.glb"));
}

TEST(GltfLoader, DataUrisAreTheSameScene) {
  expectCorpusScene(load("datauri.gltf"));
}

TEST(GltfLoader, SceneLoaderPicksItByExtension) {
  Scene s = loadGltf(corpus("scene.glb"));
  EXPECT_EQ(s.meshes.size(), load("scene.gltf").meshes.size());
}

struct BadGltf {
  std::string file;
  std::string contains;
};

std::ostream& operator<<(std::ostream& os, const BadGltf& b) {
  return os << b.file;
}

class GltfCorpusError : public testing::TestWithParam<BadGltf> {};

TEST_P(GltfCorpusError, SaysWhatAndWhere) {
  const BadGltf& bad = GetParam();
  try {
    load(bad.file);
    FAIL() << bad.file << " loaded without error";
  } catch (const InputError& e) {
    std::string m = e.what();
    EXPECT_NE(m.find(bad.file), std::string::npos) << m;
    EXPECT_NE(m.find(bad.contains), std::string::npos) << m << "\nexpected: " << bad.contains;
  }
}

const std::vector<BadGltf> kBadGltf = {
    {"accessor_overrun.gltf", "accessor 0 (1000 elements) goes past its buffer view"},
    {"huge_count.gltf", "has 4000000000 elements: too many"},
    {"index_out_of_range.gltf", "index 99 (entry 2) is out of range: 3 vertices"},
    {"nan_position.gltf", "position 1 is not finite"},
    {"missing_bin.gltf", "not here.bin"},
    {"node_cycle.gltf", "node 0 is its own ancestor"},
    {"missing_image.gltf", "file \"no such image.png\" not found"},
    {"bad_accessor_index.gltf", "accessor 7 does not exist"},
    {"bad_json.gltf", "bad_json.gltf: "},
    {"truncated.glb", "truncated?"},
    {"bad_magic.glb", "not a .glb file"},
    {"lying_length.glb", "truncated?"},
    {"bad_ior.gltf", "material \"lens\": KHR_materials_ior ior is -1.5: must be 0 or at least 1"},
    {"bad_clearcoat.gltf",
     "material \"paint\": KHR_materials_clearcoat clearcoatFactor is 2: must be in [0, 1]"},
    {"bad_specular_type.gltf",
     "material \"shiny\": KHR_materials_specular is [1,1,1], not an object"},
    {"bad_transmission_texture.gltf",
     "material \"frosted\": KHR_materials_transmission transmissionTexture uses texture 5, which "
     "does not exist (1 textures)"},
    {"bad_texture_transform.gltf",
     "material \"atlas\": baseColorTexture KHR_texture_transform "
     "scale is \"big\", not an array of 2 numbers"},
    {"bad_overflowing_factor.gltf",
     "material \"glass\": KHR_materials_transmission transmissionFactor is 1e+39: not a finite "
     "single-precision number"},
};

INSTANTIATE_TEST_SUITE_P(Corpus, GltfCorpusError, testing::ValuesIn(kBadGltf));

TEST(GltfLoader, EveryCorpusFileIsCovered) {
  std::set<std::string> tested = {"scene.gltf", "scene.glb", "datauri.gltf"};
  for (const BadGltf& b : kBadGltf) tested.insert(b.file);
  for (const auto& entry : fs::directory_iterator(kCorpus)) {
    std::string ext = entry.path().extension().string();
    if (ext == ".gltf" || ext == ".glb") {
      EXPECT_TRUE(tested.count(entry.path().filename().string())) << entry.path();
    }
  }
}

// ------------------------------------------- materials, in files the tests write

// One small glTF in a directory of its own: a unit quad in z = 0 facing +z
// (two counter-clockwise triangles), TEXCOORD_0 running from glTF's top-left
// corner and TEXCOORD_1 the same halved, using material 0 of the materials
// the test gives; images are PNGs the test writes next to it.
class QuadFile {
 public:
  QuadFile() {
    std::string test = testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(test.begin(), test.end(), '/', '_');  // parameterised: "Suite/param"
    dir_ =
        fs::temp_directory_path() / ("ferry_gltf_test_" + std::to_string(::getpid()) + "_" + test);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~QuadFile() { fs::remove_all(dir_); }

  // A w x h RGBA image (rows top first) as a texture; returns the texture's index.
  int texture(int width, int height, const std::vector<uint8_t>& rgba, bool clamp = false) {
    const std::string name = "image" + std::to_string(images_.size()) + ".png";
    writePng((dir_ / name).string(), width, height, rgba);
    images_.push_back({{"uri", name}});
    nlohmann::json t = {{"source", images_.size() - 1}};
    if (clamp) t["sampler"] = 0;
    textures_.push_back(t);
    return int(textures_.size() - 1);
  }

  std::string path() const { return (dir_ / "quad.gltf").string(); }

  Scene load(const nlohmann::json& materials, std::vector<std::string>* warnings = nullptr) {
    write(materials);
    LoadOptions options;
    options.warn = [&](const std::string& w) {
      if (warnings) warnings->push_back(w);
    };
    Scene s = loadGltf(path(), options);
    s.validate();
    return s;
  }

  void write(const nlohmann::json& materials) {
    std::vector<float> floats = {0, 0,  0,  1,  0,  0, 1, 1, 0, 0, 1, 0,  // positions
                                 0, 0,  1,  0,  0,  1, 0, 0, 1, 0, 0, 1,  // normals
                                 0, 1,  1,  1,  1,  0, 0, 0,              // TEXCOORD_0
                                 0, .5, .5, .5, .5, 0, 0, 0};             // TEXCOORD_1
    std::vector<uint16_t> indices = {0, 1, 2, 0, 2, 3, 0, 0};             // padded to 4 bytes
    std::ofstream bin(dir_ / "quad.bin", std::ios::binary);
    bin.write(reinterpret_cast<const char*>(floats.data()), std::streamsize(floats.size() * 4));
    bin.write(reinterpret_cast<const char*>(indices.data()), std::streamsize(indices.size() * 2));
    bin.close();
    nlohmann::json doc = {
        {"asset", {{"version", "2.0"}}},
        {"extensionsUsed",
         {"KHR_materials_ior", "KHR_materials_transmission", "KHR_materials_specular",
          "KHR_materials_clearcoat", "KHR_materials_emissive_strength", "KHR_texture_transform"}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", {{{"mesh", 0}}}},
        {"meshes",
         {{{"primitives",
            {{{"attributes",
               {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}, {"TEXCOORD_1", 3}}},
              {"indices", 4},
              {"material", 0}}}}}}},
        {"materials", materials},
        {"buffers", {{{"uri", "quad.bin"}, {"byteLength", floats.size() * 4 + 16}}}},
        {"bufferViews",
         {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
          {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 48}},
          {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 32}},
          {{"buffer", 0}, {"byteOffset", 128}, {"byteLength", 32}},
          {{"buffer", 0}, {"byteOffset", 160}, {"byteLength", 12}}}},
        {"accessors",
         {{{"bufferView", 0},
           {"componentType", 5126},
           {"count", 4},
           {"type", "VEC3"},
           {"min", {0, 0, 0}},
           {"max", {1, 1, 0}}},
          {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
          {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
          {{"bufferView", 3}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
          {{"bufferView", 4}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}},
        {"samplers", {{{"wrapS", 33071}, {"wrapT", 33071}}}}};
    if (!textures_.empty()) {
      doc["textures"] = textures_;
      doc["images"] = images_;
    }
    std::ofstream((dir_ / "quad.gltf").string()) << doc.dump(1);
  }

 private:
  fs::path dir_;
  nlohmann::json textures_ = nlohmann::json::array(), images_ = nlohmann::json::array();
};

// Material 0 of the scene (the quad's; the emission split may add copies).
const Material& quadMaterial(const Scene& s) {
  return s.materials[size_t(s.meshes.at(0).material)];
}

bool saidOnce(const std::vector<std::string>& warnings, const std::string& part) {
  return std::count_if(warnings.begin(), warnings.end(), [&](const std::string& w) {
           return w.find(part) != std::string::npos;
         }) == 1;
}

TEST(GltfMaterials, DielectricBaseHasTheSpecsSpecularLayer) {
  QuadFile file;
  Scene s = file.load({{{"name", "plastic"},
                        {"pbrMetallicRoughness",
                         {{"baseColorFactor", {0.5, 0.2, 0.1, 1}},
                          {"metallicFactor", 0},
                          {"roughnessFactor", 0.4}}}}});
  const auto* coat = modelAs<CoatedDiffuseModel>(quadMaterial(s));
  ASSERT_NE(coat, nullptr);
  EXPECT_TRUE(coat->layered);
  EXPECT_EQ(coat->specular, Vec3f(1));
  EXPECT_FLOAT_EQ(coat->roughness, 0.4f);
  EXPECT_EQ(coat->eta, 1.5f);  // F0 0.04
}

TEST(GltfMaterials, MetalsStayConductorsWithoutACoat) {
  QuadFile file;
  Scene s = file.load({{{"name", "gold"},
                        {"pbrMetallicRoughness",
                         {{"baseColorFactor", {1, 0.8, 0.3, 1}},
                          {"metallicFactor", 1},
                          {"roughnessFactor", 0.3}}}}});
  // A bare (uncoated) conductor, rough.
  const auto* metal = modelAs<ConductorModel>(quadMaterial(s));
  ASSERT_NE(metal, nullptr);
  EXPECT_FLOAT_EQ(metal->roughness, 0.3f);
}

TEST(GltfMaterials, IorRefractsAndSetsTheSpecularLayer) {
  QuadFile file;
  Scene s = file.load({{{"name", "water"},
                        {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0}}},
                        {"extensions",
                         {{"KHR_materials_ior", {{"ior", 1.33}}},
                          {"KHR_materials_transmission", {{"transmissionFactor", 1}}}}}}});
  // Transmitting: a smooth dielectric of that ior.
  const auto* water = modelAs<DielectricModel>(quadMaterial(s));
  ASSERT_NE(water, nullptr);
  EXPECT_FLOAT_EQ(water->ior, 1.33f);
  EXPECT_EQ(water->roughness, 0.0f);
  // Opaque: the specular layer over the diffuse base has that ior.
  s = file.load({{{"name", "wet"},
                  {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0}}},
                  {"extensions", {{"KHR_materials_ior", {{"ior", 1.33}}}}}}});
  const auto* coat = modelAs<CoatedDiffuseModel>(quadMaterial(s));
  ASSERT_NE(coat, nullptr);
  EXPECT_FLOAT_EQ(coat->eta, 1.33f);
}

TEST(GltfMaterials, LegacyIorZeroReflectsTheSpecularColour) {
  QuadFile file;
  Scene s =
      file.load({{{"name", "legacy"},
                  {"pbrMetallicRoughness", {{"metallicFactor", 0}}},
                  {"extensions",
                   {{"KHR_materials_ior", {{"ior", 0}}},
                    {"KHR_materials_specular", {{"specularColorFactor", {0.5, 0.5, 0.5}}}}}}}});
  const auto* coat = modelAs<CoatedDiffuseModel>(quadMaterial(s));
  ASSERT_NE(coat, nullptr);
  EXPECT_NEAR(coat->specular.x * fresnelDielectric(1, coat->eta), 0.5f, 1e-5f);
  // 0 has no refraction: a transmitting material keeps the default ior.
  s = file.load({{{"name", "legacy glass"},
                  {"pbrMetallicRoughness", {{"metallicFactor", 0}}},
                  {"extensions",
                   {{"KHR_materials_ior", {{"ior", 0}}},
                    {"KHR_materials_transmission", {{"transmissionFactor", 1}}}}}}});
  const auto* glass = modelAs<DielectricModel>(quadMaterial(s));
  ASSERT_NE(glass, nullptr);
  EXPECT_EQ(glass->ior, 1.5f);
}

TEST(GltfMaterials, TransmissionIsTheFactorTimesTheMeanOfItsTexture) {
  QuadFile file;
  int half = file.texture(2, 1, {255, 9, 9, 255, 0, 9, 9, 255});  // red channel: mean 0.5
  std::vector<std::string> w;
  Scene s =
      file.load({{{"name", "frosted"},
                  {"pbrMetallicRoughness", {{"metallicFactor", 0}}},
                  {"extensions",
                   {{"KHR_materials_transmission",
                     {{"transmissionFactor", 0.8}, {"transmissionTexture", {{"index", half}}}}}}}}},
                &w);
  // 0.8 * 0.5 = 0.4: below the dielectric's 0.5, an opaque (coated diffuse) surface.
  EXPECT_NE(modelAs<CoatedDiffuseModel>(quadMaterial(s)), nullptr);
  EXPECT_TRUE(saidOnce(w, "transmission textures are averaged")) << ::testing::PrintToString(w);
  // Red 1 and 128/255 (mean 0.75): 0.8 * 0.75 = 0.6, glass.
  int most = file.texture(2, 1, {255, 9, 9, 255, 128, 9, 9, 255});
  s = file.load(
      {{{"name", "clearer"},
        {"pbrMetallicRoughness", {{"metallicFactor", 0}}},
        {"extensions",
         {{"KHR_materials_transmission",
           {{"transmissionFactor", 0.8}, {"transmissionTexture", {{"index", most}}}}}}}}});
  EXPECT_NE(modelAs<DielectricModel>(quadMaterial(s)), nullptr);
}

TEST(GltfMaterials, SpecularFactorAndColourWithTheirTextures) {
  QuadFile file;
  // specularTexture: alpha 255 and 0 (mean 0.5); specularColorTexture: sRGB
  // 188 everywhere (linear about 0.5).
  int strength = file.texture(2, 1, {9, 9, 9, 255, 9, 9, 9, 0});
  int color = file.texture(1, 1, {188, 188, 188, 255});
  std::vector<std::string> w;
  Scene s = file.load({{{"name", "tinted"},
                        {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0.5}}},
                        {"extensions",
                         {{"KHR_materials_specular",
                           {{"specularFactor", 0.5},
                            {"specularColorFactor", {1, 0.5, 0.25}},
                            {"specularTexture", {{"index", strength}}},
                            {"specularColorTexture", {{"index", color}}}}}}}}},
                      &w);
  const auto* coat = modelAs<CoatedDiffuseModel>(quadMaterial(s));
  ASSERT_NE(coat, nullptr);
  const float linear = srgbToLinear(188 / 255.0f);
  // F0 = 0.04 * colour * texture, times specularFactor * 0.5; the largest
  // channel (0.04 * linear) goes into eta, the rest into the tint.
  EXPECT_NEAR(fresnelDielectric(1, coat->eta), 0.04f * linear, 1e-5f);
  EXPECT_NEAR(coat->specular.x, 0.25f, 1e-6f);
  EXPECT_NEAR(coat->specular.y, 0.125f, 1e-6f);
  EXPECT_NEAR(coat->specular.z, 0.0625f, 1e-6f);
  EXPECT_FLOAT_EQ(coat->roughness, 0.5f);
  EXPECT_TRUE(saidOnce(w, "specular textures are averaged"));
  EXPECT_TRUE(saidOnce(w, "specularColor textures are averaged"));
}

TEST(GltfMaterials, SpecularColourAboveOneRaisesF0) {
  QuadFile file;
  Scene s = file.load(
      {{{"name", "bright"},
        {"pbrMetallicRoughness", {{"metallicFactor", 0}}},
        {"extensions", {{"KHR_materials_specular", {{"specularColorFactor", {2, 2, 2}}}}}}}});
  const auto* coat = modelAs<CoatedDiffuseModel>(quadMaterial(s));
  ASSERT_NE(coat, nullptr);
  EXPECT_NEAR(fresnelDielectric(1, coat->eta), 0.08f, 1e-5f);
  EXPECT_NEAR(maxComponent(coat->specular), 1, 1e-6f);  // never above 1: F reaches 1 at grazing
}

TEST(GltfMaterials, ClearcoatBecomesTheCoat) {
  QuadFile file;
  std::vector<std::string> w;
  Scene s = file.load({{{"name", "lacquer"},
                        {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0.9}}},
                        {"extensions",
                         {{"KHR_materials_clearcoat",
                           {{"clearcoatFactor", 1}, {"clearcoatRoughnessFactor", 0.1}}}}}}},
                      &w);
  const auto* coat = modelAs<CoatedDiffuseModel>(quadMaterial(s));
  ASSERT_NE(coat, nullptr);
  EXPECT_TRUE(coat->layered);
  EXPECT_EQ(coat->specular, Vec3f(1));
  EXPECT_EQ(coat->eta, 1.5f);
  EXPECT_FLOAT_EQ(coat->roughness, 0.1f);
  EXPECT_TRUE(saidOnce(w, "Ferry has one coat")) << ::testing::PrintToString(w);
}

TEST(GltfMaterials, ClearcoatTexturesAreAveragedAndMixed) {
  QuadFile file;
  // Red (clearcoatTexture) and green (clearcoatRoughnessTexture) both average 0.5.
  int coat = file.texture(2, 1, {255, 255, 0, 255, 0, 0, 0, 255});
  std::vector<std::string> w;
  Scene s = file.load({{{"name", "half"},
                        {"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0.9}}},
                        {"extensions",
                         {{"KHR_materials_clearcoat",
                           {{"clearcoatFactor", 1},
                            {"clearcoatTexture", {{"index", coat}}},
                            {"clearcoatRoughnessFactor", 0.2},
                            {"clearcoatRoughnessTexture", {{"index", coat}}},
                            {"clearcoatNormalTexture", {{"index", coat}}}}}}}}},
                      &w);
  const auto* mixed = modelAs<CoatedDiffuseModel>(quadMaterial(s));
  ASSERT_NE(mixed, nullptr);
  // Clear coat 0.5 (tint 1, eta 1.5, roughness 0.1) mixed half and half
  // with the specular layer (tint 1, eta 1.5, roughness 0.9).
  EXPECT_EQ(mixed->specular, Vec3f(1));
  EXPECT_FLOAT_EQ(mixed->eta, 1.5f);
  EXPECT_NEAR(mixed->roughness, 0.5f, 1e-6f);
  EXPECT_TRUE(saidOnce(w, "clearcoat textures are averaged")) << ::testing::PrintToString(w);
  EXPECT_TRUE(saidOnce(w, "clearcoatRoughness textures are averaged"));
  EXPECT_TRUE(saidOnce(w, "clearcoatNormalTexture is ignored"));
}

TEST(GltfMaterials, ClearcoatOnAMetalIsDropped) {
  QuadFile file;
  std::vector<std::string> w;
  Scene s = file.load({{{"name", "coated metal"},
                        {"pbrMetallicRoughness", {{"metallicFactor", 1}}},
                        {"extensions", {{"KHR_materials_clearcoat", {{"clearcoatFactor", 1}}}}}}},
                      &w);
  EXPECT_NE(modelAs<ConductorModel>(quadMaterial(s)), nullptr);  // not a coated conductor
  EXPECT_TRUE(saidOnce(w, "a clear coat on a metallic material is dropped"));
}

// The quad's vertex i in Ferry's uvs: glTF's (u, v) at the corners are
// (0, 1), (1, 1), (1, 0), (0, 0).
Vec2f quadUv(const Scene& s, int vertex) {
  return s.meshes.at(0).uvs.at(size_t(vertex));
}

void expectUv(Vec2f got, Vec2f want) {
  EXPECT_NEAR(got.x, want.x, 1e-6f);
  EXPECT_NEAR(got.y, want.y, 1e-6f);
}

TEST(GltfMaterials, TextureTransformIsBakedIntoTheUvs) {
  QuadFile file;
  int checker = file.texture(1, 1, {255, 255, 255, 255});
  // The extension's own example: the lower-left quadrant of the image, turned.
  Scene s = file.load(
      {{{"name", "atlas"},
        {"pbrMetallicRoughness",
         {{"baseColorTexture",
           {{"index", checker},
            {"extensions",
             {{"KHR_texture_transform",
               {{"offset", {0, 1}}, {"rotation", 1.57079632679}, {"scale", {0.5, 0.5}}}}}}}}}}}});
  // glTF (0, 1) -> (0.5, 1), (1, 1) -> (0.5, 0.5), (1, 0) -> (0, 0.5), (0, 0)
  // -> (0, 1): u in [0, 0.5], v in [0.5, 1] (the lower left); Ferry's v = 1 - v.
  expectUv(quadUv(s, 0), {0.5f, 0});
  expectUv(quadUv(s, 1), {0.5f, 0.5f});
  expectUv(quadUv(s, 2), {0, 0.5f});
  expectUv(quadUv(s, 3), {0, 0});
}

TEST(GltfMaterials, TextureCoordinateSetsAreRead) {
  QuadFile file;
  int white = file.texture(1, 1, {255, 255, 255, 255});
  // texCoord 1 (TEXCOORD_1: the set halved), on the textureInfo ...
  nlohmann::json second = {{"index", white}, {"texCoord", 1}};
  Scene s = file.load(
      {{{"name", "second set"}, {"pbrMetallicRoughness", {{"baseColorTexture", second}}}}});
  expectUv(quadUv(s, 1), {0.5f, 0.5f});
  // ... or overridden by KHR_texture_transform's, with its offset.
  nlohmann::json override = {
      {"index", white},
      {"extensions", {{"KHR_texture_transform", {{"texCoord", 1}, {"offset", {0.25, 0}}}}}}};
  s = file.load(
      {{{"name", "override"}, {"pbrMetallicRoughness", {{"baseColorTexture", override}}}}});
  expectUv(quadUv(s, 1), {0.75f, 0.5f});
}

TEST(GltfMaterials, NormalMapOnOtherUvsUsesTheBaseColours) {
  QuadFile file;
  int white = file.texture(1, 1, {255, 255, 255, 255});
  int flat = file.texture(1, 1, {128, 128, 255, 255});
  std::vector<std::string> w;
  Scene s = file.load(
      {{{"name", "mixed"},
        {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", white}}}}},
        {"normalTexture",
         {{"index", flat}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}}}},
      &w);
  expectUv(quadUv(s, 1), {1, 0});  // the base colour's: untransformed
  EXPECT_TRUE(saidOnce(w, "normalTexture and baseColorTexture use other texture coordinates"))
      << ::testing::PrintToString(w);
  // Without a base colour texture, the normal map's transform is the mesh's.
  s = file.load(
      {{{"name", "bumpy"},
        {"normalTexture",
         {{"index", flat}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}}}});
  expectUv(quadUv(s, 1), {2, -1});
}

TEST(GltfMaterials, EmissiveTextureIsBakedWithItsOwnTransform) {
  QuadFile file;
  // Left texel white, right black; clamped. A transform of scale 0 looks
  // every point up at the offset: the white texel's centre, or the black one's.
  int glow = file.texture(2, 1, {255, 255, 255, 255, 0, 0, 0, 255}, /*clamp=*/true);
  auto emissive = [&](double u) {
    return nlohmann::json::array(
        {{{"name", "panel"},
          {"emissiveFactor", {1, 1, 1}},
          {"emissiveTexture",
           {{"index", glow},
            {"extensions",
             {{"KHR_texture_transform", {{"offset", {u, 0.5}}, {"scale", {0, 0}}}}}}}}}});
  };
  Scene s = file.load(emissive(0.25));
  ASSERT_EQ(s.meshes.size(), 1u);  // every triangle the same: one emitting mesh
  EXPECT_NEAR(quadMaterial(s).emission.x, 1, 1e-6f);
  expectUv(quadUv(s, 1), {1, 0});  // the mesh keeps its own uvs
  s = file.load(emissive(0.75));
  EXPECT_FALSE(quadMaterial(s).isEmissive());
}

TEST(GltfMaterials, EmissionIsOneSidedUnlessDoubleSided) {
  QuadFile file;
  for (bool doubleSided : {false, true}) {
    nlohmann::json lamp = {
        {"name", "lamp"}, {"emissiveFactor", {1, 1, 1}}, {"doubleSided", doubleSided}};
    Scene s = file.load(nlohmann::json::array({lamp}));
    const Material& m = quadMaterial(s);
    EXPECT_TRUE(m.isEmissive());
    EXPECT_EQ(m.emitsBackSide, doubleSided);
    // The emitting side is the winding normal's: glTF's front (counter-clockwise), +z here.
    const Mesh& mesh = s.meshes[0];
    for (const Vec3i& t : mesh.indices) {
      Vec3f n = cross(mesh.positions[size_t(t.y)] - mesh.positions[size_t(t.x)],
                      mesh.positions[size_t(t.z)] - mesh.positions[size_t(t.x)]);
      EXPECT_GT(n.z, 0);
    }
  }
}

TEST(GltfMaterials, NormalTextureIsLinearAndScaled) {
  QuadFile file;
  int map = file.texture(1, 1, {64, 128, 255, 255});
  Scene s = file.load({{{"name", "bumpy"},
                        {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", map}}}}},
                        {"normalTexture", {{"index", map}, {"scale", 0.5}}}}});
  const Material& m = quadMaterial(s);
  ASSERT_NE(m.normalTexture, kNoTexture);
  EXPECT_FLOAT_EQ(m.normalScale, 0.5f);
  const Texture& normal = s.textures[size_t(m.normalTexture)];
  EXPECT_FALSE(normal.srgb);
  Vec4f texel = normal.sample({0.5f, 0.5f});
  EXPECT_FLOAT_EQ(texel.x, 64 / 255.0f);  // raw, not decoded from sRGB
  EXPECT_FLOAT_EQ(texel.y, 128 / 255.0f);
  // The same image as a base colour is another texture, decoded from sRGB.
  ASSERT_NE(m.baseColorTexture, m.normalTexture);
  EXPECT_TRUE(s.textures[size_t(m.baseColorTexture)].srgb);
  // Without "scale", 1.
  s = file.load({{{"name", "plain"}, {"normalTexture", {{"index", map}}}}});
  EXPECT_EQ(quadMaterial(s).normalScale, 1.0f);
}

struct BadMaterial {
  std::string name;
  nlohmann::json material;  // pbrMetallicRoughness, normalTexture, extensions, ...
  std::string contains;
};

std::ostream& operator<<(std::ostream& os, const BadMaterial& b) {
  return os << b.name;
}

class GltfMaterialError : public testing::TestWithParam<BadMaterial> {};

TEST_P(GltfMaterialError, NamesTheFileTheMaterialAndTheValue) {
  const BadMaterial& bad = GetParam();
  QuadFile file;
  file.texture(1, 1, {255, 255, 255, 255});  // texture 0
  nlohmann::json material = bad.material;
  material["name"] = "bad";
  try {
    file.load(nlohmann::json::array({material}));
    FAIL() << bad.name << " loaded without error";
  } catch (const InputError& e) {
    std::string m = e.what();
    EXPECT_NE(m.find(file.path() + ": material \"bad\": "), std::string::npos) << m;
    EXPECT_NE(m.find(bad.contains), std::string::npos) << m << "\nexpected: " << bad.contains;
  }
}

nlohmann::json withExtension(const char* name, nlohmann::json value) {
  return {{"extensions", {{name, std::move(value)}}}};
}

nlohmann::json withTransform(nlohmann::json transform) {
  return {{"pbrMetallicRoughness",
           {{"baseColorTexture",
             {{"index", 0}, {"extensions", {{"KHR_texture_transform", std::move(transform)}}}}}}}};
}

const std::vector<BadMaterial> kBadMaterials = {
    {"negative ior", withExtension("KHR_materials_ior", {{"ior", -1}}),
     "KHR_materials_ior ior is -1: must be 0 or at least 1"},
    {"ior below 1", withExtension("KHR_materials_ior", {{"ior", 0.5}}),
     "KHR_materials_ior ior is 0.5: must be 0 or at least 1"},
    {"ior not a number", withExtension("KHR_materials_ior", {{"ior", "glass"}}),
     "KHR_materials_ior ior is \"glass\", not a number"},
    {"transmission above 1",
     withExtension("KHR_materials_transmission", {{"transmissionFactor", 1.5}}),
     "KHR_materials_transmission transmissionFactor is 1.5: must be in [0, 1]"},
    {"transmission texture missing",
     withExtension("KHR_materials_transmission", {{"transmissionTexture", {{"index", 9}}}}),
     "transmissionTexture uses texture 9, which does not exist (1 textures)"},
    {"transmission texture index not an integer",
     withExtension("KHR_materials_transmission", {{"transmissionTexture", {{"index", 0.5}}}}),
     "transmissionTexture index is 0.5, not an integer"},
    {"transmission texture index too large",
     withExtension("KHR_materials_transmission",
                   {{"transmissionTexture", {{"index", 4294967296}}}}),
     "transmissionTexture index is 4294967296: too large"},
    {"transmission texture without index",
     withExtension("KHR_materials_transmission", {{"transmissionTexture", {{"texCoord", 0}}}}),
     "transmissionTexture has no index"},
    {"clearcoat not a number",
     withExtension("KHR_materials_clearcoat", {{"clearcoatFactor", "high"}}),
     "KHR_materials_clearcoat clearcoatFactor is \"high\", not a number"},
    {"clearcoat roughness negative",
     withExtension("KHR_materials_clearcoat", {{"clearcoatRoughnessFactor", -0.1}}),
     "KHR_materials_clearcoat clearcoatRoughnessFactor is -0.1: must be in [0, 1]"},
    {"clearcoat texture not an object",
     withExtension("KHR_materials_clearcoat", {{"clearcoatTexture", 0}}),
     "KHR_materials_clearcoat clearcoatTexture is 0, not a textureInfo object"},
    {"specular not finite", withExtension("KHR_materials_specular", {{"specularFactor", 1e39}}),
     "KHR_materials_specular specularFactor is 1e+39: not a finite single-precision number"},
    {"specular colour of two",
     withExtension("KHR_materials_specular", {{"specularColorFactor", {1, 1}}}),
     "KHR_materials_specular specularColorFactor is [1,1], not an array of 3 numbers"},
    {"specular colour negative",
     withExtension("KHR_materials_specular", {{"specularColorFactor", {1, -1, 1}}}),
     "KHR_materials_specular specularColorFactor is -1: must be at least 0"},
    {"extension not an object", withExtension("KHR_materials_specular", 3),
     "KHR_materials_specular is 3, not an object"},
    {"emissive strength negative",
     withExtension("KHR_materials_emissive_strength", {{"emissiveStrength", -2}}),
     "KHR_materials_emissive_strength emissiveStrength is -2: must be at least 0"},
    {"transform scale of one", withTransform({{"scale", {1}}}),
     "baseColorTexture KHR_texture_transform scale is [1], not an array of 2 numbers"},
    {"transform rotation not a number", withTransform({{"rotation", "left"}}),
     "baseColorTexture KHR_texture_transform rotation is \"left\", not a number"},
    {"transform offset not finite", withTransform({{"offset", {0, -1e39}}}),
     "baseColorTexture KHR_texture_transform offset is -1e+39: not a finite"},
    {"transform texCoord negative", withTransform({{"texCoord", -1}}),
     "baseColorTexture KHR_texture_transform texCoord is -1: must be at least 0"},
    {"transform not an object", withTransform(5), "KHR_texture_transform is 5, not an object"},
    {"normal scale not finite",
     {{"normalTexture", {{"index", 0}, {"scale", 1e39}}}},
     "normalTexture scale is 1e+39: not a finite single-precision number"},
};

INSTANTIATE_TEST_SUITE_P(Values, GltfMaterialError, testing::ValuesIn(kBadMaterials),
                         [](const testing::TestParamInfo<BadMaterial>& info) {
                           std::string name = info.param.name;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace ferry
