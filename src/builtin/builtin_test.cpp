// Spec parsing, and the properties every built-in must have: describing it
// gives exactly the summary of generating it, it is deterministic from its
// seed, it validates, and its instances lie within its bounds.
#include "builtin/builtin.h"

#include <map>
#include <memory>

#include <gtest/gtest.h>

#include "core/error.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

// Generating the bigger scenes takes a moment; each is made once per test run.
const Scene& cachedScene(const std::string& spec) {
  static std::map<std::string, std::unique_ptr<Scene>> cache;
  auto& slot = cache[spec];
  if (!slot) slot = std::make_unique<Scene>(generateBuiltin(parseBuiltinSpec(spec)));
  return *slot;
}

std::string expectThrowMessage(const std::string& spec) {
  try {
    parseBuiltinSpec(spec);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError for '" << spec << "'";
  return {};
}

TEST(BuiltinSpec, RecognizesThePrefix) {
  EXPECT_TRUE(isBuiltinSpec("builtin:island"));
  EXPECT_TRUE(isBuiltinSpec("builtin:nope"));
  EXPECT_FALSE(isBuiltinSpec("island"));
  EXPECT_FALSE(isBuiltinSpec("scenes/builtin:island.obj"));
  EXPECT_FALSE(isBuiltinSpec(""));
}

TEST(BuiltinSpec, ParsesNameScaleAndSeed) {
  BuiltinParams p = parseBuiltinSpec("builtin:island?scale=4&seed=7");
  EXPECT_EQ(p.name, "island");
  EXPECT_DOUBLE_EQ(p.scale, 4.0);
  EXPECT_EQ(p.seed, 7u);

  p = parseBuiltinSpec("builtin:cornell");
  EXPECT_EQ(p.name, "cornell");
  EXPECT_DOUBLE_EQ(p.scale, 1.0);
  EXPECT_EQ(p.seed, 1u);

  p = parseBuiltinSpec("builtin:landscape?seed=4294967295&scale=0.25");
  EXPECT_EQ(p.seed, 4294967295u);
  EXPECT_DOUBLE_EQ(p.scale, 0.25);

  p = parseBuiltinSpec("builtin:furnace?scale=1e3");
  EXPECT_DOUBLE_EQ(p.scale, 1000.0);

  p = parseBuiltinSpec("builtin:furnace?");
  EXPECT_EQ(p.name, "furnace");

  p = parseBuiltinSpec("builtin:fur?strands=1000000");
  EXPECT_EQ(p.strands, 1000000u);
  expectThrowMessage("builtin:fur?strands=0");
  expectThrowMessage("builtin:fur?strands=x");
  EXPECT_THROW(describeBuiltin(parseBuiltinSpec("builtin:cornell?strands=5")), InputError);
  EXPECT_EQ(parseBuiltinSpec("builtin:particles?count=10000000").count, 10000000u);
  EXPECT_THROW(describeBuiltin(parseBuiltinSpec("builtin:fur?count=5")), InputError);
}

TEST(BuiltinSpec, FurHasItsStrandsAsCurveSegments) {
  const SceneSummary s = describeBuiltin(parseBuiltinSpec("builtin:fur?strands=1000000"));
  EXPECT_EQ(s.geometries, 1u);
  EXPECT_EQ(s.shapePrimitives, 4000000u);  // 4 segments a strand
  // The segment (64 bytes), Embree's control points (64) and index (4).
  EXPECT_EQ(s.memory.shapes, 4000000u * 132u);
}

TEST(BuiltinSpec, UnknownNameListsTheBuiltins) {
  std::string msg = expectThrowMessage("builtin:volcano");
  EXPECT_NE(msg.find("volcano"), std::string::npos) << msg;
  for (const std::string& name : builtinNames())
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
  expectThrowMessage("builtin:");
  expectThrowMessage("builtin:Island");
  expectThrowMessage("island");
}

TEST(BuiltinSpec, UnknownKeyListsTheAcceptedKeys) {
  std::string msg = expectThrowMessage("builtin:island?depth=3");
  EXPECT_NE(msg.find("depth"), std::string::npos) << msg;
  EXPECT_NE(msg.find("scale"), std::string::npos) << msg;
  EXPECT_NE(msg.find("seed"), std::string::npos) << msg;
  expectThrowMessage("builtin:island?scale");  // no value
}

TEST(BuiltinSpec, RejectsBadScales) {
  for (const char* bad : {"0", "-1", "abc", "", "1x", "inf", "nan", "-0", "1e999"}) {
    std::string msg = expectThrowMessage(std::string("builtin:island?scale=") + bad);
    EXPECT_NE(msg.find("scale"), std::string::npos) << msg;
  }
}

TEST(BuiltinSpec, RejectsBadSeeds) {
  for (const char* bad : {"-1", "1.5", "abc", "", "4294967296", "7 ", "0x10"}) {
    std::string msg = expectThrowMessage(std::string("builtin:island?seed=") + bad);
    EXPECT_NE(msg.find("seed"), std::string::npos) << msg;
  }
  expectThrowMessage("builtin:island?seed=1&seed=2");
}

TEST(BuiltinSpec, NamesAreTheEightBuiltins) {
  EXPECT_EQ(builtinNames(), (std::vector<std::string>{"island", "landscape", "cornell", "furnace",
                                                      "volume", "fur", "particles", "tets"}));
}

TEST(BuiltinSpec, GenerateRejectsBadParams) {
  BuiltinParams p;
  p.name = "furnace";
  p.scale = 0;
  EXPECT_THROW(generateBuiltin(p), InputError);
  EXPECT_THROW(describeBuiltin(p), InputError);
  p.scale = 1;
  p.name = "teapot";
  EXPECT_THROW(generateBuiltin(p), InputError);
}

void expectSameSummary(const SceneSummary& described, const SceneSummary& made) {
  EXPECT_EQ(described.name, made.name);
  EXPECT_EQ(described.uniqueMeshes, made.uniqueMeshes);
  EXPECT_EQ(described.triangles, made.triangles);
  EXPECT_EQ(described.vertices, made.vertices);
  EXPECT_EQ(described.objects, made.objects);
  EXPECT_EQ(described.instances, made.instances);
  EXPECT_EQ(described.instancedTriangles, made.instancedTriangles);
  EXPECT_EQ(described.textures, made.textures);
  EXPECT_EQ(described.texels, made.texels);
  EXPECT_EQ(described.suns, made.suns);
  EXPECT_EQ(described.environments, made.environments);
  EXPECT_EQ(described.emissiveMeshes, made.emissiveMeshes);
  EXPECT_EQ(described.emissiveTriangles, made.emissiveTriangles);
  EXPECT_EQ(described.views, made.views);
  EXPECT_EQ(described.geometries, made.geometries);
  EXPECT_EQ(described.shapePrimitives, made.shapePrimitives);
  EXPECT_EQ(described.shapeKinds, made.shapeKinds);
  EXPECT_EQ(described.memory.vertices, made.memory.vertices);
  EXPECT_EQ(described.memory.normals, made.memory.normals);
  EXPECT_EQ(described.memory.uvs, made.memory.uvs);
  EXPECT_EQ(described.memory.indices, made.memory.indices);
  EXPECT_EQ(described.memory.texels, made.memory.texels);
  EXPECT_EQ(described.memory.instances, made.memory.instances);
  EXPECT_EQ(described.memory.accel, made.memory.accel);
  EXPECT_EQ(described.memory.media, made.memory.media);
  EXPECT_EQ(described.memory.total(), made.memory.total());
  ASSERT_FALSE(described.bounds.empty());
  ASSERT_FALSE(made.bounds.empty());
  float tolerance = 1e-4f * maxComponent(made.bounds.size());
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(described.bounds.lower[a], made.bounds.lower[a], tolerance) << "axis " << a;
    EXPECT_NEAR(described.bounds.upper[a], made.bounds.upper[a], tolerance) << "axis " << a;
  }
}

