// The proxy query that decides which rank generates a camera path
// (proxy-guided primaries, paper Section 3.3) and where a ray is forwarded:
// the closest proxy along a ray whose owners the ray has not visited. At 8
// ranks this query was 81 % of all stage time (issue 13), so it is measured
// here on its own, side by side with the binary ProxyBvh of 8896a05
// (`BaselineProxyBvh` below, kept only as this benchmark's baseline), in one
// run.
//
// Proxies: the island's 8-rank `best` partition (the default scale: about
// 78 K proxies), and the same proxies tiled 5 x 5 over the plane with the
// island's extent as pitch (about 2 M proxies, the size of the scale=30
// partition; a stand-in, since partitioning scale=30 itself needs 4.5 GB).
// Rays: the camera rays of the island's first view at 640x360, one per pixel
// centre, nothing excluded (the primary-ownership query); and the same rays
// with rank r excluded (a forwarding decision after a local trace on rank r,
// the rank that owns most of what the view sees).
// Each benchmark checks that every tree answers every query identically. A
// third tree, `OwnApart`, is the one rank r builds (ProxyBvh with its own
// proxies apart): for the ray sets with rank r excluded it never enters them.
// `EmbreeFaces` and `EmbreeFacesApart` ask Embree instead: the same boxes as
// triangles (issue 46's question, whether the query is cheaper folded into
// the local trace); they print how many answers differ and what Embree holds.
//
//   build/bench/proxy_query_bench                      (ratios printed at the end)
//   build/bench/proxy_query_bench --benchmark_repetitions=5
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/floating_point_mode.h"
#include "core/random.h"
#include "distributed/proxy_bvh.h"
#include "io/scene_loader.h"
#include "material/bsdf.h"
#include "partition/partitioner.h"
#include "render/camera.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"

namespace ferry {
namespace {

// The ProxyBvh of 8896a05, kept only as this benchmark's baseline: the same
// binned-SAH tree, binary, one box test at a time, children visited nearer
// first. (Before it, da05014's median split with children in a fixed order
// was 3.6-3.9x slower than this one: docs/data-parallel.md.)
class BaselineProxyBvh {
  // The next float above t >= 0, the smallest normal one above 0 (denormals read as 0).
  static float nextAbove(float t) {
    if (t == kInfinity) return t;
    if (t < std::numeric_limits<float>::min()) return std::numeric_limits<float>::min();
    return std::bit_cast<float>(std::bit_cast<uint32_t>(t) + 1u);
  }

 public:
  explicit BaselineProxyBvh(const std::vector<Proxy>& proxies) : proxies_(proxies) {
    for (const Proxy& p : proxies_) masks_.push_back(p.owners.mask());
    order_.resize(proxies_.size());
    for (size_t i = 0; i < order_.size(); ++i) order_[i] = int32_t(i);
    std::vector<Vec3f> centers;
    for (const Proxy& p : proxies_) centers.push_back(p.bounds.center());
    if (!proxies_.empty()) build(0, int32_t(proxies_.size()), 0, centers);
  }
  size_t nodeCount() const { return nodes_.size(); }
  ProxyBvh::Hit closest(Vec3f origin, Vec3f direction, float tmax, RankMask excluded) const {
    ProxyBvh::Hit best;
    const Vec3f inv{1 / direction.x, 1 / direction.y, 1 / direction.z};
    auto mayImprove = [&](float t, int32_t minIndex) {
      return t < best.tEnter || (t == best.tEnter && minIndex < best.proxy);
    };
    struct Entry {
      int32_t node;
      float t;
      int32_t minIndex;
    };
    Entry stack[128];
    int top = 0;
    float tRoot;
    if ((nodes_[0].owners & ~excluded) == 0 ||
        !intersectBox(nodes_[0].bounds, origin, inv, tmax, tRoot))
      return best;
    stack[top++] = {0, tRoot, nodes_[0].minIndex};
    while (top > 0) {
      const Entry e = stack[--top];
      if (!mayImprove(e.t, e.minIndex)) continue;
      const Node& node = nodes_[size_t(e.node)];
      if (node.left < 0) {
        for (int32_t i = node.first; i < node.first + node.count; ++i) {
          const int32_t id = order_[size_t(i)];
          if (masks_[size_t(id)] & excluded) continue;
          float t;
          if (!intersectBox(proxies_[size_t(id)].bounds, origin, inv, tmax, t)) continue;
          if (t < best.tEnter || (t == best.tEnter && id < best.proxy)) best = {id, t};
        }
        continue;
      }
      const float limit = std::min(tmax, nextAbove(best.tEnter));
      Entry near{-1, 0, 0}, far{-1, 0, 0};
      for (int32_t k : {node.left, node.right}) {
        const Node& child = nodes_[size_t(k)];
        float t;
        if ((child.owners & ~excluded) == 0 || !intersectBox(child.bounds, origin, inv, limit, t) ||
            !mayImprove(t, child.minIndex))
          continue;
        const Entry entry{k, t, child.minIndex};
        if (near.node < 0) {
          near = entry;
        } else if (entry.t < near.t || (entry.t == near.t && entry.minIndex < near.minIndex)) {
          far = near;
          near = entry;
        } else {
          far = entry;
        }
      }
      if (far.node >= 0) stack[top++] = far;
      if (near.node >= 0) stack[top++] = near;
    }
    return best;
  }

