#include "io/obj/obj_loader.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "obj";

std::string corpus(const std::string& name) {
  return (kCorpus / name).string();
}

// The error loadObj throws for `path`; fails the test if it throws anything
// else or nothing.
InputError loadError(const std::string& path) {
  try {
    loadObj(path);
  } catch (const InputError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << path << ": expected an InputError, got: " << e.what();
    return InputError("wrong exception");
  }
  ADD_FAILURE() << path << ": loaded without error";
  return InputError("no exception");
}

const Mesh* findMesh(const Scene& scene, const std::string& name) {
  for (const Mesh& m : scene.meshes)
    if (m.name == name) return &m;
  return nullptr;
}

const Material* findMaterial(const Scene& scene, const std::string& name) {
  for (const Material& m : scene.materials)
    if (m.name == name) return &m;
  return nullptr;
}

// The material's model if it is a T, else null.
template <class T>
const T* modelAs(const Material& m) {
  return dynamic_cast<const T*>(m.model.get());
}

uint64_t totalTriangles(const Scene& scene) {
  uint64_t n = 0;
  for (const Mesh& m : scene.meshes) n += m.triangleCount();
  return n;
}

float triangleArea(const Mesh& mesh, const Vec3i& t) {
  return 0.5f * length(cross(mesh.positions[t.y] - mesh.positions[t.x],
                             mesh.positions[t.z] - mesh.positions[t.x]));
}

// ------------------------------------------------------------ malformed files

struct BadFile {
  std::string obj;         // the file passed to loadObj
  std::string errorIn;     // the file the error must name (the OBJ or one of its MTLs)
  int line;                // 0: the error has no line
  std::string contains;    // a piece of the message
  bool truncated = false;  // the message must (or must not) say the file looks truncated
};

std::ostream& operator<<(std::ostream& os, const BadFile& b) {
  return os << b.obj;
}

class ObjCorpusError : public testing::TestWithParam<BadFile> {};

TEST_P(ObjCorpusError, NamesFileAndLine) {
  const BadFile& bad = GetParam();
  InputError e = loadError(corpus(bad.obj));
  const std::string message = e.what();
  SCOPED_TRACE(message);
  RecordProperty("message", message);
  EXPECT_EQ(fs::path(e.where().file).filename().string(), bad.errorIn);
  EXPECT_EQ(e.where().line, bad.line);
  if (bad.line > 0) {
    EXPECT_NE(message.find(bad.errorIn + ":" + std::to_string(bad.line) + ": "), std::string::npos);
  } else {
    EXPECT_NE(message.find(bad.errorIn), std::string::npos);
  }
  EXPECT_NE(message.find(bad.contains), std::string::npos) << "expected: " << bad.contains;
  EXPECT_EQ(
      message.find("ends inside this line without a newline: truncated?") != std::string::npos,
      bad.truncated);
}

