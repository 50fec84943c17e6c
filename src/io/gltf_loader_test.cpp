#include "io/gltf_loader.h"

#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "gltf";

std::string corpus(const std::string& name) {
  return (kCorpus / name).string();
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
  EXPECT_FLOAT_EQ(masked.roughness, 0.8f);
  const Texture& tex = s.textures[size_t(masked.baseColorTexture)];
  ASSERT_EQ(tex.width, 2);
  EXPECT_EQ(tex.wrap, WrapMode::Clamp);
  // glTF's v runs down the image: uv (0.25, 0.75) in Ferry is the top-left texel, red.
  EXPECT_GT(tex.sample({0.25f, 0.75f}).x, 0.99f);
  EXPECT_EQ(tex.sampleAlpha({0.75f, 0.75f}), 0.0f);  // top right: transparent green
  const Material& glassMaterial = material(s, "glass");
  EXPECT_EQ(glassMaterial.transmission, 1);
  EXPECT_FLOAT_EQ(glassMaterial.ior, 1.33f);

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

}  // namespace
}  // namespace ferry