 private:
  struct Node {
    Box3f bounds;
    RankMask owners = 0;
    int32_t left = -1, right = -1, first = 0, count = 0, minIndex = 0;
  };
  int32_t build(int32_t first, int32_t count, int depth, const std::vector<Vec3f>& centers) {
    constexpr int kBins = 16;
    const int32_t index = int32_t(nodes_.size());
    nodes_.push_back({});
    Box3f bounds, centerBounds;
    RankMask owners = 0;
    int32_t minIndex = std::numeric_limits<int32_t>::max();
    for (int32_t i = first; i < first + count; ++i) {
      const int32_t id = order_[size_t(i)];
      bounds.extend(proxies_[size_t(id)].bounds);
      centerBounds.extend(centers[size_t(id)]);
      owners |= masks_[size_t(id)];
      minIndex = std::min(minIndex, id);
    }
    nodes_[size_t(index)].bounds = bounds;
    nodes_[size_t(index)].owners = owners;
    nodes_[size_t(index)].minIndex = minIndex;
    if (count <= 4 || depth > 60) {
      nodes_[size_t(index)].first = first;
      nodes_[size_t(index)].count = count;
      return index;
    }
    int bestAxis = -1, bestBin = 0;
    float bestCost = kInfinity;
    const Vec3f extent = centerBounds.size();
    auto binOf = [&](int axis, int32_t id) {
      const float f = (centers[size_t(id)][axis] - centerBounds.lower[axis]) / extent[axis];
      return std::clamp(int(f * kBins), 0, kBins - 1);
    };
    for (int axis = 0; axis < 3; ++axis) {
      if (!(extent[axis] > 0)) continue;
      Box3f binBounds[kBins];
      int binCount[kBins] = {};
      for (int32_t i = first; i < first + count; ++i) {
        const int b = binOf(axis, order_[size_t(i)]);
        binBounds[b].extend(proxies_[size_t(order_[size_t(i)])].bounds);
        ++binCount[b];
      }
      float rightArea[kBins];
      int rightCount[kBins];
      Box3f acc;
      int n = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.extend(binBounds[b]);
        n += binCount[b];
        rightArea[b] = acc.surfaceArea();
        rightCount[b] = n;
      }
      acc = Box3f{};
      n = 0;
      for (int b = 1; b < kBins; ++b) {
        acc.extend(binBounds[b - 1]);
        n += binCount[b - 1];
        if (n == 0 || rightCount[b] == 0) continue;
        const float cost = acc.surfaceArea() * float(n) + rightArea[b] * float(rightCount[b]);
        if (cost < bestCost) bestAxis = axis, bestBin = b, bestCost = cost;
      }
    }
    int32_t mid = first + count / 2;
    if (bestAxis >= 0)
      mid = int32_t(std::partition(order_.begin() + first, order_.begin() + first + count,
                                   [&](int32_t id) { return binOf(bestAxis, id) < bestBin; }) -
                    order_.begin());
    const int32_t left = build(first, mid - first, depth + 1, centers);
    const int32_t right = build(mid, first + count - mid, depth + 1, centers);
    nodes_[size_t(index)].left = left;
    nodes_[size_t(index)].right = right;
    return index;
  }
  const std::vector<Proxy>& proxies_;
  std::vector<RankMask> masks_;
  std::vector<int32_t> order_;
  std::vector<Node> nodes_;
};

// The same boxes as Embree triangles (12 a box), for issue 46's question:
// is the proxy query cheaper inside Embree's traversal, folded into the
// local trace? An intersection filter rejects the faces of boxes whose
// owners the ray has visited; the closest accepted face answers, entered at
// its distance, or at 0 when the origin lies inside its box (a back face).
// That is not always the tree's answer: a ray starting inside a box whose
// exit lies beyond tmax does not see it at all, and a nearer front face
// wins over the box around the origin. Both are counted (`differs`).
class EmbreeFaces {
 public:
  // With ownRank >= 0 the boxes that rank alone owns are left out, as
  // ProxyBvh keeps them apart for that rank's queries.
  explicit EmbreeFaces(const std::vector<Proxy>& proxies, int ownRank = -1) {
    device_ = rtcNewDevice(nullptr);
    rtcSetDeviceMemoryMonitorFunction(
        device_,
        [](void* self, ssize_t bytes, bool) {
          static_cast<EmbreeFaces*>(self)->bytes_ += bytes;
          return true;
        },
        this);
    for (const Proxy& p : proxies)
      if (ownRank < 0 || p.owners.mask() != (RankMask(1) << ownRank)) proxies_.push_back(p);
    for (const Proxy& p : proxies_) masks_.push_back(p.owners.mask());
    scene_ = rtcNewScene(device_);
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v =
        static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                    3 * sizeof(float), 8 * proxies_.size() + 1));
    auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), 12 * proxies_.size()));
    // Corner k has x from bit 0, y from bit 1, z from bit 2; two triangles a face.
    static const uint32_t kFaces[12][3] = {{0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3},
                                           {0, 4, 5}, {0, 5, 1}, {2, 3, 7}, {2, 7, 6},
                                           {0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}};
    for (size_t b = 0; b < proxies_.size(); ++b) {
      const Box3f& box = proxies_[b].bounds;
      for (uint32_t k = 0; k < 8; ++k) {
        v[3 * (8 * b + k) + 0] = (k & 1) ? box.upper.x : box.lower.x;
        v[3 * (8 * b + k) + 1] = (k & 2) ? box.upper.y : box.lower.y;
        v[3 * (8 * b + k) + 2] = (k & 4) ? box.upper.z : box.lower.z;
      }
      for (int f = 0; f < 12; ++f)
        for (int i = 0; i < 3; ++i)
          t[3 * (12 * b + size_t(f)) + size_t(i)] = uint32_t(8 * b) + kFaces[f][i];
    }
    rtcSetGeometryUserData(g, this);
    rtcSetGeometryIntersectFilterFunction(g, &EmbreeFaces::filter);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcCommitScene(scene_);
  }
  ~EmbreeFaces() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  ProxyBvh::Hit closest(Vec3f origin, Vec3f direction, float tmax, RankMask excluded) const {
    Context context;
    rtcInitIntersectContext(&context.embree);
    context.excluded = excluded;
    RTCRayHit rh;
    rh.ray.org_x = origin.x, rh.ray.org_y = origin.y, rh.ray.org_z = origin.z, rh.ray.tnear = 0;
    rh.ray.dir_x = direction.x, rh.ray.dir_y = direction.y, rh.ray.dir_z = direction.z;
    rh.ray.time = 0, rh.ray.tfar = tmax, rh.ray.mask = ~0u, rh.ray.id = 0, rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context.embree, &rh);
    ProxyBvh::Hit hit;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.proxy = int32_t(rh.hit.primID / 12);
    const Box3f& box = proxies_[size_t(hit.proxy)].bounds;
    hit.tEnter = box.contains(Box3f{origin, origin}) ? 0.0f : rh.ray.tfar;
    return hit;
  }
  size_t bytes() const { return bytes_; }

 private:
  struct Context {
    RTCIntersectContext embree;  // first: Embree hands the filter this pointer
    RankMask excluded = 0;
  };
  static void filter(const RTCFilterFunctionNArguments* args) {
    const auto* self = static_cast<const EmbreeFaces*>(args->geometryUserPtr);
    const auto* context = reinterpret_cast<const Context*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
      if (args->valid[i] == 0) continue;
      const uint32_t prim = RTCHitN_primID(args->hit, args->N, i);
      if (self->masks_[prim / 12] & context->excluded) args->valid[i] = 0;
    }
  }
  std::vector<Proxy> proxies_;
  std::vector<RankMask> masks_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  ssize_t bytes_ = 0;  // what Embree holds (its memory monitor)
};

