#include "partition/partition.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <map>
#include <numeric>
#include <unordered_map>

#include "core/error.h"
#include "core/random.h"
#include "partition/triangle_clusters.h"
#include "partition/units.h"
#include "scene/scene.h"

namespace ferry {
namespace {

// Which proxies overlap a box: a small median-split tree over proxy boxes.
class ProxyOverlapTree {
 public:
  explicit ProxyOverlapTree(const std::vector<Proxy>& proxies)
      : proxies_(proxies), order_(proxies.size()) {
    std::iota(order_.begin(), order_.end(), 0u);
    if (order_.empty()) return;
    nodes_.resize(1);
    build(0, 0, uint32_t(order_.size()));
  }
  // Indices of proxies overlapping `box` (closed boxes), ascending.
  std::vector<uint32_t> overlapping(const Box3f& box) const {
    std::vector<uint32_t> out;
    if (nodes_.empty()) return out;
    std::vector<uint32_t> stack = {0};
    while (!stack.empty()) {
      const Node& n = nodes_[stack.back()];
      stack.pop_back();
      if (!n.bounds.overlaps(box)) continue;
      if (n.left < 0) {
        for (uint32_t k = n.first; k < n.first + n.count; ++k)
          if (proxies_[order_[k]].bounds.overlaps(box)) out.push_back(order_[k]);
      } else {
        stack.push_back(uint32_t(n.left));
        stack.push_back(uint32_t(n.left + 1));
      }
    }
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  struct Node {
    Box3f bounds;
    int32_t left = -1;  // children at left, left + 1
    uint32_t first = 0, count = 0;
  };
  // Fills nodes_[slot] with the subtree over order_[first, first + count).
  void build(uint32_t slot, uint32_t first, uint32_t count) {
    Box3f bounds, centres;
    for (uint32_t k = first; k < first + count; ++k) {
      bounds.extend(proxies_[order_[k]].bounds);
      centres.extend(proxies_[order_[k]].bounds.center());
    }
    nodes_[slot].bounds = bounds;
    if (count <= 8) {
      nodes_[slot].first = first;
      nodes_[slot].count = count;
      return;
    }
    const int axis = centres.longestAxis();
    const uint32_t mid = first + count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                     [&](uint32_t a, uint32_t b) {
                       float ca = proxies_[a].bounds.center()[axis],
                             cb = proxies_[b].bounds.center()[axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    const int32_t left = int32_t(nodes_.size());
    nodes_.resize(nodes_.size() + 2);
    nodes_[slot].left = left;
    build(uint32_t(left), first, mid - first);
    build(uint32_t(left + 1), mid, first + count - mid);
  }

  const std::vector<Proxy>& proxies_;
  std::vector<uint32_t> order_;
  std::vector<Node> nodes_;
};

// Cluster size at the leaves of the cover check's trees: small enough that
// a leaf lies in few proxies, large enough that the trees stay small (about
// 7 bytes per triangle of the meshes that need one).
constexpr size_t kCoverLeafTriangles = 16;

// Is `box` inside the union of the candidate boxes? Subtracts one overlapping
// candidate at a time and recurses on the (up to 6) pieces left. `budget`
// bounds the work; when it runs out the answer is "not shown" (false).
bool coveredByUnion(const Box3f& box, const std::vector<const Box3f*>& candidates, size_t from,
                    int64_t& budget) {
  if (--budget < 0) return false;
  for (size_t k = from; k < candidates.size(); ++k)
    if (candidates[k]->contains(box)) return true;
  for (size_t k = from; k < candidates.size(); ++k) {
    const Box3f& c = *candidates[k];
    if (!c.overlaps(box)) continue;
    // box minus c: slabs below and above c along each axis, then narrow.
    Box3f rest = box;
    for (int axis = 0; axis < 3; ++axis) {
      if (rest.lower[axis] < c.lower[axis]) {
        Box3f piece = rest;
        piece.upper[axis] = c.lower[axis];
        if (!coveredByUnion(piece, candidates, k + 1, budget)) return false;
        rest.lower[axis] = c.lower[axis];
      }
      if (rest.upper[axis] > c.upper[axis]) {
        Box3f piece = rest;
        piece.lower[axis] = c.upper[axis];
        if (!coveredByUnion(piece, candidates, k + 1, budget)) return false;
        rest.upper[axis] = c.upper[axis];
      }
    }
    return true;  // what is left of the box is inside c
  }
  return false;
}

}  // namespace

std::vector<int32_t> Partition::instancesOf(int rank) const {
  std::vector<int32_t> out;
  for (size_t i = 0; i < instanceOwners.size(); ++i)
    if (instanceOwners[i].contains(rank)) out.push_back(int32_t(i));
  return out;
}

void Partition::checkCovers(const Scene& scene) const {
  FERRY_CHECK_EQ(instanceOwners.size(), scene.instances.size());
  FERRY_CHECK_GE(ranks, 1);
  const RankSet valid = RankSet::firstN(ranks);
  for (const Proxy& p : proxies) {
    if (p.owners.empty() || !p.owners.isSubsetOf(valid))
      throw InternalError(
          fmt::format("a proxy has owners {} outside {} ranks", p.owners.toString(), ranks));
    if (p.shape >= 0 && (size_t(p.shape) >= proxyShapes.size() || p.placement < 0 ||
                         size_t(p.placement) >= proxyPlacements.size()))
      throw InternalError(fmt::format("a proxy has shape {} of {}, placement {} of {}", p.shape,
                                      proxyShapes.size(), p.placement, proxyPlacements.size()));
  }
  ProxyOverlapTree tree(proxies);
  const std::vector<Box3f> bounds = instanceWorldBounds(scene);
  const std::vector<uint32_t> placements = scene.instanceCountPerObject();
  std::unordered_map<int32_t, ClusterTree> objectSpaceTrees;  // by mesh, made when first needed

  // Box proxies a ray may be sent to for content of `owners` near `box`:
  // those overlapping it whose every owner holds the content.
  auto eligible = [&](const Box3f& box, const RankSet& owners) {
    std::vector<const Box3f*> out;
    for (uint32_t k : tree.overlapping(box))
      if (proxies[k].shape < 0 && proxies[k].owners.isSubsetOf(owners))
        out.push_back(&proxies[k].bounds);
    return out;
  };
  // An instanced proxy covers an instance when it is placed as the instance
  // is (the same transform, bit for bit), its owners hold the instance, and
  // every triangle of the instance's object lies, in object space, in one of
  // its shape's boxes (checked once per shape and object).
  std::map<std::pair<int32_t, int32_t>, bool> shapeCovers;
  auto coversObject = [&](int32_t shape, int32_t object) {
    const std::vector<Box3f>& boxes = proxyShapes[size_t(shape)].boxes;
    // Neighbouring triangles mostly share a box (the boxes are clusters of
    // them), so the box that held the last triangle is tried first: shapes
    // by size have up to 1024 boxes per mesh.
    size_t last = 0;
    for (int32_t m : scene.objects[size_t(object)].meshes) {
      Mesh scratch;
      const Mesh& mesh = scene.geometry(m, scratch);
      for (const auto& t : mesh.indices) {
        Box3f tri;
        for (int v = 0; v < 3; ++v) tri.extend(mesh.positions[t[v]]);
        if (last < boxes.size() && boxes[last].contains(tri)) continue;
        const auto it = std::find_if(boxes.begin(), boxes.end(),
                                     [&](const Box3f& b) { return b.contains(tri); });
        if (it == boxes.end()) return false;
        last = size_t(it - boxes.begin());
      }
    }
    for (int32_t g : scene.objects[size_t(object)].geometries)
      if (const Shape* shape = scene.geometries[g].shape.get(); shape && !shape->bounds().empty())
        if (std::none_of(boxes.begin(), boxes.end(),
                         [&](const Box3f& b) { return b.contains(shape->bounds()); }))
          return false;
    return true;
  };
  auto coveredByInstanced = [&](size_t i, const RankSet& owners) {
    const Instance& inst = scene.instances[i];
    if (inst.motion) return false;  // placed proxies are static
    for (uint32_t k : tree.overlapping(bounds[i])) {
      const Proxy& p = proxies[k];
      if (p.shape < 0 || !p.owners.isSubsetOf(owners) ||
          std::memcmp(&proxyPlacements[size_t(p.placement)], &inst.transform, sizeof(Affine3f)) !=
              0)
        continue;
      const auto key = std::make_pair(p.shape, inst.object);
      auto it = shapeCovers.find(key);
      if (it == shapeCovers.end())
        it = shapeCovers.emplace(key, coversObject(p.shape, inst.object)).first;
      if (it->second) return true;
    }
    return false;
  };
  auto covered = [&](const Box3f& box, const std::vector<const Box3f*>& candidates,
                     int64_t budget) { return coveredByUnion(box, candidates, 0, budget); };

  for (size_t i = 0; i < bounds.size(); ++i) {
    const RankSet& owners = instanceOwners[i];
    if (owners.empty()) throw InternalError(fmt::format("instance {} has no owner", i));
    if (!owners.isSubsetOf(valid))
      throw InternalError(
          fmt::format("instance {} has owners {} outside {} ranks", i, owners.toString(), ranks));
    if (bounds[i].empty()) continue;
    // (No instanced proxies, no second overlap query per instance.)
    if (!proxyShapes.empty() && coveredByInstanced(i, owners)) continue;
    const std::vector<const Box3f*> near = eligible(bounds[i], owners);
    if (covered(bounds[i], near, 2000)) continue;
    // Proxies that follow the content (braided meshes and instances, domains)
    // need not cover the instance's box, only its geometry: go down each
    // mesh's cluster tree (the build steps braiding uses, so a braided box is
    // one of its nodes) until a node's box is covered, then, at the leaves,
    // triangle by triangle. An instanced object's trees are made once, in
    // object space, and shared by its instances.
    const Instance& inst = scene.instances[i];
    if (inst.motion) {  // its proxies are its meshes' and geometries' swept boxes
      for (int32_t m : scene.objects[inst.object].meshes) {
        if (scene.meshes[m].triangleCount() == 0) continue;
        const Box3f box = inst.placeBox(scene.meshes[m].bounds());
        if (!covered(box, eligible(box, owners), 1000000))
          throw InternalError(fmt::format(
              "moving instance {} (object '{}') is not covered by proxies of its owners {}", i,
              scene.objects[inst.object].name, owners.toString()));
      }
    }
    const bool shared = placements[inst.object] > 1;
    for (int32_t m : scene.objects[inst.object].meshes) {
      if (scene.meshes[m].triangleCount() == 0 || inst.motion) continue;
      if (!shared) {  // (a shared mesh's box is its tree's root, made once)
        const Box3f meshBox = inst.transform.transformBox(scene.meshes[m].bounds());
        if (covered(meshBox, eligible(meshBox, owners), 2000)) continue;
      }
      // A stored mesh (out of core) is read back only when needed: to make
      // its tree, or at a leaf no proxy holds whole; not for every instance.
      Mesh scratch;
      const Mesh* stored = nullptr;
      auto geometry = [&]() -> const Mesh& {
        if (!stored) stored = &scene.geometry(m, scratch);
        return *stored;
      };
      ClusterTree own;
      if (!shared) own = clusterTree(geometry(), inst.transform, kCoverLeafTriangles);
      auto it = objectSpaceTrees.find(m);
      if (shared && it == objectSpaceTrees.end())
        it = objectSpaceTrees
                 .emplace(m, clusterTree(geometry(), Affine3f::identity(), kCoverLeafTriangles))
                 .first;
      const ClusterTree& tree = shared ? it->second : own;
      // A node's box in world space: object-space boxes are transformed as
      // unitProxyBoxes transforms a braided instance's (the same floats).
      auto worldBox = [&](const Box3f& b) { return shared ? inst.transform.transformBox(b) : b; };
      std::vector<int32_t> stack{0};
      while (!stack.empty()) {
        const ClusterTree::Node& node = tree.nodes[size_t(stack.back())];
        stack.pop_back();
        const Box3f box = worldBox(node.bounds);
        const std::vector<const Box3f*> nodeNear = eligible(box, owners);
        // A node whose box is not in one proxy is usually split by the
        // proxies into its children: a small budget, then down.
        if (covered(box, nodeNear, node.left < 0 ? 2000 : 64)) continue;
        if (node.left >= 0) {
          stack.push_back(node.right);
          stack.push_back(node.left);
          continue;
        }
        const Mesh& mesh = geometry();
        std::vector<const Box3f*> triNear;
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
          const uint32_t t = tree.triangles[k];
          Box3f tri;
          for (int v = 0; v < 3; ++v)
            tri.extend(inst.transform.transformPoint(mesh.positions[mesh.indices[t][v]]));
          triNear.clear();
          for (const Box3f* b : nodeNear)
            if (b->overlaps(tri)) triNear.push_back(b);
          if (!covered(tri, triNear, 1000000))
            throw InternalError(
                fmt::format("instance {} (object '{}', mesh '{}', triangle {}) is not covered by "
                            "proxies of its owners {}",
                            i, scene.objects[inst.object].name, mesh.name, t, owners.toString()));
        }
      }
    }
    for (int32_t g : scene.objects[inst.object].geometries) {
      const Shape* shape = scene.geometries[g].shape.get();
      if (!shape || shape->bounds().empty()) continue;
      const Box3f box = inst.placeBox(shape->bounds());
      if (!covered(box, eligible(box, owners), 1000000))
        throw InternalError(fmt::format(
            "instance {} (object '{}', geometry '{}') is not covered by proxies of its owners {}",
            i, scene.objects[inst.object].name, scene.geometries[g].name, owners.toString()));
    }
  }
}

Partition roundRobinPartition(const Scene& scene, int ranks) {
  Partition p;
  p.ranks = ranks;
  std::vector<Box3f> bounds = instanceWorldBounds(scene);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    RankSet owner = RankSet::single(int(i % size_t(ranks)));
    p.instanceOwners.push_back(owner);
    if (!bounds[i].empty()) p.proxies.push_back({bounds[i], owner});
  }
  return p;
}

Partition randomPartition(const Scene& scene, int ranks, uint32_t seed) {
  Partition p;
  p.ranks = ranks;
  std::vector<Box3f> bounds = instanceWorldBounds(scene);
  Box3f world;
  for (const Box3f& b : bounds) world.extend(b);
  auto uniform = [&](uint32_t a, uint32_t b) {
    return random01(RandomKey{a, b, 0, seed}, RandomDim::OwnerPick);
  };
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    int copies = 1 + int(uniform(uint32_t(i), 0) * std::min(3, ranks));
    RankSet owners;
    for (int c = 0; owners.empty() || owners.count() < copies; ++c)
      owners.insert(int(uniform(uint32_t(i), 1 + c) * ranks));
    p.instanceOwners.push_back(owners);
    if (bounds[i].empty()) continue;
    // Inflated by up to half its size: conservative, overlapping neighbours.
    Vec3f grow = bounds[i].size() * (0.5f * uniform(uint32_t(i), 100));
    p.proxies.push_back({{bounds[i].lower - grow, bounds[i].upper + grow}, owners});
  }
  // Random single-owner boxes anywhere in the world.
  for (int k = 0; k < 2 * ranks; ++k) {
    Vec3f a = world.lower + world.size() * Vec3f(uniform(1000000 + k, 1), uniform(1000000 + k, 2),
                                                 uniform(1000000 + k, 3));
    Vec3f b = world.lower + world.size() * Vec3f(uniform(1000000 + k, 4), uniform(1000000 + k, 5),
                                                 uniform(1000000 + k, 6));
    Box3f box;
    box.extend(a);
    box.extend(b);
    p.proxies.push_back({box, RankSet::single(int(uniform(1000000 + k, 7) * ranks))});
  }
  return p;
}

}  // namespace ferry