const std::vector<BadFile> kBadFiles = {
    BadFile{"bad_index.obj", "bad_index.obj", 7,
            "vertex index 5 is out of range: 4 vertices defined above this line"},
    BadFile{"bad_relative_index.obj", "bad_relative_index.obj", 5,
            "relative vertex index -4 is out of range: 3 vertices"},
    BadFile{"forward_reference.obj", "forward_reference.obj", 2,
            "vertex index 1 is out of range: 0 vertices"},
    BadFile{"zero_index.obj", "zero_index.obj", 5,
            "vertex index 0 is invalid (OBJ indices start at 1)"},
    BadFile{"bad_texcoord_index.obj", "bad_texcoord_index.obj", 7,
            "texture coordinate index 3 is out of range: 2 texture coordinates"},
    BadFile{"bad_normal_index.obj", "bad_normal_index.obj", 6,
            "normal index 2 is out of range: 1 normal defined"},
    BadFile{"nan_vertex.obj", "nan_vertex.obj", 3, "vertex value 'nan' is not finite"},
    BadFile{"inf_vertex.obj", "inf_vertex.obj", 2, "vertex value 'inf' is not finite"},
    BadFile{"huge_vertex.obj", "huge_vertex.obj", 3,
            "vertex value '1e39' is too large for a 32-bit float"},
    BadFile{"nan_normal.obj", "nan_normal.obj", 5, "normal value 'NaN' is not finite"},
    BadFile{"truncated.obj", "truncated.obj", 6, "vertex needs 3 numbers", true},
    BadFile{"truncated_face.obj", "truncated_face.obj", 7,
            "face needs at least 3 vertices, found 2", true},
    BadFile{"short_face.obj", "short_face.obj", 5, "face needs at least 3 vertices, found 2"},
    BadFile{"short_vertex.obj", "short_vertex.obj", 2, "vertex needs 3 numbers"},
    BadFile{"garbage_token.obj", "garbage_token.obj", 3, "expected a number, found 'abc'"},
    BadFile{"garbage_index.obj", "garbage_index.obj", 5, "expected a vertex index, found 'x'"},
    BadFile{"malformed_reference.obj", "malformed_reference.obj", 7,
            "malformed vertex reference '1/1/1/1'"},
    BadFile{"unknown_material.obj", "unknown_material.obj", 8,
            "unknown material 'blue' (not defined in unknown_material.mtl; defined: red)"},
    BadFile{"no_mtllib.obj", "no_mtllib.obj", 5,
            "unknown material 'red': no material library (mtllib)"},
    BadFile{"missing_mtl.obj", "missing_mtl.obj", 2,
            "material library 'does_not_exist.mtl' not found"},
    BadFile{"missing_texture.obj", "missing_texture.mtl", 3,
            "texture 'textures/no_such_texture.png' not found"},
    BadFile{"corrupt_texture.obj", "corrupt_texture.mtl", 3, "texture '../images/truncated.png': "},
    BadFile{"bad_mtl_number.obj", "bad_mtl_number.mtl", 2, "expected a number, found 'zero'"},
    BadFile{"nan_mtl.obj", "nan_mtl.mtl", 3, "Ns: value 'nan' is not finite"},
    BadFile{"empty.obj", "empty.obj", 0, "no faces"},
    BadFile{"no_faces.obj", "no_faces.obj", 0, "no faces"},
    BadFile{"continuation.obj", "continuation.obj", 5, "line continuation"},
    BadFile{"binary.obj", "binary.obj", 2, "NUL byte"}};

INSTANTIATE_TEST_SUITE_P(Corpus, ObjCorpusError, testing::ValuesIn(kBadFiles));

TEST(ObjLoader, MissingTextureNamesTheUsingObjLine) {
  InputError e = loadError(corpus("missing_texture.obj"));
  std::string message = e.what();
  EXPECT_NE(message.find("material 'wood' used at "), std::string::npos) << message;
  EXPECT_NE(message.find("missing_texture.obj:7"), std::string::npos) << message;
  EXPECT_NE(message.find((kCorpus / "textures" / "no_such_texture.png").string()),
            std::string::npos)
      << message;
}

TEST(ObjLoader, CorruptTextureSaysWhy) {
  InputError e = loadError(corpus("corrupt_texture.obj"));
  std::string message = e.what();
  EXPECT_NE(message.find("truncated.png: cannot decode image: "), std::string::npos) << message;
}

TEST(ObjLoader, MissingObjFile) {
  std::string path = corpus("no_such_file.obj");
  InputError e = loadError(path);
  EXPECT_EQ(std::string(e.what()), path + ": no such file");
}

TEST(ObjLoader, EveryCorpusObjIsCovered) {
  // A new corpus file must get a test: good files below, bad ones in the table.
  std::set<std::string> tested = {"textured_quad.obj", "cube.obj", "emissive_quad.obj",
                                  "features.obj"};
  for (const BadFile& bad : kBadFiles) tested.insert(bad.obj);
  for (const auto& entry : fs::directory_iterator(kCorpus)) {
    if (entry.path().extension() == ".obj") {
      EXPECT_TRUE(tested.count(entry.path().filename().string())) << entry.path();
    }
  }
}