// The image whose camera rays are queried (one per pixel centre).
constexpr int kWidth = 640, kHeight = 360;

struct Ray {
  Vec3f origin, direction;
  float tmax = kInfinity;
};

// The three kinds of query a rank makes, as ray sets:
//   0 camera:  camera rays, nothing excluded, no tmax (who owns a camera path);
//   1 to hit:  the same rays up to their hit in the whole scene, rank r
//              visited (the forwarding decision after a camera ray's trace);
//   2 bounce:  from each hit, a direction on the upper hemisphere (a diffuse
//              bounce off the ground) up to its own hit, rank r visited (the
//              decision after a continuation's trace);
//   3 own:     those of set 2 that start inside a proxy of rank r alone (a
//              bounce off rank r's own content: the decisions rank r makes
//              after tracing its continuations, where its own proxies crowd
//              around the origin).
constexpr int kRaySets = 4;
// r: the rank whose own proxies hold the most origins of set 2.

struct Case {
  std::vector<Proxy> proxies;
  std::vector<Ray> rays[kRaySets];
  std::unique_ptr<ProxyBvh> tree;
  // What rank r builds in the renderer (tiles 1 only): its own proxies apart,
  // and instanced proxies entered where their shapes' boxes are, not at
  // their world boxes (so its answers differ from the flattened trees').
  std::unique_ptr<ProxyBvh> instanced;
  int ownRank = 0;  // r
  RankMask excluded(int set) const { return set == 0 ? 0 : RankMask(1) << ownRank; }
  std::unique_ptr<BaselineProxyBvh> baseline;
  std::unique_ptr<EmbreeFaces> faces;
  std::unique_ptr<EmbreeFaces> facesApart;  // without rank r's own-only boxes
  // What rank r would ask for ray set `set` (set 0 excludes nothing: every box).
  const EmbreeFaces& facesFor(int set) const { return set == 0 ? *faces : *facesApart; }
  std::vector<std::unique_ptr<ProxyBvh>>
      splitOf;  // every rank's own proxies in a tree of their own
  const ProxyBvh& split() const { return *splitOf[size_t(ownRank)]; }  // rank r's
};