class EveryBuiltin : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryBuiltin, DescribeEqualsSummaryOfGenerate) {
  const std::string spec = GetParam();
  SCOPED_TRACE(spec);
  expectSameSummary(describeBuiltin(parseBuiltinSpec(spec)), summarize(cachedScene(spec)));
}

TEST_P(EveryBuiltin, Validates) {
  const Scene& scene = cachedScene(GetParam());
  EXPECT_NO_THROW(scene.validate());
  EXPECT_FALSE(scene.views.empty());
  EXPECT_FALSE(scene.name.empty());
  for (const Texture& t : scene.textures) {
    EXPECT_TRUE(t.srgb) << t.name;
    EXPECT_EQ(t.rgba.size(), t.texelCount() * 4) << t.name;
  }
  // Cut-outs use one RGBA texture for colour and alpha.
  for (const Material& m : scene.materials)
    if (m.alphaTexture != kNoTexture) {
      EXPECT_EQ(m.alphaTexture, m.baseColorTexture) << m.name;
    }
}

TEST_P(EveryBuiltin, EveryInstanceIsInsideTheBounds) {
  const std::string spec = GetParam();
  const Scene& scene = cachedScene(spec);
  Box3f bounds = describeBuiltin(parseBuiltinSpec(spec)).bounds;
  float slack = 1e-4f * maxComponent(bounds.size());
  bounds.lower = bounds.lower - Vec3f(slack);
  bounds.upper = bounds.upper + Vec3f(slack);
  std::vector<Box3f> objectBounds(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o)
    objectBounds[o] = scene.objectBounds(int32_t(o));
  size_t outside = 0;
  for (const Instance& inst : scene.instances) {
    Box3f b = inst.transform.transformBox(objectBounds[inst.object]);
    if (!bounds.contains(b)) {
      if (++outside <= 5)
        ADD_FAILURE() << scene.objects[inst.object].name << " instance at (" << inst.transform.t.x
                      << ", " << inst.transform.t.y << ", " << inst.transform.t.z << ") reaches ("
                      << b.lower.x << ", " << b.lower.y << ", " << b.lower.z << ") - (" << b.upper.x
                      << ", " << b.upper.y << ", " << b.upper.z << ")";
    }
  }
  EXPECT_EQ(outside, 0u);
}

