// The two trace backends agree ray by ray: the Embree backend (what `ferry`
// renders with) against the plain C++ reference (double-precision triangle
// tests, median-split BVHs), on camera rays and random rays, closest hits and
// occlusion, through instances and alpha cut-outs, in both instancing modes,
// on the built-in Cornell box, a small island and the low-resolution bunny.
//
// Agreement: the same hit or miss, naming the same (instance, mesh slot,
// triangle), with t within a relative tolerance; for shadow rays, the same
// occlusion. Two correct intersectors may still differ where a ray grazes an
// edge (Embree's float test against a double one; two float instance
// inverses) or a cut-out's alpha contour. Such a disagreement is tolerated
// only when the ray passes within epsilon (1e-5 of the scene's largest
// coordinate) of one: when either backend's hit point lies within epsilon of
// an edge of its triangle (its barycentrics times the triangle's altitudes),
// or, for cut-outs and occlusion, when Embree's answer is what the reference
// answers for the ray's origin moved by epsilon along +-x, +-y or +-z. A
// different distance on the same triangle is never tolerated; every other
// disagreement is a failure, and the tolerated ones must stay below 0.2 % of
// the rays. Also right either way: a face listed twice (the low-resolution
// bunny has some, in either winding), hit by both backends at the same t. A self-test shifts one
// vertex by 1e-3 of the scene's size under the reference only and checks that
// the comparison then fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "builtin/builtin.h"
#include "core/random.h"
#include "io/scene_loader.h"
#include "path/path.h"
#include "render/camera.h"
#include "render/frame_buffer.h"
#include "render/lights.h"
#include "render/ray_traversal.h"
#include "render/render_test_util.h"
#include "render/wavefront_renderer.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"
#include "trace/reference_backend.h"

namespace ferry {
namespace {

float uniform(uint32_t i, uint32_t d) {
  return random01(RandomKey{i, 0, 0, 23}, RandomDim(d % 8));
}

float largestCoordinate(const Box3f& b) {
  return std::max({std::abs(b.lower.x), std::abs(b.lower.y), std::abs(b.lower.z),
                   std::abs(b.upper.x), std::abs(b.upper.y), std::abs(b.upper.z)});
}

// Camera rays through pixel centres, then rays from random points of the
// (slightly grown) bounds in random directions, a third of them with a finite tmax.
std::vector<TraceRay> testRays(const Scene& scene, const Box3f& bounds, int width, int height,
                               size_t randomCount) {
  std::vector<TraceRay> rays;
  if (!scene.views.empty()) {
    Camera camera(scene.view(""), width, height);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        rays.push_back({camera.origin(), camera.direction(float(x) + 0.5f, float(y) + 0.5f)});
  }
  const Vec3f grow = bounds.size() * 0.1f;
  const Box3f b{bounds.lower - grow, bounds.upper + grow};
  for (uint32_t i = 0; i < randomCount; ++i) {
    Vec3f o{b.lower.x + (b.upper.x - b.lower.x) * uniform(i, 0),
            b.lower.y + (b.upper.y - b.lower.y) * uniform(i, 1),
            b.lower.z + (b.upper.z - b.lower.z) * uniform(i, 2)};
    Vec3f d = normalize(Vec3f(uniform(i, 3), uniform(i, 4), uniform(i, 5)) - Vec3f(0.5f));
    rays.push_back({o, d, 0, i % 3 == 0 ? 0.3f * length(b.upper - b.lower) : kInfinity});
  }
  return rays;
}

PathQueue<Path8> asPaths(const std::vector<TraceRay>& rays, bool shadow) {
  PathQueue<Path8> paths(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    Path8& p = paths[i];
    p.origin = rays[i].origin;
    p.setDirAndWeight(rays[i].direction, Vec3f(1));
    p.tmax = rays[i].tmax;
    p.setPixelAndFlags(uint32_t(i), shadow ? uint32_t(kPathShadow) : 0u);
    p.clearHistory();
  }
  return paths;
}

bool sameTriangle(const TraceHit& a, const TraceHit& b) {
  return a.valid() == b.valid() && (!a.valid() || (a.instance == b.instance && a.slot == b.slot &&
                                                   a.primitive == b.primitive));
}

struct Agreement {
  size_t rays = 0;
  size_t agreedHits = 0;      // closest: same triangle, t within tolerance
  size_t agreedMisses = 0;    // closest: both miss
  size_t agreedOccluded = 0;  // shadow rays both found occluded
  size_t onInstances = 0;     // of the same hits, through a transformed instance
  size_t onCutouts = 0;       // of the same hits, on an alpha-tested material
  size_t tolerated = 0;       // disagreements on rays within epsilon of an edge
  size_t coincident = 0;      // different triangles with the same corners, at the same t
  size_t failed = 0;          // any other disagreement
  double largestRelativeT = 0;
  std::vector<std::string> examples;  // the first few failures, described

