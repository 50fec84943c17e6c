#include "io/parts/part_file.h"
#include "material/models/coated_diffuse.h"
#include "material/models/fourier.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include "builtin/builtin.h"
#include "core/error.h"
#include "io/parts/part_directory.h"
#include "io/pbrt/fourier_bsdf_file.h"
#include "partition/partitioner.h"
#include "render/lights.h"
#include "scene/light_scene.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  TempDir() {
    path =
        fs::temp_directory_path() / fmt::format("ferry-part-test-{}-{}", ::getpid(), counter()++);
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  static int& counter() {
    static int n = 0;
    return n;
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

template <typename Array>  // std::vector or SharedArray
bool sameBytes(const Array& a, const Array& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

bool sameMaterial(const Scene& sa, const Material& a, const Scene& sb, const Material& b) {
  auto sameTexture = [&](int32_t ta, int32_t tb) {
    if ((ta == kNoTexture) != (tb == kNoTexture)) return false;
    if (ta == kNoTexture) return true;
    const Texture &x = sa.textures[ta], &y = sb.textures[tb];
    return x.name == y.name && x.width == y.width && x.height == y.height && x.wrap == y.wrap &&
           x.srgb == y.srgb && sameBytes(x.rgba, y.rgba) && x.solid.kind == y.solid.kind &&
           std::memcmp(&x.solid.worldToTexture, &y.solid.worldToTexture, sizeof(Affine3f)) == 0 &&
           x.solid.octaves == y.solid.octaves && x.solid.omega == y.solid.omega &&
           x.solid.scale == y.solid.scale && x.solid.variation == y.solid.variation &&
           x.combination == y.combination && x.parts.size() == y.parts.size() &&
           [&] {  // the same values everywhere: operands and parts alike
             for (int i = 0; i < 64; ++i) {
               const Vec2f uv{float(i % 8) / 8 + 0.03f, float(i / 8) / 8 + 0.07f};
               const Vec3f p{0.31f * float(i), 0.17f * float(i % 5), 0.05f};
               if (!(x.value(uv, p) == y.value(uv, p))) return false;
             }
             return true;
           }();
  };
  // The same model with the same parameters: the same record.
  auto record = [](const Material& m) {
    MaterialRecordWriter w;
    m.model->write(w);
    return w.bytes();
  };
  return a.name == b.name && a.baseColor == b.baseColor && a.model->name() == b.model->name() &&
         record(a) == record(b) && a.emission == b.emission && a.alphaCutoff == b.alphaCutoff &&
         a.emitsBackSide == b.emitsBackSide &&
         a.lightSampledOnBackSide == b.lightSampledOnBackSide && a.alphaTest == b.alphaTest &&
         a.alphaRays == b.alphaRays && a.bumpScale == b.bumpScale &&
         a.normalScale == b.normalScale && a.mixAmount == b.mixAmount &&
         (a.mixedWith < 0) == (b.mixedWith < 0) &&
         sameTexture(a.baseColorTexture, b.baseColorTexture) &&
         sameTexture(a.alphaTexture, b.alphaTexture) && sameTexture(a.bumpTexture, b.bumpTexture);
}

// The loaded part holds exactly the listed instances of `scene`, bit for bit.
void expectSameContent(const Scene& scene, const std::vector<int32_t>& owned, const Scene& part) {
  ASSERT_EQ(part.instances.size(), owned.size());
  for (size_t k = 0; k < owned.size(); ++k) {
    const Instance& a = scene.instances[owned[k]];
    const Instance& b = part.instances[k];
    ASSERT_EQ(std::memcmp(&a.transform, &b.transform, sizeof(Affine3f)), 0);
    const Object& oa = scene.objects[a.object];
    const Object& ob = part.objects[b.object];
    ASSERT_EQ(oa.name, ob.name);
    ASSERT_EQ(oa.meshes.size(), ob.meshes.size());
    for (size_t slot = 0; slot < oa.meshes.size(); ++slot) {
      const Mesh& ma = scene.meshes[oa.meshes[slot]];
      const Mesh& mb = part.meshes[ob.meshes[slot]];
      ASSERT_EQ(ma.name, mb.name);
      ASSERT_TRUE(sameBytes(ma.positions, mb.positions));
      ASSERT_TRUE(sameBytes(ma.normals, mb.normals));
      ASSERT_TRUE(sameBytes(ma.uvs, mb.uvs));
      ASSERT_TRUE(sameBytes(ma.indices, mb.indices));
      ASSERT_TRUE(
          sameMaterial(scene, scene.materials[ma.material], part, part.materials[mb.material]));
    }
  }
}

const Scene& island() {
  static Scene s = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.05"));
  return s;
}

struct Written {
  Scene scene;  // as partitioned
  Partition partition;
  Manifest manifest;
};

Written writeDirectory(const std::string& dir, const std::string& partitioner, int ranks) {
  Written w;
  w.scene = island();
  // One material as a pbrt area light has it (one-sided), so the round trips cover the flag.
  w.scene.materials.back().emitsBackSide = false;
  w.scene.materials.back().lightSampledOnBackSide = true;  // pbrt-v3 under a mirror
  // The leaves' cut-outs as pbrt-v4 (stochastic) and pbrt-v3 (paths only) have them.
  bool v4 = true;
  for (Material& m : w.scene.materials)
    if (m.alphaTexture != kNoTexture) {
      m.alphaTest = v4 ? AlphaTest::Stochastic : AlphaTest::Zero;
      m.alphaRays = v4 ? AlphaRays::All : AlphaRays::NotShadowRays;
      v4 = !v4;
    }
  // And one coated, Oren-Nayar material, for a model's record.
  Material& coated = w.scene.materials.front();
  auto coat = std::make_shared<CoatedDiffuseModel>();
  coat->specular = {0.1f, 0.2f, 0.3f};
  coat->roughness = 0.4f;
  coat->eta = 1 / 1.5f;
  coat->layered = true;
  coat->sigmaDegrees = 12;
  coated.model = coat;
  // Its colour a solid texture (format 5).
  Texture marble;
  marble.name = "marble";
  marble.solid.kind = SolidTextureKind::Marble;
  marble.solid.worldToTexture = Affine3f::translate({1, 2, 3});
  marble.solid.octaves = 6;
  marble.solid.omega = 0.4f;
  marble.solid.scale = 3;
  marble.solid.variation = 0.25f;
  coated.baseColorTexture = int32_t(w.scene.textures.size());
  w.scene.textures.push_back(marble);
  // Its bump map a combination (format 11): a checkerboard of the marble and an image.
  Texture image;
  image.name = "image";
  image.width = 2;
  image.height = 1;
  image.rgba = {10, 20, 30, 255, 200, 100, 50, 255};
  Texture checker;
  checker.name = "checker";
  checker.combination = TextureCombination::Checkerboard;
  checker.mapping = {4, 3, 0.5f, 0.25f};
  checker.parts = {marble, image};
  checker.operands[0].part = 1;
  checker.operands[1].part = 0;
  checker.operands[2].constant = {0.1f, 0.2f, 0.3f};
  coated.bumpTexture = int32_t(w.scene.textures.size());
  coated.bumpScale = 0.5f;
  w.scene.textures.push_back(checker);
  // Mixed with another material, which the part keeps with it.
  coated.mixedWith = int32_t(w.scene.materials.size()) - 1;
  coated.mixAmount = 0.3f;
  Scene lights = lightScene(w.scene);
  PartitionerOptions o;
  o.partitioner = &partitionerNamed(partitioner);
  w.partition = partitionScene(w.scene, ranks, o);
  PartDirectoryInfo info;
  info.scene = "builtin:island?scale=0.05";
  info.partitioner = partitioner;
  info.summary = summarize(island()).toJson();
  w.manifest = writePartDirectory(dir, w.scene, w.partition, lights, info);
  return w;
}

void flipByte(const std::string& path, uint64_t at) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekg(std::streamoff(at));
  char c;
  f.get(c);
  f.seekp(std::streamoff(at));
  f.put(char(c ^ 0x5a));
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

void expectSameProxies(const std::vector<Proxy>& got, const std::vector<Proxy>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) {
    ASSERT_EQ(std::memcmp(&got[k].bounds, &want[k].bounds, sizeof(Box3f)), 0) << "proxy " << k;
    ASSERT_EQ(got[k].owners, want[k].owners) << "proxy " << k;
    ASSERT_EQ(got[k].shape, want[k].shape) << "proxy " << k;
    ASSERT_EQ(got[k].placement >= 0, want[k].placement >= 0) << "proxy " << k;
  }
}

}  // namespace