TEST_P(EveryBuiltin, EveryObjectIsInstancedAndNonEmpty) {
  const Scene& scene = cachedScene(GetParam());
  std::vector<uint32_t> counts = scene.instanceCountPerObject();
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    EXPECT_GE(counts[o], 1u) << scene.objects[o].name;
    uint64_t primitives = 0;
    for (int32_t m : scene.objects[o].meshes) primitives += scene.meshes[m].triangleCount();
    for (int32_t g : scene.objects[o].geometries)
      primitives += scene.geometries[g].shape->primitiveCount();
    EXPECT_GT(primitives, 0u) << scene.objects[o].name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Builtin, EveryBuiltin,
    ::testing::Values("builtin:island", "builtin:island?scale=0.1&seed=3", "builtin:landscape",
                      "builtin:landscape?scale=0.2&seed=5", "builtin:cornell",
                      "builtin:cornell?scale=3", "builtin:furnace", "builtin:furnace?scale=0.3",
                      "builtin:fur?strands=300&seed=2", "builtin:particles?count=500",
                      "builtin:tets?count=3000"),
    [](const ::testing::TestParamInfo<std::string>& info) {
      std::string name = info.param.substr(8);
      for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });

bool sameMesh(const Mesh& a, const Mesh& b) {
  if (a.positions.size() != b.positions.size() || a.indices.size() != b.indices.size())
    return false;
  for (size_t i = 0; i < a.positions.size(); ++i)
    if (!(a.positions[i] == b.positions[i])) return false;
  for (size_t i = 0; i < a.indices.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (a.indices[i][k] != b.indices[i][k]) return false;
  return a.material == b.material && a.name == b.name;
}

bool sameTransform(const Affine3f& a, const Affine3f& b) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a.l[i][j] != b.l[i][j]) return false;
  return a.t == b.t;
}

class SeededBuiltin : public ::testing::TestWithParam<std::string> {};

TEST_P(SeededBuiltin, SameSeedGivesTheSameScene) {
  const std::string spec = "builtin:" + GetParam() + "?scale=0.1&seed=7";
  Scene a = generateBuiltin(parseBuiltinSpec(spec));
  Scene b = generateBuiltin(parseBuiltinSpec(spec));
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t m = 0; m < a.meshes.size(); ++m)
    EXPECT_TRUE(sameMesh(a.meshes[m], b.meshes[m])) << a.meshes[m].name;
  ASSERT_EQ(a.instances.size(), b.instances.size());
  for (size_t i = 0; i < a.instances.size(); ++i) {
    EXPECT_EQ(a.instances[i].object, b.instances[i].object);
    EXPECT_TRUE(sameTransform(a.instances[i].transform, b.instances[i].transform))
        << "instance " << i;
  }
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (size_t t = 0; t < a.textures.size(); ++t) EXPECT_EQ(a.textures[t].rgba, b.textures[t].rgba);
}

TEST_P(SeededBuiltin, DifferentSeedsGiveDifferentPlacements) {
  Scene a = generateBuiltin(parseBuiltinSpec("builtin:" + GetParam() + "?scale=0.1&seed=7"));
  Scene b = generateBuiltin(parseBuiltinSpec("builtin:" + GetParam() + "?scale=0.1&seed=8"));
  // Same recipe, so the same numbers of things ...
  ASSERT_EQ(a.instances.size(), b.instances.size());
  ASSERT_EQ(a.objects.size(), b.objects.size());
  // ... but the multi-instance content stands elsewhere.
  std::vector<uint32_t> counts = a.instanceCountPerObject();
  size_t compared = 0, moved = 0;
  for (size_t i = 0; i < a.instances.size(); ++i) {
    if (counts[a.instances[i].object] < 2) continue;
    ++compared;
    if (length(a.instances[i].transform.t - b.instances[i].transform.t) > 1e-3f) ++moved;
  }
  ASSERT_GT(compared, 100u);
  EXPECT_GT(double(moved), 0.95 * double(compared));
}