// ------------------------------------------------------------------ good files

TEST(ObjLoader, TexturedQuadWithAlphaMaps) {
  Scene scene = loadObj(corpus("textured_quad.obj"));
  EXPECT_NO_THROW(scene.validate());
  EXPECT_EQ(scene.name, "textured_quad");
  ASSERT_EQ(scene.meshes.size(), 2u);
  ASSERT_EQ(scene.objects.size(), 2u);
  ASSERT_EQ(scene.instances.size(), 2u);
  EXPECT_EQ(scene.meshes[0].name, "leaf/leaf");
  EXPECT_EQ(scene.meshes[1].name, "card/card");
  for (const Mesh& m : scene.meshes) {
    EXPECT_EQ(m.vertexCount(), 4u);
    EXPECT_EQ(m.triangleCount(), 2u);
    EXPECT_EQ(m.normals.size(), 4u);
    EXPECT_EQ(m.uvs.size(), 4u);
    for (size_t v = 0; v < m.positions.size(); ++v) {
      // The uv of each corner is (x + 1) / 2, (y + 1) / 2 in this file.
      EXPECT_FLOAT_EQ(m.uvs[v].x, (m.positions[v].x + 1) / 2);
      EXPECT_FLOAT_EQ(m.uvs[v].y, (m.positions[v].y + 1) / 2);
      EXPECT_EQ(m.normals[v], Vec3f(0, 0, 1));
    }
  }

  // Only the used materials; the unused one's missing texture did not matter.
  ASSERT_EQ(scene.materials.size(), 2u);
  const Material* leaf = findMaterial(scene, "leaf");
  const Material* card = findMaterial(scene, "card");
  ASSERT_TRUE(leaf && card);
  EXPECT_EQ(scene.meshes[0].material, leaf - scene.materials.data());
  EXPECT_EQ(scene.meshes[1].material, card - scene.materials.data());
  EXPECT_EQ(leaf->baseColor, Vec3f(1, 1, 1));
  EXPECT_EQ(card->baseColor, Vec3f(0.5f, 0.5f, 0.5f));  // "Kd 0.5": grey

  // checker.png loads once for both materials; the two masks separately.
  ASSERT_EQ(scene.textures.size(), 3u);
  ASSERT_NE(leaf->baseColorTexture, kNoTexture);
  EXPECT_EQ(leaf->baseColorTexture, card->baseColorTexture);
  const Texture& checker = scene.textures[size_t(leaf->baseColorTexture)];
  EXPECT_EQ(fs::path(checker.name).filename(), "checker.png");
  ASSERT_EQ(checker.width, 4);
  ASSERT_EQ(checker.height, 4);
  EXPECT_EQ(checker.rgba[0], 255);  // top left red
  EXPECT_EQ(checker.rgba[2], 0);
  EXPECT_EQ(checker.rgba[4 + 0], 0);  // its right neighbour blue
  EXPECT_EQ(checker.rgba[4 + 2], 255);

  // Grey mask without alpha channel: the grey value becomes alpha.
  ASSERT_NE(leaf->alphaTexture, kNoTexture);
  const Texture& grey = scene.textures[size_t(leaf->alphaTexture)];
  EXPECT_EQ(fs::path(grey.name).filename(), "mask_grey.png");
  ASSERT_EQ(grey.width, 4);
  EXPECT_EQ(grey.rgba[3], 255);                     // top row opaque
  EXPECT_EQ(grey.rgba[(3 * 4 + 0) * 4 + 3], 0);     // bottom row a hole
  EXPECT_EQ(grey.sampleAlpha({0.5f, 0.7f}), 1.0f);  // between the two top rows
  EXPECT_EQ(grey.sampleAlpha({0.5f, 0.3f}), 0.0f);  // between the two bottom rows

  // RGBA mask: its own alpha.
  ASSERT_NE(card->alphaTexture, kNoTexture);
  const Texture& rgba = scene.textures[size_t(card->alphaTexture)];
  EXPECT_EQ(fs::path(rgba.name).filename(), "mask_rgba.png");
  ASSERT_EQ(rgba.rgba.size(), 16u);
  EXPECT_EQ(rgba.rgba[3], 255);
  EXPECT_EQ(rgba.rgba[7], 0);
  EXPECT_EQ(rgba.rgba[11], 128);
  EXPECT_EQ(rgba.rgba[15], 64);
}