// Format 2 stores owner sets of any width: a partition over more than 64
// ranks (replicated random owners, so sets span several words) round-trips.
TEST(PartFiles, MoreThan64RanksRoundTrip) {
  for (const char* partitioner : {"round-robin", "random"}) {
    SCOPED_TRACE(partitioner);
    TempDir dir;
    Written w;
    w.scene = island();
    PartitionerOptions o;
    o.partitioner = &partitionerNamed(partitioner);
    w.partition = partitionScene(w.scene, 70, o);
    bool wide = false;
    for (const RankSet& s : w.partition.instanceOwners) wide = wide || !s.fitsInMask();
    ASSERT_TRUE(wide);
    PartDirectoryInfo info;
    writePartDirectory(dir.path.string(), w.scene, w.partition, lightScene(w.scene), info);
    for (int r : {0, 63, 64, 69}) {
      SCOPED_TRACE(r);
      RankPart part = loadRankPart(dir.path.string(), r, 70);
      const std::vector<int32_t> owned = w.partition.instancesOf(r);
      ASSERT_EQ(part.partition.instanceOwners.size(), owned.size());
      for (size_t k = 0; k < owned.size(); ++k)
        EXPECT_EQ(part.partition.instanceOwners[k], w.partition.instanceOwners[owned[k]]);
      expectSameProxies(part.partition.proxies, w.partition.proxies);
    }
  }
}