INSTANTIATE_TEST_SUITE_P(Builtin, SeededBuiltin, ::testing::Values("island", "landscape"));

TEST(BuiltinViews, ViewsExistByName) {
  const Scene& island = cachedScene("builtin:island?scale=0.1&seed=3");
  for (const char* name : {"default", "beach", "overview"}) EXPECT_EQ(island.view(name).name, name);
  EXPECT_EQ(island.views.front().name, "default");
  const Scene& landscape = cachedScene("builtin:landscape?scale=0.2&seed=5");
  for (const char* name : {"path", "view-3", "top"}) EXPECT_EQ(landscape.view(name).name, name);
  EXPECT_EQ(cachedScene("builtin:cornell").view("default").name, "default");
  EXPECT_EQ(cachedScene("builtin:furnace").view("default").name, "default");
  EXPECT_THROW(island.view("nope"), InputError);
}

TEST(BuiltinViews, CamerasLookAtSomethingAndAreNotBuried) {
  for (const char* spec :
       {"builtin:island?scale=0.1&seed=3", "builtin:landscape?scale=0.2&seed=5"}) {
    const Scene& scene = cachedScene(spec);
    Box3f bounds = scene.worldBounds();
    for (const CameraView& v : scene.views) {
      EXPECT_GT(length(v.at - v.from), 1.0f) << spec << " " << v.name;
      EXPECT_LT(length(cross(normalize(v.at - v.from), normalize(v.up))), 1.0f + 1e-6f);
      EXPECT_GT(v.fovY, 10.0f);
      EXPECT_LT(v.fovY, 120.0f);
      // Eyes are within the scene's horizontal extent and above its lowest point.
      EXPECT_GT(v.from.y, bounds.lower.y) << spec << " " << v.name;
      EXPECT_GE(v.from.x, bounds.lower.x);
      EXPECT_LE(v.from.x, bounds.upper.x);
    }
  }
}

}  // namespace
}  // namespace ferry

namespace ferry {
namespace {

TEST(BuiltinVolume, IsAGridMediumOfTheSizeAskedInItsBox) {
  const BuiltinParams params = parseBuiltinSpec("builtin:volume?size=12&seed=3");
  ASSERT_EQ(params.size, 12);
  const SceneSummary described = describeBuiltin(params);
  ASSERT_EQ(described.media.size(), 1u);
  EXPECT_EQ(described.media[0].kind, "grid 12x12x12");
  const Scene scene = generateBuiltin(params);
  scene.validate();
  ASSERT_EQ(scene.media.size(), 1u);
  const Medium& cloud = scene.media[0];
  ASSERT_FALSE(cloud.homogeneous());
  EXPECT_EQ(cloud.density->nx(), 12);
  EXPECT_GE(cloud.density->minValue(), described.media[0].minDensity);
  EXPECT_LE(cloud.density->maxValue(), described.media[0].maxDensity);
  EXPECT_GT(cloud.density->maxValue(), 0.5f);  // a cloud, not a haze
  ASSERT_EQ(scene.mediumBoundaries.size(), 1u);
  EXPECT_EQ(scene.mediumBoundaries[0].media, (MediumInterface{0, kNoMedium}));
  // Its box's normals point out of it (inside is the cloud).
  const Mesh& box = scene.mediumBoundaries[0].mesh;
  for (const Vec3i& t : box.indices) {
    const Vec3f a = box.positions[size_t(t.x)];
    const Vec3f n = cross(box.positions[size_t(t.y)] - a, box.positions[size_t(t.z)] - a);
    EXPECT_GT(dot(n, (a + box.positions[size_t(t.y)] + box.positions[size_t(t.z)]) * (1.0f / 3)),
              0);
  }
  // The same seed, the same densities.
  EXPECT_EQ(generateBuiltin(params).media[0].density->values(), cloud.density->values());
  // The memory model counts the volume, on every rank (a rank that owns no
  // instance still holds it), and the plan says so before it is made.
  const SceneSummary made = summarize(scene);
  EXPECT_GE(made.memory.media, uint64_t(12 * 12 * 12) * sizeof(float) + sizeof(Medium));
  EXPECT_EQ(made.memory.media, cloud.bytes() + meshCost(box).total());
  EXPECT_EQ(ownedMemory(scene, {}).media, made.memory.media);
  EXPECT_EQ(described.memory.media, made.memory.media);
}

TEST(BuiltinVolume, SizeBelongsToTheVolumeAlone) {
  EXPECT_THROW(describeBuiltin(parseBuiltinSpec("builtin:cornell?size=4")), InputError);
  EXPECT_THROW(parseBuiltinSpec("builtin:volume?size=1"), InputError);
  EXPECT_THROW(parseBuiltinSpec("builtin:volume?size=huge"), InputError);
}

}  // namespace
}  // namespace ferry