TEST(ObjLoader, CubeWithNormalsAndUvs) {
  Scene scene = loadObj(corpus("cube.obj"));
  EXPECT_NO_THROW(scene.validate());
  ASSERT_EQ(scene.meshes.size(), 1u);
  const Mesh& cube = scene.meshes[0];
  EXPECT_EQ(cube.name, "cube/red");
  EXPECT_EQ(cube.vertexCount(), 24u);  // 6 faces x 4 distinct corners
  EXPECT_EQ(cube.triangleCount(), 12u);
  ASSERT_EQ(cube.normals.size(), 24u);
  ASSERT_EQ(cube.uvs.size(), 24u);
  float area = 0;
  for (const Vec3i& t : cube.indices) {
    area += triangleArea(cube, t);
    // Counter-clockwise from outside: the geometric normal is the vertex normal.
    Vec3f n = normalize(cross(cube.positions[t.y] - cube.positions[t.x],
                              cube.positions[t.z] - cube.positions[t.x]));
    for (int k = 0; k < 3; ++k) EXPECT_GT(dot(n, cube.normals[t[k]]), 0.999f);
  }
  EXPECT_NEAR(area, 24.0f, 1e-4f);

  ASSERT_EQ(scene.materials.size(), 1u);
  const Material& red = scene.materials[0];
  EXPECT_EQ(red.name, "red");
  EXPECT_EQ(red.baseColor, Vec3f(0.8f, 0.1f, 0.1f));
  // Neither metallic nor transmitting: Lambertian (its Ns has no use).
  const auto* diffuse = modelAs<DiffuseModel>(red);
  ASSERT_NE(diffuse, nullptr);
  EXPECT_EQ(diffuse->sigmaDegrees, 0.0f);
  EXPECT_FALSE(red.isEmissive());

  // No emitter: a sun and a grey environment, and a view that frames the cube.
  ASSERT_EQ(scene.suns.size(), 1u);
  EXPECT_NEAR(length(scene.suns[0].direction), 1.0f, 1e-6f);
  EXPECT_GT(scene.suns[0].direction.y, 0.0f);
  EXPECT_EQ(scene.environment.color, Vec3f(0.5f));
  ASSERT_EQ(scene.views.size(), 1u);
  const CameraView& view = scene.view("default");
  EXPECT_EQ(view.fovY, 45.0f);
  EXPECT_EQ(view.at, Vec3f(0, 0, 0));
  EXPECT_EQ(view.from.x, 0.0f);
  EXPECT_EQ(view.from.y, 0.0f);
  EXPECT_GT(view.from.z, 1.0f);
  Vec3f forward = normalize(view.at - view.from);
  for (const Vec3f& p : cube.positions) {
    float angle = std::acos(dot(normalize(p - view.from), forward)) * 180 / kPi;
    EXPECT_LT(angle, 22.5f);
  }
}

TEST(ObjLoader, EmissiveQuadKeepsAuthoredLighting) {
  Scene scene = loadObj(corpus("emissive_quad.obj"));
  EXPECT_NO_THROW(scene.validate());
  ASSERT_EQ(scene.meshes.size(), 2u);
  const Material* lamp = findMaterial(scene, "lamp");
  const Material* white = findMaterial(scene, "white");
  ASSERT_TRUE(lamp && white);
  EXPECT_EQ(lamp->emission, Vec3f(10, 9, 8));
  EXPECT_EQ(white->emission, Vec3f(0, 0, 0));  // "Ka 1 1 1" on the lamp is not emission either
  EXPECT_TRUE(scene.suns.empty());
  EXPECT_TRUE(scene.environment.isBlack());
  EXPECT_EQ(findMesh(scene, "lamp/lamp")->material, lamp - scene.materials.data());
}

