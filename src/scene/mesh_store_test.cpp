#include "scene/mesh_store.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/error.h"

namespace ferry {
namespace {

std::string spillPath(const char* name) {
  return (std::filesystem::temp_directory_path() /
          (std::string(name) + "." + std::to_string(::getpid())))
      .string();
}

Mesh triangleFan(int n, bool normals, bool uvs) {
  Mesh m;
  m.name = "fan";
  m.material = 2;
  m.positions.push_back({0, 0, 0});
  for (int i = 0; i <= n; ++i) m.positions.push_back({float(i), 1.0f + float(i % 3), -float(i)});
  for (int i = 0; i < n; ++i) m.indices.push_back({0, i + 1, i + 2});
  if (normals) m.normals.assign(m.positions.size(), Vec3f{0, 1, 0});
  if (uvs)
    for (size_t i = 0; i < m.positions.size(); ++i) m.uvs.push_back({float(i), 0.5f});
  return m;
}

}  // namespace

TEST(MeshStore, StoredMeshesKeepCountsAndBoundsAndReadBackExactly) {
  auto store = std::make_shared<MeshStore>(spillPath("ferry-mesh-store-test"));
  EXPECT_FALSE(std::filesystem::exists(store->path()));  // unlinked at once
  Scene scene;
  scene.meshStore = store;
  for (int k = 0; k < 3; ++k) {
    Mesh m = triangleFan(10 + k, k != 1, k != 2);
    m.media = MediumInterface{k, kNoMedium};
    const Mesh copy = m;
    store->store(m);
    ASSERT_TRUE(m.stored.has_value());
    EXPECT_TRUE(m.positions.empty() && m.indices.empty() && m.normals.empty() && m.uvs.empty());
    EXPECT_EQ(m.triangleCount(), copy.triangleCount());
    EXPECT_EQ(m.vertexCount(), copy.vertexCount());
    EXPECT_EQ(m.hasNormals(), copy.hasNormals());
    EXPECT_EQ(m.hasUvs(), copy.hasUvs());
    EXPECT_EQ(m.bounds().lower, copy.bounds().lower);
    EXPECT_EQ(m.bounds().upper, copy.bounds().upper);
    scene.meshes.push_back(std::move(m));
    Mesh scratch;
    const Mesh& back = scene.geometry(int32_t(k), scratch);
    EXPECT_EQ(back.name, copy.name);
    EXPECT_EQ(back.material, copy.material);
    EXPECT_EQ(back.media, copy.media);
    EXPECT_FALSE(back.stored.has_value());
    EXPECT_TRUE(back.hasVertexSlack());
    ASSERT_EQ(back.positions.size(), copy.positions.size());
    for (size_t i = 0; i < copy.positions.size(); ++i)
      EXPECT_EQ(back.positions[i], copy.positions[i]);
    ASSERT_EQ(back.indices.size(), copy.indices.size());
    for (size_t i = 0; i < copy.indices.size(); ++i)
      for (int j = 0; j < 3; ++j) EXPECT_EQ(back.indices[i][j], copy.indices[i][j]);
    EXPECT_EQ(back.normals.size(), copy.normals.size());
    EXPECT_EQ(back.uvs.size(), copy.uvs.size());
  }
  // A mesh in memory is given back as it is.
  scene.meshes.push_back(triangleFan(4, true, true));
  Mesh scratch;
  EXPECT_EQ(&scene.geometry(3, scratch), &scene.meshes[3]);
}

TEST(MeshStore, ABrokenMeshIsAnInputErrorNamingItNotStoredSilently) {
  MeshStore store(spillPath("ferry-mesh-store-bad"));
  Mesh m = triangleFan(5, false, false);
  m.indices[3].z = 99;
  try {
    store.store(m);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mesh 'fan' triangle 3 uses vertex 99"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(m.stored.has_value());
}

}  // namespace ferry