// A part directory written by format 1 (Ferry at 5ffc21c: `ferry partition
// builtin:cornell --ranks 3 --partitioner best`) still loads, with the owners
// and proxies the same partitioner makes today.
TEST(PartFiles, Format1DirectoriesStillLoad) {
  const std::string dir = std::string(FERRY_SOURCE_DIR) + "/tests/corpus/parts-v1";
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  PartitionerOptions o;
  o.partitioner = &bestPartitioner();
  Partition fresh = partitionScene(scene, 3, o);
  for (int r = 0; r < 3; ++r) {
    SCOPED_TRACE(r);
    RankPart part = loadRankPart(dir, r, 3);
    EXPECT_EQ(part.manifest.version, 1u);
    const std::vector<int32_t> owned = fresh.instancesOf(r);
    expectSameContent(scene, owned, part.scene);
    for (size_t k = 0; k < owned.size(); ++k)
      EXPECT_EQ(part.partition.instanceOwners[k], fresh.instanceOwners[owned[k]]);
    expectSameProxies(part.partition.proxies, fresh.proxies);
  }
}

TEST(PartFiles, EveryRankRoundTripsExactly) {
  TempDir dir;
  Written w = writeDirectory(dir.path.string(), "best", 3);
  ASSERT_TRUE(isPartDirectory(dir.path.string()));
  LightSampler reference(island());
  for (int r = 0; r < 3; ++r) {
    SCOPED_TRACE(r);
    RankPart part = loadRankPart(dir.path.string(), r, 3);
    const std::vector<int32_t> owned = w.partition.instancesOf(r);
    expectSameContent(w.scene, owned, part.scene);
    for (size_t k = 0; k < owned.size(); ++k)
      EXPECT_EQ(part.partition.instanceOwners[k], w.partition.instanceOwners[owned[k]]);
    expectSameProxies(part.partition.proxies, w.partition.proxies);
    // best's instanced proxies: their placements and shapes, bit for bit.
    ASSERT_FALSE(w.partition.proxyPlacements.empty());
    ASSERT_EQ(part.partition.proxyPlacements.size(), w.partition.proxyPlacements.size());
    EXPECT_EQ(std::memcmp(part.partition.proxyPlacements.data(), w.partition.proxyPlacements.data(),
                          w.partition.proxyPlacements.size() * sizeof(Affine3f)),
              0);
    ASSERT_EQ(part.partition.proxyShapes.size(), w.partition.proxyShapes.size());
    for (size_t s = 0; s < w.partition.proxyShapes.size(); ++s) {
      const std::vector<Box3f>& a = part.partition.proxyShapes[s].boxes;
      const std::vector<Box3f>& b = w.partition.proxyShapes[s].boxes;
      ASSERT_EQ(a.size(), b.size());
      EXPECT_EQ(std::memcmp(a.data(), b.data(), b.size() * sizeof(Box3f)), 0) << "shape " << s;
    }
    ASSERT_EQ(part.scene.views.size(), island().views.size());
    EXPECT_EQ(part.scene.views[0].name, island().views[0].name);
    EXPECT_TRUE(part.scene.views[0].from == island().views[0].from);
    // Only what the rank owns (plus what it needs) is in its part.
    EXPECT_EQ(ownedMemory(part.scene, part.partition.instancesOf(r)).total(),
              w.manifest.parts[r].estimatedBytes);
    EXPECT_EQ(ownedMemory(w.scene, owned).total(), w.manifest.parts[r].estimatedBytes);
    // Lights survive the trip: the same emitters, environment and suns.
    LightSampler lights(part.lights);
    EXPECT_EQ(lights.emissiveTriangleCount(), reference.emissiveTriangleCount());
    ASSERT_TRUE(part.lights.environment.image != nullptr || island().environment.image == nullptr);
    if (island().environment.image) {
      EXPECT_TRUE(
          sameBytes(part.lights.environment.image->pixels, island().environment.image->pixels));
    }
    EXPECT_EQ(part.lights.suns.size(), island().suns.size());
  }
}