  void fail(std::string what) {
    ++failed;
    if (examples.size() < 5) examples.push_back(std::move(what));
  }
};

std::string describe(const TraceHit& h) {
  if (!h.valid()) return "miss";
  return fmt::format("instance {} slot {} triangle {} t {}", h.instance, h.slot, h.primitive, h.t);
}

// Whether the two hits name triangles with the same three corners (a face
// listed twice, in either winding): either is the right answer.
bool coincident(const Scene& scene, const TraceHit& a, const TraceHit& b) {
  if (!a.valid() || !b.valid() || a.instance != b.instance || a.slot != b.slot) return false;
  const Instance& inst = scene.instances[size_t(a.instance)];
  const Mesh& mesh =
      scene.meshes[size_t(scene.objects[size_t(inst.object)].meshes[size_t(a.slot)])];
  const Vec3i& p = mesh.indices[a.primitive];
  const Vec3i& q = mesh.indices[b.primitive];
  auto corner = [&](int32_t i) { return mesh.positions[size_t(i)]; };
  auto has = [&](Vec3f c) { return corner(q.x) == c || corner(q.y) == c || corner(q.z) == c; };
  return has(corner(p.x)) && has(corner(p.y)) && has(corner(p.z));
}

// Whether `hit` lies within `epsilon` (world units) of an edge of its triangle.
bool nearAnEdge(const Scene& scene, const TraceHit& hit, float epsilon) {
  if (!hit.valid()) return false;
  const Instance& inst = scene.instances[size_t(hit.instance)];
  const Mesh& mesh =
      scene.meshes[size_t(scene.objects[size_t(inst.object)].meshes[size_t(hit.slot)])];
  const Vec3i& tri = mesh.indices[hit.primitive];
  const Vec3f p[3] = {inst.transform.transformPoint(mesh.positions[size_t(tri.x)]),
                      inst.transform.transformPoint(mesh.positions[size_t(tri.y)]),
                      inst.transform.transformPoint(mesh.positions[size_t(tri.z)])};
  const float twiceArea = length(cross(p[1] - p[0], p[2] - p[0]));
  const float barycentric[3] = {1 - hit.u - hit.v, hit.u, hit.v};
  for (int k = 0; k < 3; ++k) {
    // The distance to the edge opposite vertex k: its barycentric times the altitude.
    const float edge = length(p[(k + 2) % 3] - p[(k + 1) % 3]);
    if (edge > 0 && barycentric[k] * twiceArea / edge <= epsilon) return true;
  }
  return false;
}

// Traces `rays` through both backends as the renderer does (the wavefront
// trace, closest hits kept; shadow rays) and compares them ray by ray (see
// the top of this file). `scene` is the reference's.
Agreement compare(const Scene& scene, const TraceBackend& embree, const TraceBackend& reference,
                  const std::vector<TraceRay>& rays, float sceneScale) {
  PathQueue<Path8> pathsE = asPaths(rays, false), pathsR = pathsE;
  PathQueue<Path8> shadowsE = asPaths(rays, true), shadowsR = shadowsE;
  std::vector<TraceHit> hitsE(rays.size()), hitsR(rays.size());
  embree.trace(pathsE, 0, {}, hitsE);
  reference.trace(pathsR, 0, {}, hitsR);
  embree.trace(shadowsE, 0, {});
  reference.trace(shadowsR, 0, {});

  const float epsilon = 1e-5f * sceneScale;
  auto nearby = [&](const TraceRay& ray, int k) {
    TraceRay moved = ray;
    moved.origin[k / 2] += k % 2 ? epsilon : -epsilon;
    return moved;
  };
  Agreement a;
  a.rays = rays.size();
  for (size_t i = 0; i < rays.size(); ++i) {
    // The ray as traced (its direction quantized in the path).
    const TraceRay ray{pathsE[i].origin, pathsE[i].dir(), 0, rays[i].tmax};
    const TraceHit& e = hitsE[i];
    const TraceHit& r = hitsR[i];
    if (sameTriangle(e, r)) {
      if (!e.valid()) {
        ++a.agreedMisses;
      } else {
        // Embree's float error scales with the coordinates as well as with t.
        const double difference = std::abs(double(e.t) - double(r.t));
        a.largestRelativeT = std::max(a.largestRelativeT, difference / (r.t + sceneScale));
        if (difference <= 1e-5 * (r.t + sceneScale)) {
          ++a.agreedHits;
          const Instance& inst = scene.instances[size_t(r.instance)];
          const int32_t mesh = scene.objects[size_t(inst.object)].meshes[size_t(r.slot)];
          a.onInstances += !inst.transform.isIdentity();
          a.onCutouts +=
              scene.materials[size_t(scene.meshes[size_t(mesh)].material)].alphaTexture !=
              kNoTexture;
        } else {  // no edge explains another distance on the same triangle
          a.fail(fmt::format("closest hit of ray {}: Embree {}, reference {}", i, describe(e),
                             describe(r)));
        }
      }
    } else if (coincident(scene, e, r) &&
               std::abs(double(e.t) - double(r.t)) <= 1e-5 * (r.t + sceneScale)) {
      ++a.coincident;
    } else {
      bool explained = nearAnEdge(scene, e, epsilon) || nearAnEdge(scene, r, epsilon);
      for (int k = 0; k < 6 && !explained; ++k)
        explained = sameTriangle(e, reference.intersect(nearby(ray, k)));
      if (explained)
        ++a.tolerated;
      else
        a.fail(fmt::format("closest hit of ray {}: Embree {}, reference {}", i, describe(e),
                           describe(r)));
    }
    const bool occludedE = shadowsE[i].has(kPathOccluded);
    if (occludedE == shadowsR[i].has(kPathOccluded)) {
      a.agreedOccluded += occludedE;
      continue;
    }
    bool explained = false;
    for (int k = 0; k < 6 && !explained; ++k)
      explained = reference.occluded(nearby(ray, k)) == occludedE;
    if (explained)
      ++a.tolerated;
    else
      a.fail(fmt::format("occlusion of ray {}: Embree {}, reference {}", i, occludedE, !occludedE));
  }
  return a;
}

// `expectedHits` same hits at least, of which `expectedSpecial` through
// instances and as many on cut-outs.
void expectAgreement(const std::string& name, const Scene& scene, int width, int height,
                     size_t randomCount, size_t expectedHits, size_t expectedSpecial = 0) {
  for (Instancing instancing : {Instancing::Shared, Instancing::Always}) {
    const std::unique_ptr<TraceBackend> embree = makeEmbreeBackend(scene, {}, instancing);
    const std::unique_ptr<TraceBackend> reference = makeReferenceBackend(scene, {}, instancing);
    const BuiltCounts e = embree->built(), r = reference->built();
    EXPECT_EQ(e.objects, r.objects) << name;
    EXPECT_EQ(e.instances, r.instances) << name;
    EXPECT_EQ(e.topLevelObjects, r.topLevelObjects) << name;
    const Box3f bounds = reference->bounds();
    // Embree's bounds come from its BVH (instances: a transformed BVH box):
    // they hold the geometry, and the reference's boxes hold it exactly.
    EXPECT_TRUE(embree->bounds().contains(scene.worldBounds())) << name;
    EXPECT_TRUE(bounds.contains(scene.worldBounds())) << name;

    const float scale = largestCoordinate(bounds);
    const std::vector<TraceRay> rays = testRays(scene, bounds, width, height, randomCount);
    const Agreement a = compare(scene, *embree, *reference, rays, scale);
    std::printf(
        "  %-22s %-6s %6zu rays: %6zu same hits (%zu through instances, %zu on cut-outs), %5zu "
        "same misses, %5zu both occluded, "
        "%zu tolerated near an edge, %zu ties on coincident triangles, %zu failed; largest t "
        "difference %.2g of (t + scale)\n",
        name.c_str(), instancing == Instancing::Shared ? "shared" : "always", a.rays, a.agreedHits,
        a.onInstances, a.onCutouts, a.agreedMisses, a.agreedOccluded, a.tolerated, a.coincident,
        a.failed, a.largestRelativeT);
    EXPECT_EQ(a.failed, 0u) << name << ", e.g. " << fmt::format("{}", fmt::join(a.examples, "; "));
    EXPECT_LE(a.tolerated, a.rays / 500) << name;
    EXPECT_GE(a.agreedHits, expectedHits) << name;
    EXPECT_GE(a.agreedOccluded, expectedHits / 2) << name;
    EXPECT_GE(a.onInstances, expectedSpecial) << name;
    EXPECT_GE(a.onCutouts, expectedSpecial) << name;
  }
}

TEST(TraceBackendCrossCheck, EmbreeAndReferenceAgreeOnTheCornellBox) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  expectAgreement("cornell", scene, 64, 64, 4000, 5000);
}

TEST(TraceBackendCrossCheck, EmbreeAndReferenceAgreeOnASmallIsland) {
  // Instanced plants with alpha-tested leaves, terrain and water at the top level.
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.02"));
  size_t cutouts = 0;
  for (const Material& m : scene.materials) cutouts += m.alphaTexture != kNoTexture;
  ASSERT_GT(cutouts, 0u);
  ASSERT_LT(scene.objects.size(), scene.instances.size());
  expectAgreement("island?scale=0.02", scene, 64, 36, 4000, 2000, 50);
}

TEST(TraceBackendCrossCheck, EmbreeAndReferenceAgreeOnTheBunny) {
  const std::filesystem::path path =
      std::filesystem::path(FERRY_SHARED_SCENES) / "stanford-bunny" / "bun_zipper_res4.ply";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is not available";
  Scene scene = loadScene(path.string());
  expectAgreement("bun_zipper_res4", scene, 48, 48, 4000, 500);
}

// The comparison can fail: one vertex moved by 1e-3 of the Cornell box's size
// under the reference only (the most-hit triangle's first vertex, along its
// normal) must show as failed rays.
TEST(TraceBackendCrossCheck, AShiftedVertexIsCaught) {
  const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  const std::unique_ptr<TraceBackend> embree = makeEmbreeBackend(scene);
  const Box3f bounds = embree->bounds();
  const std::vector<TraceRay> rays = testRays(scene, bounds, 64, 64, 0);
  PathQueue<Path8> paths = asPaths(rays, false);
  std::vector<TraceHit> hits(rays.size());
  embree->trace(paths, 0, {}, hits);
  std::map<std::tuple<int32_t, int32_t, uint32_t>, int> counts;
  for (const TraceHit& h : hits)
    if (h.valid()) ++counts[{h.instance, h.slot, h.primitive}];
  ASSERT_FALSE(counts.empty());
  const auto [instance, slot, primitive] =
      std::max_element(counts.begin(), counts.end(), [](const auto& a, const auto& b) {
        return a.second < b.second;
      })->first;

  Scene shifted = scene;
  Mesh& mesh = shifted.meshes[size_t(
      shifted.objects[size_t(shifted.instances[size_t(instance)].object)].meshes[size_t(slot)])];
  const Vec3i tri = mesh.indices[primitive];
  const Vec3f normal =
      normalize(cross(mesh.positions[size_t(tri.y)] - mesh.positions[size_t(tri.x)],
                      mesh.positions[size_t(tri.z)] - mesh.positions[size_t(tri.x)]));
  mesh.positions[size_t(tri.x)] =
      mesh.positions[size_t(tri.x)] + normal * (1e-3f * length(bounds.upper - bounds.lower));
  const std::unique_ptr<TraceBackend> reference = makeReferenceBackend(shifted);
  const Agreement unshifted =
      compare(scene, *embree, *makeReferenceBackend(scene), rays, largestCoordinate(bounds));
  EXPECT_EQ(unshifted.failed, 0u);
  const Agreement a = compare(shifted, *embree, *reference, rays, largestCoordinate(bounds));
  EXPECT_GT(a.failed, 20u) << "a vertex moved by 1e-3 of the scene went unnoticed";
}

// The seam: the renderer runs on either backend unchanged (traversal and
// shading's re-traces, --retrace all so the re-trace runs on one rank too),
// and as the two agree ray by ray, so do the images: the same random
// numbers, surfaces a float rounding apart, paths that part only where a ray
// grazes an edge.
std::vector<Vec3f> renderCornell(TraceBackend& backend, const Scene& scene) {
  RenderSettings settings;
  settings.width = 40;
  settings.height = 40;
  settings.samplesPerPixel = 4;
  settings.retraceAll = true;
  LightSampler lights(scene);
  LocalTraversal<Path8> traversal(backend);
  WavefrontRenderer<Path8> renderer(scene, backend, lights, traversal, settings);
  FrameBuffer frame(settings.width, settings.height);
  const FrameStats stats = renderer.renderFrame(0, frame);
  EXPECT_GT(stats.retraces, 0u);
  EXPECT_EQ(stats.retraceMisses, 0u);
  return frame.sum();
}

TEST(TraceBackendCrossCheck, TheRendererRunsOnEitherBackend) {
  const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  const std::vector<Vec3f> e = renderCornell(*makeEmbreeBackend(scene), scene);
  const std::vector<Vec3f> r = renderCornell(*makeReferenceBackend(scene), scene);
  ASSERT_EQ(e.size(), r.size());
  double sumE = 0, sumR = 0;
  size_t close = 0;
  for (size_t i = 0; i < e.size(); ++i) {
    const double le = e[i].x + e[i].y + e[i].z, lr = r[i].x + r[i].y + r[i].z;
    sumE += le;
    sumR += lr;
    close += std::abs(le - lr) <= 1e-3 * std::max(le, 1e-3);
  }
  std::printf("  image sum reference / Embree %.6f, %zu of %zu pixels within 0.1 %%\n", sumR / sumE,
              close, e.size());
  EXPECT_GT(sumE, 0);
  EXPECT_NEAR(sumR / sumE, 1.0, 0.01);
  EXPECT_GE(close, e.size() * 9 / 10) << "pixels within 0.1 %";
}

// The wavefront trace's bookkeeping, the same in every layout and backend:
// the mask layouts record the hit content's owners from the table, the
// replay layout the rank that found it; paths are marked traced; a shadow
// ray already occluded elsewhere is not traced again (nor counted).
template <typename Path>
void checkQueueBookkeeping(const TraceBackend& backend, const Scene& scene) {
  const std::vector<TraceRay> rays = testRays(scene, backend.bounds(), 16, 16, 0);
  PathQueue<Path> paths(rays.size() * 2);
  for (size_t i = 0; i < paths.size(); ++i) {
    Path& p = paths[i];
    const TraceRay& r = rays[i / 2];
    p.origin = r.origin;
    p.setDirAndWeight(r.direction, Vec3f(1));
    p.tmax = r.tmax;
    // Every other path a shadow ray, every fourth of those already occluded.
    uint32_t flags = i % 2 ? uint32_t(kPathShadow) : 0u;
    if (i % 8 == 1) flags |= kPathOccluded;
    p.setPixelAndFlags(uint32_t(i), flags);
    p.clearHistory();
  }
  std::vector<uint64_t> owners(scene.instances.size());
  for (size_t k = 0; k < owners.size(); ++k) owners[k] = (uint64_t(1) << (k % 5)) | 0x40u;
  std::vector<TraceHit> kept(paths.size());
  const int rank = 3;
  const TraceCounts counts = backend.trace(paths, rank, owners, kept);
  EXPECT_EQ(counts.closest, rays.size());
  EXPECT_EQ(counts.occlusion, rays.size() - (rays.size() + 3) / 4);
  size_t hits = 0;
  for (size_t i = 0; i < paths.size(); ++i) {
    const Path& p = paths[i];
    if constexpr (Path::kReplay) {
      EXPECT_EQ(p.generatingRank, rank);
    } else {
      EXPECT_EQ(p.visited, typename Path::Mask(1u << rank));
    }
    if (p.isShadow()) {
      EXPECT_FALSE(kept[i].valid());
      continue;
    }
    EXPECT_EQ(kept[i].valid(), p.hasHit());
    if (!kept[i].valid()) continue;
    ++hits;
    EXPECT_EQ(p.tmax, kept[i].t);
    if constexpr (Path::kReplay) {
      EXPECT_EQ(p.hitRank, rank);
    } else {
      EXPECT_EQ(uint64_t(p.hitOwners), owners[size_t(kept[i].instance)]);
    }
  }
  EXPECT_GT(hits, rays.size() / 2);
}

TEST(TraceBackendQueue, BookkeepingIsTheSameInEveryLayoutAndBackend) {
  const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  for (auto make : {makeEmbreeBackend, makeReferenceBackend}) {
    const std::unique_ptr<TraceBackend> backend = make(scene, {}, Instancing::Shared);
    checkQueueBookkeeping<Path8>(*backend, scene);
    checkQueueBookkeeping<Path64>(*backend, scene);
    checkQueueBookkeeping<PathReplay>(*backend, scene);
  }
}

}  // namespace
}  // namespace ferry