// The island's 8-rank best partition and its first view's rays.
const Case& islandCase(int tiles) {
  static std::map<int, std::unique_ptr<Case>> cases;
  auto& slot = cases[tiles];
  if (slot) return *slot;
  slot = std::make_unique<Case>();
  Case& c = *slot;
  Scene scene = loadScene("builtin:island");
  const CameraView view = scene.view("");
  PartitionerOptions options;
  options.partitioner = &bestPartitioner();
  Partition partition = partitionScene(scene, 8, options);
  Box3f extent;
  for (const Proxy& p : partition.proxies) extent.extend(p.bounds);
  const Vec3f pitch = extent.upper - extent.lower;
  for (int i = 0; i < tiles; ++i)
    for (int j = 0; j < tiles; ++j) {
      const Vec3f shift{float(i - tiles / 2) * pitch.x, 0, float(j - tiles / 2) * pitch.z};
      for (Proxy p : partition.proxies) {
        p.shape = -1;  // the tree of boxes is measured: an instanced proxy as its world box
        p.bounds.lower = p.bounds.lower + shift;
        p.bounds.upper = p.bounds.upper + shift;
        c.proxies.push_back(p);
      }
    }
  const std::unique_ptr<TraceBackend> geometry = makeEmbreeBackend(scene);
  Camera camera(view, kWidth, kHeight);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const Ray primary{camera.origin(), camera.direction(float(x) + 0.5f, float(y) + 0.5f)};
      c.rays[0].push_back(primary);
      const TraceHit hit = geometry->intersect({primary.origin, primary.direction});
      c.rays[1].push_back({primary.origin, primary.direction, hit.t});
      if (!hit.valid()) continue;
      const uint32_t pixel = uint32_t(y * kWidth + x);
      const Vec2f u{random01(RandomKey{pixel, 0, 0, 7}, RandomDim::OwnerPick),
                    random01(RandomKey{pixel, 1, 0, 7}, RandomDim::OwnerPick)};
      const Vec3f local = sampleCosineHemisphere(u);  // about +z; the island's up is +y
      const Vec3f dir{local.x, local.z, local.y};
      const Vec3f origin = primary.origin + primary.direction * (hit.t * (1 - 1e-4f));
      c.rays[2].push_back({origin, dir, geometry->intersect({origin, dir, 1e-3f}).t});
    }
  c.tree = std::make_unique<ProxyBvh>(c.proxies);
  // Set 3 and r: origins inside a box of rank r alone (entered at 0).
  auto ownedBy = [&](int rank) {
    std::vector<Ray> own;
    for (const Ray& r : c.rays[2])
      if (c.tree->closest(r.origin, r.direction, 1e-30f, ~(RankMask(1) << rank)).found())
        own.push_back(r);
    return own;
  };
  for (int rank = 0; rank < 8; ++rank) {
    std::vector<Ray> own = ownedBy(rank);
    if (own.size() > c.rays[3].size()) c.rays[3] = std::move(own), c.ownRank = rank;
  }
  for (int rank = 0; rank < 8; ++rank)
    c.splitOf.push_back(std::make_unique<ProxyBvh>(c.proxies, rank));
  if (tiles == 1)  // (the tiles above are copies: partition.proxies still has its shapes)
    c.instanced = std::make_unique<ProxyBvh>(std::move(partition.proxies), c.ownRank,
                                             std::move(partition.proxyShapes),
                                             std::move(partition.proxyPlacements));
  c.baseline = std::make_unique<BaselineProxyBvh>(c.proxies);
  c.faces = std::make_unique<EmbreeFaces>(c.proxies);
  c.facesApart = std::make_unique<EmbreeFaces>(c.proxies, c.ownRank);
  std::fprintf(stderr,
               "proxy_query_bench: Embree faces hold %.1f MiB (rank r's: %.1f MiB), ProxyBvh "
               "%.1f MiB (rank r's: %.1f MiB)\n",
               double(c.faces->bytes()) / 1048576, double(c.facesApart->bytes()) / 1048576,
               double(c.tree->bytes()) / 1048576, double(c.split().bytes()) / 1048576);
  for (int set = 0; set < kRaySets; ++set) {
    size_t differs = 0, missed = 0;
    const EmbreeFaces& faces = c.facesFor(set);
    for (const Ray& r : c.rays[set]) {
      const ProxyBvh::Hit a = c.tree->closest(r.origin, r.direction, r.tmax, c.excluded(set));
      const ProxyBvh::Hit f = faces.closest(r.origin, r.direction, r.tmax, c.excluded(set));
      if (a.found() != f.found())
        ++missed;
      else if (a.found() && std::abs(a.tEnter - f.tEnter) > 1e-4f * std::max(1.0f, a.tEnter))
        ++differs;
    }
    std::fprintf(stderr,
                 "proxy_query_bench: Embree faces, set %d: %zu of %zu rays found/not found "
                 "otherwise than the tree, %zu entered elsewhere\n",
                 set, missed, c.rays[set].size(), differs);
  }

  for (int set = 0; set < kRaySets; ++set)
    for (const Ray& r : c.rays[set]) {
      ProxyBvh::Hit a = c.tree->closest(r.origin, r.direction, r.tmax, c.excluded(set));
      ProxyBvh::Hit b = c.baseline->closest(r.origin, r.direction, r.tmax, c.excluded(set));
      ProxyBvh::Hit s = c.split().closest(r.origin, r.direction, r.tmax, c.excluded(set));
      if (a.proxy != b.proxy || a.tEnter != b.tEnter || s.proxy != a.proxy) {
        std::fprintf(
            stderr,
            "proxy_query_bench: the trees disagree (%d at %.9g vs %d at %.9g), set %d, tmax %.9g\n",
            a.proxy, a.tEnter, b.proxy, b.tEnter, set, r.tmax);
        std::abort();
      }
    }
  std::fprintf(stderr,
               "proxy_query_bench: %zu proxies, %zu + %zu + %zu + %zu rays, %zu binary nodes, %zu "
               "%d-wide nodes; rank r = %d (%zu own-only proxies)\n",
               c.proxies.size(), c.rays[0].size(), c.rays[1].size(), c.rays[2].size(),
               c.rays[3].size(), c.baseline->nodeCount(), c.tree->nodeCount(), ProxyBvh::kWidth,
               c.ownRank, c.split().ownOnlyCount());
  return c;
}