// Point and spot lights (format 13) come back as they were written.
TEST(PartFiles, PointLightsSurviveTheTrip) {
  TempDir dir;
  Scene scene = island();
  PointLight spot;
  spot.position = {1, 2, 3};
  spot.intensity = {4, 5, 6};
  spot.direction = normalize(Vec3f(0, -1, 1));
  spot.cosTotalWidth = 0.8f;
  spot.cosFalloffStart = 0.9f;
  spot.falloff = PointLight::Falloff::Quartic;
  scene.pointLights = {PointLight{}, spot};
  PartDirectoryInfo info;
  writePartDirectory(dir.path.string(), scene, roundRobinPartition(scene, 2), lightScene(scene),
                     info);
  const RankPart part = loadRankPart(dir.path.string(), 1, 2);
  ASSERT_EQ(part.lights.pointLights.size(), 2u);
  const PointLight& back = part.lights.pointLights[1];
  EXPECT_EQ(back.position, spot.position);
  EXPECT_EQ(back.intensity, spot.intensity);
  EXPECT_EQ(back.direction, spot.direction);
  EXPECT_EQ(back.cosTotalWidth, spot.cosTotalWidth);
  EXPECT_EQ(back.cosFalloffStart, spot.cosFalloffStart);
  EXPECT_EQ(back.falloff, spot.falloff);
  EXPECT_EQ(part.lights.pointLights[0].falloff, PointLight::Falloff::None);
}

