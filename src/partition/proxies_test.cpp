#include "partition/proxies.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "render/render_test_util.h"
#include "scene/scene.h"

namespace ferry {
namespace {

using testing::diffuseMaterial;
using testing::makeQuad;

// A palm: a thin trunk 10 high and a wide crown on top, one mesh, placed twice.
Scene twoPalms() {
  Scene scene;
  scene.materials.push_back(diffuseMaterial({0.5f, 0.5f, 0.5f}));
  Mesh palm = makeQuad({0, 0, 0}, {0.1f, 0, 0}, {0, 10, 0}, 0);
  const Mesh crown = makeQuad({-3, 10, -3}, {6, 0, 0}, {0, 0, 6}, 0);
  for (const auto& t : crown.indices) palm.indices.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  palm.positions.insert(palm.positions.end(), crown.positions.begin(), crown.positions.end());
  palm.uvs.insert(palm.uvs.end(), crown.uvs.begin(), crown.uvs.end());
  scene.meshes.push_back(palm);
  scene.objects.push_back({"palm", {0}});
  for (float x : {0.0f, 20.0f}) {
    Instance instance;
    instance.transform.t = {x, 0, 0};
    scene.instances.push_back(instance);
  }
  return scene;
}

bool inside(const Box3f& b, Vec3f p) {
  for (int a = 0; a < 3; ++a)
    if (p[a] < b.lower[a] || p[a] > b.upper[a]) return false;
  return true;
}

TEST(InstanceProxies, BraidedInstancesLeaveTheGapsOfTheirObject) {
  const Scene scene = twoPalms();
  const UnitSet units = extractUnits(scene, {});
  const std::vector<RankSet> owners(units.units.size(), RankSet::single(0));
  const std::vector<Proxy> one = instanceProxies(scene, units, owners, 1, 1);
  const std::vector<Proxy> two = instanceProxies(scene, units, owners, 1, 2);
  ASSERT_EQ(one.size(), 2u);  // a box per instance
  ASSERT_EQ(two.size(), 4u);  // trunk and crown, per instance
  for (float x : {0.0f, 20.0f}) {
    // Beside the trunk, under the crown: in the instance's box, in none of its pieces.
    const Vec3f gap{x + 2, 5, 2};
    int inOne = 0, inTwo = 0;
    for (const Proxy& p : one) inOne += inside(p.bounds, gap);
    for (const Proxy& p : two) inTwo += inside(p.bounds, gap);
    EXPECT_EQ(inOne, 1);
    EXPECT_EQ(inTwo, 0);
    // Every vertex, placed, is still in one of the pieces.
    for (Vec3f v : scene.meshes[0].positions) {
      int in = 0;
      for (const Proxy& p : two) in += inside(p.bounds, v + Vec3f{x, 0, 0});
      EXPECT_GE(in, 1);
    }
  }
}

TEST(InstanceProxies, ShapesBySizeHaveABoxPerFourTrianglesOfEachMeshUpTo1024) {
  EXPECT_EQ(shapeBoxesForMesh(kShapeBoxesBySize, 1), 1);
  EXPECT_EQ(shapeBoxesForMesh(kShapeBoxesBySize, 4), 1);
  EXPECT_EQ(shapeBoxesForMesh(kShapeBoxesBySize, 5), 2);
  EXPECT_EQ(shapeBoxesForMesh(kShapeBoxesBySize, 4096), 1024);
  EXPECT_EQ(shapeBoxesForMesh(kShapeBoxesBySize, 100000), kMaxShapeBoxesPerMesh);
  EXPECT_EQ(shapeBoxesForMesh(16, 100000), 16);  // a number is that number
  EXPECT_EQ(shapeBoxesForMesh(1, 100000), 1);
  // On a model of two meshes, 40 and 6,000 triangles: 10 and 1,024 boxes
  // (clusterTriangles makes exactly as many as asked, up to one per triangle).
  Scene scene;
  scene.materials.push_back(diffuseMaterial({0.5f, 0.5f, 0.5f}));
  auto grid = [](int cells, float x) {
    Mesh m;
    for (int i = 0; i < cells; ++i) {
      const Mesh q = makeQuad({x + float(i), 0, 0}, {0.5f, 0, 0}, {0, 0.5f, 0}, 0);
      const int base = int(m.positions.size());
      for (const auto& t : q.indices) m.indices.push_back({t[0] + base, t[1] + base, t[2] + base});
      m.positions.insert(m.positions.end(), q.positions.begin(), q.positions.end());
      m.uvs.insert(m.uvs.end(), q.uvs.begin(), q.uvs.end());
    }
    return m;
  };
  scene.meshes.push_back(grid(20, 0));     // 40 triangles
  scene.meshes.push_back(grid(3000, 50));  // 6,000
  scene.objects.push_back({"model", {0, 1}});
  scene.instances.resize(2);
  scene.instances[1].transform.t = {0, 10, 0};
  const std::vector<std::vector<Box3f>> boxes = instancedObjectBoxes(scene, kShapeBoxesBySize);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_EQ(boxes[0].size(), 10u + 1024u);
}

TEST(InstanceProxies, TheCoverCheckFindsEveryBraidedPieceAndEveryGap) {
  // Partition::checkCovers goes down object-space cluster trees: it accepts
  // braided instances without testing each triangle, and still finds a
  // piece that no longer holds its triangles.
  const Scene scene = twoPalms();
  const UnitSet units = extractUnits(scene, {});
  const std::vector<RankSet> owners(units.units.size(), RankSet::single(0));
  Partition p;
  p.ranks = 1;
  p.instanceOwners.assign(scene.instances.size(), RankSet::single(0));
  p.proxies = instanceProxies(scene, units, owners, 1, 2);
  ASSERT_NO_THROW(p.checkCovers(scene));
  for (size_t k = 0; k < p.proxies.size(); ++k)
    for (int axis = 0; axis < 3; ++axis) {
      Partition shrunk = p;
      Box3f& b = shrunk.proxies[k].bounds;
      if (b.upper[axis] == b.lower[axis]) continue;  // a flat piece: nothing to take off
      b.upper[axis] -= 0.01f * (b.upper[axis] - b.lower[axis]);
      EXPECT_THROW(shrunk.checkCovers(scene), InternalError) << "proxy " << k << ", axis " << axis;
    }
  Partition wrongOwner = p;
  wrongOwner.ranks = 2;
  wrongOwner.proxies[3].owners = RankSet::single(1);
  EXPECT_THROW(wrongOwner.checkCovers(scene), InternalError);
}

}  // namespace
}  // namespace ferry
