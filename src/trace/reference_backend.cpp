#include "trace/reference_backend.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <vector>

#include "core/error.h"
#include "scene/scene.h"
#include "trace/alpha_cutout.h"
#include "trace/queue_trace.h"

namespace ferry {
namespace {

struct Vec3d {
  double x = 0, y = 0, z = 0;
};
Vec3d toDouble(Vec3f v) {
  return {v.x, v.y, v.z};
}
Vec3d operator-(Vec3d a, Vec3d b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
double dot(Vec3d a, Vec3d b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3d cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// A ray as the box tests read it.
struct BoxRay {
  Vec3f origin, inverseDirection;
  float tnear;
};
BoxRay boxRay(Vec3f origin, Vec3f direction, float tnear) {
  return {origin, {1 / direction.x, 1 / direction.y, 1 / direction.z}, tnear};
}

// Whether the ray crosses `b` between tnear and tfar; `entry` is where. An
// axis the ray is parallel to gives infinite slab distances (or NaN when the
// origin lies on the slab's plane, which the comparisons then ignore: the
// plane is inside the box's padding).
bool crossesBox(const Box3f& b, const BoxRay& r, float tfar, float& entry) {
  float t0 = r.tnear, t1 = tfar;
  for (int a = 0; a < 3; ++a) {
    float lo = (b.lower[a] - r.origin[a]) * r.inverseDirection[a];
    float hi = (b.upper[a] - r.origin[a]) * r.inverseDirection[a];
    if (lo > hi) std::swap(lo, hi);
    if (lo > t0) t0 = lo;
    if (hi < t1) t1 = hi;
  }
  entry = t0;
  return t0 <= t1;
}

// A bounding volume hierarchy over items given by their boxes: the longest
// axis of the centroids' box split at the median, four items a leaf. Every
// node box is padded (a flat wall's box has no thickness, and the float slab
// test must not lose a hit on it; the triangle test decides).
class Bvh {
 public:
  void build(const std::vector<Box3f>& boxes) {
    nodes_.clear();
    items_.resize(boxes.size());
    std::iota(items_.begin(), items_.end(), 0u);
    if (boxes.empty()) return;
    nodes_.resize(1);
    buildNode(boxes, 0, 0, boxes.size());
  }

  // Calls visit(item) for the items whose node boxes the ray crosses before
  // `tfar`, nearer nodes first; `tfar` is read at every node, so a
  // closest-hit search that shrinks it prunes the rest. visit returns false
  // to stop.
  template <typename Visit>
  void traverse(const BoxRay& ray, const float& tfar, const Visit& visit) const {
    if (nodes_.empty()) return;
    uint32_t stack[128];
    int size = 0;
    stack[size++] = 0;
    while (size > 0) {
      const Node& n = nodes_[stack[--size]];
      float entry;
      if (!crossesBox(n.box, ray, tfar, entry)) continue;
      if (n.count > 0) {
        for (uint32_t i = n.first; i < n.first + n.count; ++i)
          if (!visit(items_[i])) return;
        continue;
      }
      float entryLeft, entryRight;
      const bool left = crossesBox(nodes_[n.left].box, ray, tfar, entryLeft);
      const bool right = crossesBox(nodes_[n.left + 1].box, ray, tfar, entryRight);
      FERRY_CHECK_LE(size + 2, 128);
      if (left && right) {
        const bool leftFirst = entryLeft <= entryRight;
        stack[size++] = leftFirst ? n.left + 1 : n.left;
        stack[size++] = leftFirst ? n.left : n.left + 1;
      } else if (left || right) {
        stack[size++] = left ? n.left : n.left + 1;
      }
    }
  }

  size_t bytes() const {
    return nodes_.capacity() * sizeof(Node) + items_.capacity() * sizeof(uint32_t);
  }

 private:
  static constexpr size_t kLeafItems = 4;
  struct Node {
    Box3f box;
    uint32_t left = 0;   // inner node: children at left and left + 1
    uint32_t first = 0;  // leaf: items_[first, first + count)
    uint32_t count = 0;  // 0: inner node
  };

  // Builds the subtree of items_[begin, end) into nodes_[index]; the two
  // children of a node are adjacent, made before either subtree.
  void buildNode(const std::vector<Box3f>& boxes, uint32_t index, size_t begin, size_t end) {
    Box3f box, centroids;
    for (size_t i = begin; i < end; ++i) {
      box.extend(boxes[items_[i]]);
      centroids.extend(boxes[items_[i]].center());
    }
    const float scale =
        std::max({std::abs(box.lower.x), std::abs(box.lower.y), std::abs(box.lower.z),
                  std::abs(box.upper.x), std::abs(box.upper.y), std::abs(box.upper.z), 1e-3f});
    const Vec3f pad(1e-5f * scale);
    nodes_[index].box = {box.lower - pad, box.upper + pad};
    if (end - begin <= kLeafItems) {
      nodes_[index].first = uint32_t(begin);
      nodes_[index].count = uint32_t(end - begin);
      return;
    }
    const int axis = centroids.longestAxis();
    const size_t middle = (begin + end) / 2;
    std::nth_element(items_.begin() + ptrdiff_t(begin), items_.begin() + ptrdiff_t(middle),
                     items_.begin() + ptrdiff_t(end), [&](uint32_t a, uint32_t b) {
                       return boxes[a].center()[axis] < boxes[b].center()[axis];
                     });
    const uint32_t left = uint32_t(nodes_.size());
    nodes_.resize(nodes_.size() + 2);
    nodes_[index].left = left;
    buildNode(boxes, left, begin, middle);
    buildNode(boxes, left + 1, middle, end);
  }

  std::vector<Node> nodes_;
  std::vector<uint32_t> items_;
};

// One candidate hit: a triangle the ray crosses, in double precision.
bool crossesTriangle(const Mesh& mesh, uint32_t primitive, Vec3d o, Vec3d d, double& t, double& u,
                     double& v) {
  const Vec3i& tri = mesh.indices[primitive];
  const Vec3d p0 = toDouble(mesh.positions[size_t(tri.x)]);
  const Vec3d e1 = toDouble(mesh.positions[size_t(tri.y)]) - p0;
  const Vec3d e2 = toDouble(mesh.positions[size_t(tri.z)]) - p0;
  const Vec3d pv = cross(d, e2);
  const double det = dot(e1, pv);
  if (det == 0 || !std::isfinite(det)) return false;
  const double inv = 1 / det;
  const Vec3d tv = o - p0;
  u = dot(tv, pv) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3d qv = cross(tv, e1);
  v = dot(d, qv) * inv;
  if (v < 0 || u + v > 1) return false;
  t = dot(e2, qv) * inv;
  return true;
}

// One object's triangles (every mesh slot with triangles) under one BVH, in
// the object's own space.
struct ObjectGeometry {
  struct Triangle {
    uint32_t slot, primitive;
  };
  std::vector<const Mesh*> meshes;   // by mesh slot
  std::vector<AlphaCutout> cutouts;  // by mesh slot (inactive: none)
  std::vector<const Shape*> shapes;  // by slot after the meshes' (null: released)
  std::vector<Triangle> triangles;   // the BVH's items: triangles, then shapes' primitives

  // Whether the ray crosses item `tri` at t in (tnear, tfar); the float ray
  // for shapes, the double one for triangles.
  bool crosses(Triangle tri, Vec3d o, Vec3d d, Vec3f origin, Vec3f direction, float tnear,
               double tfar, double& t, double& u, double& v) const {
    if (tri.slot < meshes.size())
      return crossesTriangle(*meshes[tri.slot], tri.primitive, o, d, t, u, v);
    float ft;
    Vec2f uv;
    if (!shapes[tri.slot - meshes.size()]->intersect(tri.primitive, origin, direction, tnear,
                                                     float(tfar), ft, uv))
      return false;
    t = ft;
    u = uv.x;
    v = uv.y;
    return true;
  }
  // Whether a path (or a shadow ray) whose alphaRayHash is `rayHash` passes
  // through item `tri` there; `toWorld`: the placement's transform (null:
  // the identity).
  bool isHole(Triangle tri, double u, double v, const Affine3f* toWorld, uint32_t rayHash,
              bool shadowRay) const {
    if (tri.slot >= cutouts.size()) return false;
    const AlphaCutout& c = cutouts[tri.slot];
    return (shadowRay ? c.cutsShadowRays() : c.cutsPaths()) &&
           c.isHole(tri.primitive, float(u), float(v), toWorld, rayHash);
  }
  Box3f bounds;
  Bvh bvh;
};

// An instance as placed here.
struct Placement {
  int32_t instance = 0;
  uint32_t object = 0;       // into ReferenceBackend::objects_
  bool transformed = false;  // else entered as is (the top level, or an identity transform)
  Affine3f toObject;         // world to object space
  Affine3f toWorld;          // object to world space
  const InstanceMotion* motion = nullptr;  // moving: its transform at the ray's time
  const Affine3f* transform() const { return transformed ? &toWorld : nullptr; }
};

class ReferenceBackend final : public TraceBackend {
 public:
  ReferenceBackend(const Scene& scene, std::span<const int32_t> ownedInstances,
                   Instancing instancing);

  TraceCounts trace(PathQueue<Path8>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  TraceCounts trace(PathQueue<Path64>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  TraceCounts trace(PathQueue<PathReplay>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  TraceCounts trace(PathQueue<PathProbe>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  // The recorded distance is a float rounded from this backend's double
  // one: searching to the next float up always reaches the recorded hit, and
  // nothing closer exists.
  void retrace(std::span<const RetraceRay> rays, std::span<TraceHit> hits) const override {
    FERRY_CHECK_EQ(rays.size(), hits.size());
    for (size_t i = 0; i < rays.size(); ++i)
      hits[i] = intersect({rays[i].origin, rays[i].direction, 0,
                           std::nextafter(rays[i].tmax, kInfinity), rays[i].time});
  }
  TraceHit intersect(const TraceRay& ray) const override;
  bool occluded(const TraceRay& ray) const override;
  Box3f bounds() const override { return bounds_; }
  BackendBytes bytes() const override;
  BuiltCounts built() const override {
    return {objects_.size(), placements_.size(), topLevelObjects_};
  }

 private:
  // The Batch of queue_trace.h: queries answered one by one.
  class Batch {
   public:
    static constexpr size_t kCapacity = 256;
    void clear() { closestCount_ = occludedCount_ = 0; }
    ShapeWork shapeWork() const { return {}; }  // (the reference counts no work)
    void addClosest(uint32_t index, Vec3f origin, Vec3f direction, float tmax, float time) {
      closestIndex_[closestCount_] = index;
      closest_[closestCount_++] = {origin, direction, 0, tmax, time};
    }
    void addOccluded(uint32_t index, Vec3f origin, Vec3f direction, float tmax, float time) {
      occludedIndex_[occludedCount_] = index;
      occluded_[occludedCount_++] = {origin, direction, 0, tmax, time};
    }
    size_t closestCount() const { return closestCount_; }
    size_t occludedCount() const { return occludedCount_; }
    uint32_t closestIndex(size_t k) const { return closestIndex_[k]; }
    uint32_t occludedIndex(size_t k) const { return occludedIndex_[k]; }
    bool hitFound(size_t k) const { return hits_[k].valid(); }
    float hitDistance(size_t k) const { return hits_[k].t; }
    TraceHit hit(size_t k) const { return hits_[k]; }
    bool isOccluded(size_t k) const { return blocked_[k]; }

    void answer(const ReferenceBackend& backend) {
      for (size_t k = 0; k < closestCount_; ++k) hits_[k] = backend.intersect(closest_[k]);
      for (size_t k = 0; k < occludedCount_; ++k) blocked_[k] = backend.occluded(occluded_[k]);
    }

   private:
    TraceRay closest_[kCapacity], occluded_[kCapacity];
    TraceHit hits_[kCapacity];
    bool blocked_[kCapacity];
    uint32_t closestIndex_[kCapacity], occludedIndex_[kCapacity];
    size_t closestCount_ = 0, occludedCount_ = 0;
  };

  template <typename Path>
  TraceCounts traceQueue(PathQueue<Path>& paths, int rank, std::span<const uint64_t> owners,
                         std::span<TraceHit> kept, const PathTimes& times) const {
    return traceQueueInBatches<Batch>(paths, rank, owners, kept, times,
                                      [this](Batch& batch) { batch.answer(*this); });
  }

  // Calls visit(placement, object-space origin, direction) for the placements
  // whose boxes the ray crosses before tfar; visit returns false to stop.
  template <typename Visit>
  void forPlacements(const TraceRay& ray, const float& tfar, const Visit& visit) const {
    instanceBvh_.traverse(boxRay(ray.origin, ray.direction, ray.tnear), tfar, [&](uint32_t p) {
      const Placement& placement = placements_[p];
      if (placement.motion) {
        const Affine3f toObject = placement.motion->at(ray.time).inverse();
        return visit(placement, toObject.transformPoint(ray.origin),
                     toObject.transformVector(ray.direction));
      }
      if (!placement.transformed) return visit(placement, ray.origin, ray.direction);
      return visit(placement, placement.toObject.transformPoint(ray.origin),
                   placement.toObject.transformVector(ray.direction));
    });
  }

  std::vector<ObjectGeometry> objects_;
  std::vector<Placement> placements_;
  Bvh instanceBvh_;  // over the placements' world boxes
  Box3f bounds_;
  uint64_t topLevelObjects_ = 0;
};

ReferenceBackend::ReferenceBackend(const Scene& scene, std::span<const int32_t> ownedInstances,
                                   Instancing instancing) {
  std::vector<int32_t> all;
  if (ownedInstances.empty()) {
    all.resize(scene.instances.size());
    std::iota(all.begin(), all.end(), 0);
    ownedInstances = all;
  }
  std::unordered_map<int32_t, int> placements;
  for (int32_t id : ownedInstances) ++placements[scene.instances[size_t(id)].object];

  std::unordered_map<int32_t, uint32_t> built;  // scene object -> objects_ index
  auto objectGeometry = [&](int32_t objectId) {
    auto [it, added] = built.try_emplace(objectId, uint32_t(objects_.size()));
    if (!added) return it->second;
    ObjectGeometry& g = objects_.emplace_back();
    const Object& object = scene.objects[size_t(objectId)];
    std::vector<Box3f> boxes;
    for (size_t slot = 0; slot < object.meshes.size(); ++slot) {
      const Mesh& mesh = scene.meshes[size_t(object.meshes[slot])];
      g.meshes.push_back(&mesh);
      g.cutouts.push_back(mesh.indices.empty() ? AlphaCutout{} : AlphaCutout::of(scene, mesh));
      for (uint32_t prim = 0; prim < mesh.indices.size(); ++prim) {
        const Vec3i& tri = mesh.indices[prim];
        Box3f b;
        b.extend(mesh.positions[size_t(tri.x)]);
        b.extend(mesh.positions[size_t(tri.y)]);
        b.extend(mesh.positions[size_t(tri.z)]);
        g.triangles.push_back({uint32_t(slot), prim});
        boxes.push_back(b);
        g.bounds.extend(b);
      }
    }
    for (size_t k = 0; k < object.geometries.size(); ++k) {
      const Shape* shape = scene.geometries[size_t(object.geometries[k])].shape.get();
      g.shapes.push_back(shape);
      if (!shape) continue;
      const uint32_t slot = uint32_t(object.meshes.size() + k);
      for (uint32_t prim = 0; prim < shape->primitiveCount(); ++prim) {
        g.triangles.push_back({slot, prim});
        boxes.push_back(shape->primitiveBounds(prim));
        g.bounds.extend(boxes.back());
      }
    }
    g.bvh.build(boxes);
    return it->second;
  };

  std::vector<Box3f> worldBoxes;
  for (int32_t id : ownedInstances) {
    const Instance& inst = scene.instances[size_t(id)];
    Placement p;
    p.instance = id;
    p.object = objectGeometry(inst.object);
    const bool topLevel = instancing == Instancing::Shared && placements[inst.object] == 1 &&
                          inst.transform.isIdentity() && !inst.motion;
    topLevelObjects_ += topLevel;
    p.transformed = !inst.transform.isIdentity();
    p.toObject = inst.transform.inverse();
    p.toWorld = inst.transform;
    p.motion = inst.motion.get();
    placements_.push_back(p);
    worldBoxes.push_back(inst.placeBox(objects_[p.object].bounds));
    bounds_.extend(worldBoxes.back());
  }
  instanceBvh_.build(worldBoxes);
}

TraceHit ReferenceBackend::intersect(const TraceRay& ray) const {
  TraceHit best;
  const uint32_t hash = alphaRayHash(ray.origin, ray.direction);
  double bestT = ray.tmax;  // accept t <= tmax, then only closer hits
  float prune = ray.tmax;   // bestT for the box tests (the boxes are padded)
  forPlacements(ray, prune, [&](const Placement& placement, Vec3f origin, Vec3f direction) {
    const ObjectGeometry& g = objects_[placement.object];
    const Vec3d o = toDouble(origin), d = toDouble(direction);
    g.bvh.traverse(boxRay(origin, direction, ray.tnear), prune, [&](uint32_t item) {
      const ObjectGeometry::Triangle tri = g.triangles[item];
      double t, u, v;
      if (!g.crosses(tri, o, d, origin, direction, ray.tnear, bestT, t, u, v)) return true;
      if (!(t > ray.tnear && (best.valid() ? t < bestT : t <= bestT))) return true;
      if (g.isHole(tri, u, v, placement.transform(), hash, false)) return true;
      bestT = t;
      prune = float(t);
      best = {float(t), placement.instance, int32_t(tri.slot), tri.primitive,
              float(u), float(v),           ray.time};
      return true;
    });
    return true;
  });
  return best;
}

bool ReferenceBackend::occluded(const TraceRay& ray) const {
  bool blocked = false;
  const uint32_t hash = alphaRayHash(ray.origin, ray.direction);
  const float tfar = ray.tmax;
  forPlacements(ray, tfar, [&](const Placement& placement, Vec3f origin, Vec3f direction) {
    const ObjectGeometry& g = objects_[placement.object];
    const Vec3d o = toDouble(origin), d = toDouble(direction);
    g.bvh.traverse(boxRay(origin, direction, ray.tnear), tfar, [&](uint32_t item) {
      const ObjectGeometry::Triangle tri = g.triangles[item];
      double t, u, v;
      if (!g.crosses(tri, o, d, origin, direction, ray.tnear, ray.tmax, t, u, v)) return true;
      if (!(t > ray.tnear && t <= ray.tmax)) return true;
      if (g.isHole(tri, u, v, placement.transform(), hash, true)) return true;
      blocked = true;
      return false;
    });
    return !blocked;
  });
  return blocked;
}

BackendBytes ReferenceBackend::bytes() const {
  size_t total = placements_.capacity() * sizeof(Placement) + instanceBvh_.bytes();
  for (const ObjectGeometry& g : objects_)
    total += g.bvh.bytes() + g.triangles.capacity() * sizeof(ObjectGeometry::Triangle);
  return {int64_t(total), int64_t(total)};
}

}  // namespace

std::unique_ptr<TraceBackend> makeReferenceBackend(const Scene& scene,
                                                   std::span<const int32_t> ownedInstances,
                                                   Instancing instancing) {
  return std::make_unique<ReferenceBackend>(scene, ownedInstances, instancing);
}

}  // namespace ferry