// The trees measured: the baseline, ProxyBvh, ProxyBvh with rank r's own
// proxies apart (what rank r builds: its decisions exclude rank r), the
// boxes as Embree triangles, and rank r's tree with instanced proxies.
enum class Tree { Baseline, Wide, Split, Faces, FacesApart, Instanced };

template <Tree kTree>
void BM_Query(benchmark::State& state) {
  const Case& c = islandCase(int(state.range(0)));
  const int set = int(state.range(1));
  const std::vector<Ray>& rays = c.rays[set];
  if (kTree == Tree::Instanced && !c.instanced) {
    state.SkipWithError("instanced proxies: one tile only");
    return;
  }
  int64_t found = 0;
  for (auto _ : state) {
    for (const Ray& r : rays) {
      ProxyBvh::Hit h;
      if constexpr (kTree == Tree::Baseline)
        h = c.baseline->closest(r.origin, r.direction, r.tmax, c.excluded(set));
      else if constexpr (kTree == Tree::Faces)
        h = c.faces->closest(r.origin, r.direction, r.tmax, c.excluded(set));
      else if constexpr (kTree == Tree::FacesApart)
        h = c.facesFor(set).closest(r.origin, r.direction, r.tmax, c.excluded(set));
      else if constexpr (kTree == Tree::Instanced)
        h = c.instanced->closest(r.origin, r.direction, r.tmax, c.excluded(set));
      else
        h = (kTree == Tree::Wide ? *c.tree : c.split())
                .closest(r.origin, r.direction, r.tmax, c.excluded(set));
      found += h.found();
    }
  }
  benchmark::DoNotOptimize(found);
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(rays.size()));
  state.counters["us_per_query"] =
      benchmark::Counter(double(state.iterations()) * double(rays.size()) * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// Args: tiles (1: the island's proxies, 5: 25 times as many), ray set (0 camera, 1 to hit, 2
// bounce, 3 bounce off rank r's own content); the same cases for every tree.
void everyCase(benchmark::internal::Benchmark* b) {
  b->Args({1, 0})->Args({1, 1})->Args({1, 2})->Args({1, 3})->Args({5, 0})->Args({5, 2});
  b->Unit(benchmark::kMillisecond);
}
BENCHMARK_TEMPLATE(BM_Query, Tree::Baseline)->Name("Baseline")->Apply(everyCase);
BENCHMARK_TEMPLATE(BM_Query, Tree::Wide)->Name("ProxyBvh")->Apply(everyCase);
BENCHMARK_TEMPLATE(BM_Query, Tree::Split)->Name("OwnApart")->Apply(everyCase);
BENCHMARK_TEMPLATE(BM_Query, Tree::Faces)->Name("EmbreeFaces")->Apply(everyCase);
BENCHMARK_TEMPLATE(BM_Query, Tree::FacesApart)->Name("EmbreeFacesApart")->Apply(everyCase);
BENCHMARK_TEMPLATE(BM_Query, Tree::Instanced)
    ->Name("Instanced")
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Args({1, 3})
    ->Unit(benchmark::kMillisecond);

// The same ray set on every rank of the 8, each excluding itself (set 0:
// nothing), with one tree (ProxyBvh) or each rank's split tree: the average
// cost over the ranks, whose own proxies lie in the view or do not.
template <bool kSplit>
void BM_EveryRank(benchmark::State& state) {
  const Case& c = islandCase(int(state.range(0)));
  const int set = int(state.range(1));
  const std::vector<Ray>& rays = c.rays[set];
  int64_t found = 0;
  for (auto _ : state)
    for (int rank = 0; rank < 8; ++rank) {
      const ProxyBvh& tree = kSplit ? *c.splitOf[size_t(rank)] : *c.tree;
      const RankMask excluded = set == 0 ? 0 : RankMask(1) << rank;
      for (const Ray& r : rays)
        found += tree.closest(r.origin, r.direction, r.tmax, excluded).found();
    }
  benchmark::DoNotOptimize(found);
  state.counters["us_per_query"] =
      benchmark::Counter(double(state.iterations()) * 8.0 * double(rays.size()) * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK_TEMPLATE(BM_EveryRank, false)
    ->Name("ProxyBvhEveryRank")
    ->Args({1, 0})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_EveryRank, true)
    ->Name("OwnApartEveryRank")
    ->Args({1, 0})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond);

// Prints the time per query of each tree for each case, and the ratios.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.run_type != Run::RT_Iteration) continue;
      std::string name = run.benchmark_name();
      // CPU time per query, in microseconds (this machine is shared: CPU
      // time is steadier than wall time; the counter is a rate over CPU time).
      perQuery_[name.substr(name.find('/'))][name.substr(0, name.find('/'))] =
          double(run.counters.at("us_per_query"));
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf(
        "\nCPU time per query (args: tiles/ray set); Baseline, ProxyBvh,  OwnApart (rank r's own "
        "proxies apart):\n");
    for (const auto& [args, trees] : perQuery_) {
      auto at = [&trees = trees](const char* tree) {
        return trees.count(tree) ? trees.at(tree) : 0.0;
      };
      const double base = at("Baseline"), wide = at("ProxyBvh"), split = at("OwnApart");
      std::printf(
          "  %-8s %.3f us  %.3f us  %.3f us   ProxyBvh %.2fx faster than Baseline, "
          "OwnApart %.2fx faster than ProxyBvh\n",
          args.c_str(), base, wide, split, wide > 0 ? base / wide : 0.0,
          split > 0 ? wide / split : 0.0);
    }
    // Two trees side by side, for every case that ran both: b's time over a's.
    auto pair = [&](const char* title, const char* a, const char* b, const char* ratio) {
      std::printf("\n%s; %s, %s:\n", title, a, b);
      for (const auto& [args, trees] : perQuery_)
        if (trees.count(a) && trees.count(b))
          std::printf("  %-8s %.3f us  %.3f us   %s %.2fx\n", args.c_str(), trees.at(a),
                      trees.at(b), ratio, trees.at(b) / trees.at(a));
    };
    pair(
        "The same boxes as Embree triangles (issue 46: the query folded into the local trace?; "
        "rank r's own-only boxes left out)",
        "OwnApart", "EmbreeFacesApart", "Embree's time:");
    pair(
        "Rank r's tree as the renderer builds it (instanced proxies entered at their shapes' "
        "boxes)",
        "OwnApart", "Instanced", "Instanced's time:");
    pair("Every rank of the 8, each excluding itself (set 0: nothing)", "ProxyBvhEveryRank",
         "OwnApartEveryRank", "OwnApart's time:");
  }

 private:
  std::map<std::string, std::map<std::string, double>> perQuery_;
};

}  // namespace
}  // namespace ferry

int main(int argc, char** argv) {
  ferry::useFixedFloatingPointMode();  // as ferry runs
  benchmark::Initialize(&argc, argv);
  ferry::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
}