namespace ferry {
namespace {

// Moving instances (turning, stretching, sliding) hit alike in both
// backends at each ray's own time; the same rays at time 0 and 1 find the
// start and end poses.
TEST(TraceBackendCrossCheck, EmbreeAndReferenceAgreeOnMovingInstances) {
  Scene scene;
  scene.addMaterial(Material{});
  Mesh box = testing::makeQuad({-1, -0.3f, 0}, {2, 0, 0}, {0, 0.6f, 0}, 0);
  const Mesh back = testing::makeQuad({-1, -0.3f, -0.3f}, {0, 0.6f, 0}, {2, 0, 0}, 0);
  const int n = int(box.positions.size());
  for (const Vec3i& t : back.indices) box.indices.push_back({t.x + n, t.y + n, t.z + n});
  box.positions.insert(box.positions.end(), back.positions.begin(), back.positions.end());
  const int32_t object = scene.addSingleInstanceMesh(std::move(box));
  scene.instances.clear();
  const Affine3f ends[] = {Affine3f::translate({1, 0, 0}) * Affine3f::rotate({0, 0, 1}, 2.0f),
                           Affine3f::translate({0, 1, -1}) * Affine3f::rotate({1, 1, 0}, 1.0f) *
                               Affine3f::scale({1.5f, 0.5f, 1}),
                           Affine3f::translate({2, -1, 0})};
  for (int k = 0; k < 3; ++k) {
    const Affine3f start = Affine3f::translate({float(k) * 2 - 2, 0, 0});
    scene.instances.push_back(
        {object, start,
         std::make_shared<const InstanceMotion>(start, ends[k] * start, Vec3f(0, 0, float(k)))});
  }
  const auto embree = makeEmbreeBackend(scene);
  const auto reference = makeReferenceBackend(scene);
  EXPECT_TRUE(embree->bounds().contains(scene.worldBounds()) ||
              reference->bounds().contains(scene.worldBounds()));
  MotionClock clock;
  clock.imageWidth = clock.filmWidth = 100;
  std::vector<TraceRay> rays;
  testing::TestRng rng(7);
  for (int i = 0; i < 20000; ++i) {
    const Vec3f at(rng.uniform() * 8 - 4, rng.uniform() * 4 - 2, rng.uniform() * 2 - 1);
    rays.push_back({Vec3f(0, 0, 10), normalize(at - Vec3f(0, 0, 10))});
  }
  for (uint32_t sample : {0u, 1u, 2u}) {
    const PathTimes times{&clock, sample};
    PathQueue<Path8> pathsE = asPaths(rays, false), pathsR = pathsE;
    std::vector<TraceHit> hitsE(rays.size()), hitsR(rays.size());
    embree->trace(pathsE, 0, {}, hitsE, times);
    reference->trace(pathsR, 0, {}, hitsR, times);
    size_t same = 0, hits = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      hits += hitsR[i].valid();
      if (hitsE[i].valid()) {
        EXPECT_EQ(hitsE[i].time, times.of(uint32_t(i)));
      }
      if (hitsR[i].valid()) {
        EXPECT_EQ(hitsR[i].time, times.of(uint32_t(i)));
      }
      if (sameTriangle(hitsE[i], hitsR[i]) &&
          (!hitsE[i].valid() || std::abs(hitsE[i].t - hitsR[i].t) < 1e-3f * hitsR[i].t))
        ++same;
    }
    EXPECT_GT(hits, rays.size() / 20);
    // Embree's slerp differs in the last bits: a ray grazing an edge may differ.
    EXPECT_GE(same, rays.size() - rays.size() / 200) << "sample " << sample;
  }
  // Moving things are found where they are at that time, not at the start.
  const Affine3f end = ends[2] * Affine3f::translate({2, 0, 0});
  const Vec3f onEnd = end.transformPoint({0, 0, 0});
  for (const TraceBackend* b : {embree.get(), reference.get()}) {
    TraceRay ray{Vec3f(onEnd.x, onEnd.y, 10), {0, 0, -1}};
    ray.time = 1;
    EXPECT_TRUE(b->intersect(ray).valid());
    ray.time = 0;
    EXPECT_FALSE(b->intersect(ray).valid() && b->intersect(ray).instance == 2);
  }
}

}  // namespace
}  // namespace ferry