TEST(ObjLoader, FeaturesMaterialsAndPolygons) {
  Scene scene = loadObj(corpus("features.obj"));
  EXPECT_NO_THROW(scene.validate());
  std::vector<std::string> names;
  for (const Mesh& m : scene.meshes) names.push_back(m.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"features", "pentagon/glass", "pentagon/metal", "other/glass",
                                      "other/pbr", "other/clamped", "other/dissolve"}));
  std::vector<uint64_t> triangles;
  for (const Mesh& m : scene.meshes) triangles.push_back(m.triangleCount());
  EXPECT_EQ(triangles, (std::vector<uint64_t>{1, 3, 1, 1, 1, 1, 1}));
  EXPECT_EQ(totalTriangles(scene), 9u);

  // The pentagon is fanned into triangles that cover it exactly.
  const Mesh* pentagon = findMesh(scene, "pentagon/glass");
  ASSERT_TRUE(pentagon);
  float area = 0;
  for (const Vec3i& t : pentagon->indices) area += triangleArea(*pentagon, t);
  EXPECT_NEAR(area, 1.25f, 1e-6f);
  EXPECT_EQ(pentagon->vertexCount(), 5u);
  EXPECT_TRUE(pentagon->normals.empty());
  EXPECT_TRUE(pentagon->uvs.empty());

  // Relative indices and '+1.0e0 -0.5 .5'.
  const Mesh* pbrMesh = findMesh(scene, "other/pbr");
  ASSERT_TRUE(pbrMesh);
  ASSERT_EQ(pbrMesh->vertexCount(), 3u);
  EXPECT_EQ(pbrMesh->positions[2], Vec3f(1.0f, -0.5f, 0.5f));
  const Mesh* metalMesh = findMesh(scene, "pentagon/metal");
  ASSERT_TRUE(metalMesh);
  EXPECT_EQ(metalMesh->positions, (std::vector<Vec3f>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));

  std::vector<std::string> materials;
  for (const Material& m : scene.materials) materials.push_back(m.name);
  EXPECT_EQ(materials,
            (std::vector<std::string>{"default", "glass", "metal", "pbr", "clamped", "dissolve"}));
  EXPECT_EQ(scene.meshes[0].material, 0);

  const Material* glass = findMaterial(scene, "glass");
  ASSERT_TRUE(glass);
  const auto* glassModel = modelAs<DielectricModel>(*glass);
  ASSERT_NE(glassModel, nullptr);
  EXPECT_EQ(glassModel->ior, 1.5f);
  EXPECT_NEAR(glassModel->roughness, std::sqrt(2.0f / 1002.0f), 1e-6f);
  EXPECT_EQ(findMesh(scene, "other/glass")->material, glass - scene.materials.data());

  const Material* metal = findMaterial(scene, "metal");
  ASSERT_TRUE(metal);
  const auto* metalModel = modelAs<ConductorModel>(*metal);
  ASSERT_NE(metalModel, nullptr);
  EXPECT_EQ(metal->baseColor, Vec3f(0.9f, 0.8f, 0.7f));  // Ks, as illum 3 says
  EXPECT_NEAR(metalModel->roughness, std::sqrt(2.0f / 202.0f), 1e-6f);

  const Material* pbr = findMaterial(scene, "pbr");
  ASSERT_TRUE(pbr);
  const auto* pbrModel = modelAs<ConductorModel>(*pbr);
  ASSERT_NE(pbrModel, nullptr);
  EXPECT_NEAR(pbrModel->roughness, 0.3f, 1e-6f);  // Pr wins over Ns
  EXPECT_EQ(pbr->baseColor, Vec3f(0.2f, 0.4f, 0.6f));

  const Material* clamped = findMaterial(scene, "clamped");
  EXPECT_EQ(clamped->baseColor, Vec3f(1, 1, 1));  // map_Kd without Kd
  ASSERT_NE(clamped->baseColorTexture, kNoTexture);
  EXPECT_EQ(scene.textures[size_t(clamped->baseColorTexture)].wrap, WrapMode::Clamp);

  const Material* dissolve = findMaterial(scene, "dissolve");
  ASSERT_TRUE(dissolve);
  // Transmission 1 - d = 0.75 (Tf ignored for illum 2): glass.
  const auto* dissolveModel = modelAs<DielectricModel>(*dissolve);
  ASSERT_NE(dissolveModel, nullptr);
  EXPECT_EQ(dissolveModel->ior, 1.5f);        // "Ni 0" means unset
  EXPECT_EQ(dissolveModel->roughness, 1.0f);  // no Ns, no Pr
}