// Moving instances and cameras (format 14) keep their motion keys; the
// manifest the shutter and the transforms' times.
TEST(PartFiles, MotionSurvivesTheTrip) {
  TempDir dir;
  Scene scene = island();
  scene.shutterOpen = 0.25f, scene.shutterClose = 0.75f;
  scene.motionStart = 0.1f, scene.motionEnd = 0.9f;
  Affine3f sheared = Affine3f::rotate({0, 1, 0}, 1.0f);
  sheared.l[0][1] = 0.5f;
  for (size_t i = 0; i < scene.instances.size(); i += 3)
    scene.instances[i].motion = std::make_shared<const InstanceMotion>(
        scene.instances[i].transform, Affine3f::translate({1, 0, 0}) *
                                          (i % 2 ? sheared : Affine3f::identity()) *
                                          scene.instances[i].transform);
  scene.views[0].motion = std::make_shared<const InstanceMotion>(Affine3f::translate({0, 1, 0}),
                                                                 Affine3f::rotate({0, 1, 0}, 0.2f));
  PartDirectoryInfo info;
  writePartDirectory(dir.path.string(), scene, roundRobinPartition(scene, 1), lightScene(scene),
                     info);
  const RankPart part = loadRankPart(dir.path.string(), 0, 1);
  ASSERT_NE(part.scene.views[0].motion, nullptr);
  EXPECT_EQ(part.scene.views[0].motion->keys().size(), 2u);
  for (size_t v = 1; v < part.scene.views.size(); ++v)
    EXPECT_EQ(part.scene.views[v].motion, nullptr);
  EXPECT_EQ(part.manifest.shutterOpen, 0.25f);
  EXPECT_EQ(part.manifest.shutterClose, 0.75f);
  EXPECT_EQ(part.manifest.motionStart, 0.1f);
  EXPECT_EQ(part.manifest.motionEnd, 0.9f);
  ASSERT_EQ(part.scene.instances.size(), scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const auto& written = scene.instances[i].motion;
    const auto& read = part.scene.instances[i].motion;
    ASSERT_EQ(written == nullptr, read == nullptr) << i;
    if (!written) continue;
    ASSERT_EQ(read->keys().size(), written->keys().size()) << i;
    EXPECT_EQ(std::memcmp(read->keys().data(), written->keys().data(),
                          written->keys().size() * sizeof(MotionKey)),
              0)
        << i;
  }
}