TEST(ObjLoader, EmbreeCornellBox) {
  const std::string path = "/usr/share/doc/embree3/models/cornell_box.obj";
  if (!fs::exists(path)) GTEST_SKIP() << path << " is not installed";
  Scene scene = loadObj(path);
  EXPECT_NO_THROW(scene.validate());
  EXPECT_EQ(scene.name, "cornell_box");
  // 17 quads in 7 objects with faces (the light and front wall have none).
  EXPECT_EQ(scene.meshes.size(), 7u);
  EXPECT_EQ(totalTriangles(scene), 34u);
  std::set<std::string> materials;
  for (const Material& m : scene.materials) materials.insert(m.name);
  EXPECT_EQ(materials, (std::set<std::string>{"white", "red", "green"}));
  // Its light is "Ka 20 20 20", and Ka is not emission: default lights are added.
  EXPECT_EQ(scene.suns.size(), 1u);
  Box3f bounds = scene.worldBounds();
  EXPECT_NEAR(bounds.upper.x, 556.0f, 1e-3f);
  EXPECT_NEAR(bounds.upper.y, 548.8f, 1e-3f);
  EXPECT_NEAR(bounds.upper.z, 559.2f, 1e-3f);
}

// --------------------------------------------------------------- robustness

class TempDir {
 public:
  TempDir() {
    path_ =
        fs::temp_directory_path() / ("ferry_obj_test_" + std::to_string(::getpid()) + "_" +
                                     testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Mutated copies of the good files either load (into a valid scene) or fail
// with an InputError: never another exception, a crash or a hang. An
// InternalError here means the validation pass and tinyobjloader disagree.
TEST(ObjLoader, MutatedFilesFailCleanly) {
  TempDir dir;
  for (const char* name : {"checker.png", "mask_grey.png", "mask_rgba.png", "features.mtl",
                           "cube.mtl", "textured_quad.mtl"})
    fs::copy_file(kCorpus / name, dir.path() / name);
  const std::string alphabet = "0123456789 /-+.#\n\tvnftgo e\\";
  std::mt19937 rng(12345);
  int loaded = 0, rejected = 0;
  for (const char* name : {"features.obj", "cube.obj", "textured_quad.obj"}) {
    const std::string original = readFile(kCorpus / name);
    for (int trial = 0; trial < 150; ++trial) {
      std::string text = original;
      int edits = 1 + int(rng() % 4);
      for (int e = 0; e < edits; ++e) {
        size_t at = rng() % text.size();
        switch (rng() % 3) {
          case 0:
            text[at] = alphabet[rng() % alphabet.size()];
            break;
          case 1:
            text.erase(at, 1 + rng() % 8);
            break;
          default:
            text = text.substr(0, at) + alphabet[rng() % alphabet.size()] + text.substr(at);
            break;
        }
        if (text.empty()) text.push_back('#');
      }
      const fs::path path = dir.path() / name;
      std::ofstream(path, std::ios::binary) << text;
      try {
        Scene scene = loadObj(path.string());
        EXPECT_NO_THROW(scene.validate()) << text;
        ++loaded;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        ++rejected;
      } catch (const std::exception& e) {
        ADD_FAILURE() << "unexpected " << e.what() << " for:\n" << text;
      }
    }
  }
  // Both outcomes happen, or the mutations test nothing.
  EXPECT_GT(loaded, 10);
  EXPECT_GT(rejected, 10);
}

}  // namespace
}  // namespace ferry