TEST(PartFiles, OneRankHoldsTheWholeSceneBitForBit) {
  TempDir dir;
  Scene scene = island();
  Partition p = roundRobinPartition(scene, 1);
  PartDirectoryInfo info;
  writePartDirectory(dir.path.string(), scene, p, lightScene(scene), info);
  RankPart part = loadRankPart(dir.path.string(), 0, 1);
  std::vector<int32_t> all(scene.instances.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = int32_t(i);
  expectSameContent(scene, all, part.scene);
  // Nothing unused in the island: the whole scene comes back, in order.
  EXPECT_EQ(part.scene.meshes.size(), scene.meshes.size());
  EXPECT_EQ(part.scene.textures.size(), scene.textures.size());
  EXPECT_EQ(summarize(part.scene).memory.total(), summarize(scene).memory.total());
}

// A tabulated BSDF goes with the materials that name it, renumbered, and is
// checked again when read; a part without such materials holds none.
TEST(PartFiles, BsdfTablesGoWithTheirMaterials) {
  TempDir dir;
  Scene scene;
  scene.name = "tables";
  const fs::path corpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "bsdf";
  scene.bsdfTables.push_back(readFourierBsdfFile((corpus / "valid.bsdf").string()));
  scene.bsdfTables.push_back(readFourierBsdfFile((corpus / "valid.bsdf").string()));
  Material plain, tabulated;
  tabulated.name = "tabulated";
  tabulated.model = std::make_shared<FourierModel>(1);
  scene.addMaterial(plain);
  scene.addMaterial(tabulated);
  for (int32_t k = 0; k < 2; ++k) {
    Mesh mesh;
    mesh.name = "quad" + std::to_string(k);
    mesh.positions = {{0, 0, float(k)}, {1, 0, float(k)}, {1, 1, float(k)}};
    mesh.indices = {{0, 1, 2}};
    mesh.material = k;
    scene.addSingleInstanceMesh(std::move(mesh));
  }
  scene.validate();
  const std::vector<RankSet> owners(2, RankSet::single(0));
  const std::string both = (dir.path / "both.part").string(),
                    plainOnly = (dir.path / "plain.part").string();
  writePartFile(both, scene, {0, 1}, owners, 0, 1);
  writePartFile(plainOnly, scene, {0}, owners, 0, 1);
  const LoadedPart a = readPartFile(both), b = readPartFile(plainOnly);
  ASSERT_EQ(a.scene.bsdfTables.size(), 1u);  // table 0 is named by no material
  const FourierBsdfTable& t = *a.scene.bsdfTables[0];
  EXPECT_EQ(t.nMu, 5);
  EXPECT_EQ(t.coefficients, scene.bsdfTables[1]->coefficients);
  EXPECT_EQ(t.a0, scene.bsdfTables[1]->a0);
  EXPECT_EQ(a.scene.materials[1].bsdfTable(), 0);
  EXPECT_EQ(a.scene.materials[0].bsdfTable(), kNoBsdfTable);
  EXPECT_TRUE(b.scene.bsdfTables.empty());
  // A rank keeps only the tables of what it owns.
  Scene released = scene;
  released.releaseAllBut({0});
  EXPECT_FALSE(released.bsdfTables[1]);
}

TEST(PartFiles, MergedPartsHoldEveryInstance) {
  TempDir dir;
  Written w = writeDirectory(dir.path.string(), "bvh-style", 4);
  Partition merged;
  Scene all = loadAllParts(dir.path.string(), merged);
  size_t copies = 0;
  for (const RankSet& m : w.partition.instanceOwners) copies += size_t(m.count());
  EXPECT_EQ(all.instances.size(), copies);
  merged.checkCovers(all);
}

TEST(PartFiles, DamageIsReportedNamingTheFile) {
  TempDir dir;
  Written w = writeDirectory(dir.path.string(), "object-proxies", 2);
  const std::string d = dir.path.string();
  const std::string part1 = dir / partFileName(1);
  auto load1 = [&] { loadRankPart(d, 1, 2); };
  ASSERT_EQ(errorOf(load1), "(no error)");

  // Wrong rank count.
  EXPECT_NE(errorOf([&] { loadRankPart(d, 0, 3); }).find("partitioned for 2 ranks"),
            std::string::npos);

  // A flipped byte in the payload: the hash catches it.
  const auto size = fs::file_size(part1);
  fs::copy_file(part1, dir / "backup", fs::copy_options::overwrite_existing);
  flipByte(part1, size / 2);
  std::string e = errorOf(load1);
  EXPECT_NE(e.find(part1), std::string::npos) << e;
  EXPECT_NE(e.find("corrupt"), std::string::npos) << e;
  // Rank 0 does not read rank 1's part: it still loads.
  EXPECT_EQ(errorOf([&] { loadRankPart(d, 0, 2); }), "(no error)");

  // Truncated.
  fs::copy_file(dir / "backup", part1, fs::copy_options::overwrite_existing);
  fs::resize_file(part1, size - 100);
  e = errorOf(load1);
  EXPECT_NE(e.find("truncated"), std::string::npos) << e;
  fs::resize_file(part1, 10);
  EXPECT_NE(errorOf(load1).find("truncated"), std::string::npos);

  // Missing.
  fs::remove(part1);
  e = errorOf(load1);
  EXPECT_NE(e.find("no such file"), std::string::npos) << e;

  // Another version of the format (the header says so).
  fs::copy_file(dir / "backup", part1, fs::copy_options::overwrite_existing);
  {
    std::fstream f(part1, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(8);
    uint32_t v = kPartFormatVersion + 1;
    f.write(reinterpret_cast<const char*>(&v), 4);
  }
  e = errorOf(load1);
  EXPECT_NE(e.find("another version"), std::string::npos) << e;

  // A damaged header field other than the version: the header hash.
  fs::copy_file(dir / "backup", part1, fs::copy_options::overwrite_existing);
  flipByte(part1, 20);
  EXPECT_NE(errorOf(load1).find("corrupt header"), std::string::npos);

  // A valid part file from another partitioning: the manifest's hash catches it.
  {
    TempDir other;
    Written foreign = writeDirectory(other.path.string(), "spatial-simple", 2);
    ASSERT_NE(foreign.manifest.parts[1].hash, w.manifest.parts[1].hash);
    fs::copy_file(other / partFileName(1), part1, fs::copy_options::overwrite_existing);
  }
  e = errorOf(load1);
  EXPECT_NE(e.find("does not belong to this manifest"), std::string::npos) << e;

  // The shared file damaged: every rank fails.
  fs::copy_file(dir / "backup", part1, fs::copy_options::overwrite_existing);
  ASSERT_EQ(errorOf(load1), "(no error)");
  flipByte(dir / "shared.fpart", fs::file_size(dir / "shared.fpart") - 30);
  EXPECT_NE(errorOf([&] { loadRankPart(d, 0, 2); }).find("shared.fpart"), std::string::npos);
}

TEST(PartFiles, ManifestFromAnotherVersionOrBrokenIsRefused) {
  TempDir dir;
  writeDirectory(dir.path.string(), "spatial-simple", 2);
  const std::string manifest = dir / "manifest.json";
  nlohmann::json j = nlohmann::json::parse(std::ifstream(manifest));
  j["version"] = kPartFormatVersion + 7;
  std::ofstream(manifest) << j.dump();
  std::string e = errorOf([&] { loadRankPart(dir.path.string(), 0, 2); });
  EXPECT_NE(e.find("another version"), std::string::npos) << e;
  std::ofstream(manifest) << "{ not json";
  e = errorOf([&] { loadRankPart(dir.path.string(), 0, 2); });
  EXPECT_NE(e.find("not valid JSON"), std::string::npos) << e;
  j["version"] = kPartFormatVersion;
  const nlohmann::json partFile = j["parts"][1]["file"];
  j["parts"][1]["file"] = "../elsewhere.fpart";
  std::ofstream(manifest) << j.dump();
  e = errorOf([&] { loadRankPart(dir.path.string(), 0, 2); });
  EXPECT_NE(e.find("bad file name"), std::string::npos) << e;
  j["parts"][1]["file"] = partFile;
  j["integrator_max_depth"] = -3;
  std::ofstream(manifest) << j.dump();
  e = errorOf([&] { loadRankPart(dir.path.string(), 0, 2); });
  EXPECT_NE(e.find("bad integrator_max_depth -3"), std::string::npos) << e;
  j.erase("integrator_max_depth");
  // Numbers that do not fit their field are the manifest's error, not an
  // overflowing conversion (a fuzzer's finding: 2e82 instances).
  for (auto [key, value] : std::vector<std::pair<std::string, nlohmann::json>>{{"instances", 2e82},
                                                                               {"instances", -1},
                                                                               {"instances", 1.5},
                                                                               {"rank", 3e9},
                                                                               {"bytes", "12"}}) {
    nlohmann::json broken = j;
    broken["parts"][1][key] = value;
    std::ofstream(manifest) << broken.dump();
    e = errorOf([&] { loadRankPart(dir.path.string(), 0, 2); });
    EXPECT_NE(e.find("manifest.json: missing or bad field"), std::string::npos)
        << key << " " << value << ": " << e;
  }
  for (auto [key, value] : std::vector<std::pair<std::string, nlohmann::json>>{
           {"film_scale", 1e300},
           {"ranks", 1e10},
           {"version", -2},
           {"summary", {{"triangles", 2e82}}},
           {"summary", nlohmann::json::parse(R"({"bounds": [[0, 0, 0], [1, 2]]})")}}) {
    nlohmann::json broken = j;
    broken[key] = value;
    std::ofstream(manifest) << broken.dump();
    e = errorOf([&] { loadRankPart(dir.path.string(), 0, 2); });
    EXPECT_NE(e.find("manifest.json: missing or bad field"), std::string::npos)
        << key << " " << value << ": " << e;
  }
  fs::remove(manifest);
  EXPECT_FALSE(isPartDirectory(dir.path.string()));
}

}  // namespace ferry
