#include "partition/ray_sampler.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/clock.h"
#include "core/error.h"
#include "core/random.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"

namespace ferry {
namespace {

constexpr float kPi = 3.14159265358979f;

// Where a ray is inside `box`: [enter, exit] (enter > exit: it misses).
void boxSpan(const Box3f& box, Vec3f origin, Vec3f direction, float& enter, float& exit) {
  enter = 0;
  exit = kInfinity;
  box.clipRay(origin, {1.0f / direction.x, 1.0f / direction.y, 1.0f / direction.z}, enter, exit);
}

Vec3f uniformSphere(float u, float v) {
  const float z = 1 - 2 * u, r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2 * kPi * v;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3f cosineAbout(Vec3f n, float u, float v) {
  const float r = std::sqrt(u), phi = 2 * kPi * v;
  return normalize(Frame(n).toWorld({r * std::cos(phi), r * std::sin(phi), std::sqrt(1 - u)}));
}

// The hit triangle's geometric normal in world space, facing against `direction`.
Vec3f facingNormal(const Scene& scene, const TraceHit& hit, Vec3f direction) {
  const Instance& instance = scene.instances[size_t(hit.instance)];
  const Mesh& mesh =
      scene.meshes[size_t(scene.objects[size_t(instance.object)].meshes[size_t(hit.slot)])];
  const Vec3i& tri = mesh.indices[hit.primitive];
  const Vec3f p0 = instance.transform.transformPoint(mesh.positions[size_t(tri.x)]);
  const Vec3f p1 = instance.transform.transformPoint(mesh.positions[size_t(tri.y)]);
  const Vec3f p2 = instance.transform.transformPoint(mesh.positions[size_t(tri.z)]);
  Vec3f n = cross(p1 - p0, p2 - p0);
  const float len = length(n);
  if (!(len > 0)) return -direction;
  n = n * (1.0f / len);
  return dot(n, direction) > 0 ? -n : n;
}

class PathSampler {
 public:
  PathSampler(const Scene& scene, const TraceBackend& tracer, const RaySamplerOptions& o)
      : scene_(scene), tracer_(tracer), o_(o), box_(scene.worldBounds()) {
    centre_ = box_.center();
    radius_ = std::max(1e-6f, 0.5f * length(box_.size()));
    epsilon_ = 1e-5f * radius_;
  }

  // Path `index`'s rays, appended to `out`.
  void sample(uint64_t index, std::vector<RaySegment>& out) const {
    const RandomKey key0{uint32_t(index), uint32_t(index >> 32), 0, o_.seed};
    auto r = [&](uint32_t bounce, uint32_t dim) {
      RandomKey k = key0;
      k.bounce = bounce;
      return random01FromBits(randomBits(k, dim));
    };
    // 1. From outside towards a random point of the box.
    const Vec3f outside = centre_ + uniformSphere(r(0, 0), r(0, 1)) * (1.01f * radius_);
    const Vec3f target = box_.lower + box_.size() * Vec3f(r(0, 2), r(0, 3), r(0, 4));
    if (!(length(target - outside) > 0)) return;
    const Vec3f outerDirection = normalize(target - outside);
    const TraceHit outer = trace(outside, outerDirection, 0, out);
    // 2. A camera in the outer ray's free stretch inside the box.
    float enter = 0, exit = 0;
    boxSpan(box_, outside, outerDirection, enter, exit);
    exit = std::min(exit, outer.t);
    if (!(enter < exit)) return;
    const Vec3f camera = outside + outerDirection * (enter + (exit - enter) * r(0, 5));
    Vec3f direction = uniformSphere(r(0, 6), r(0, 7));
    TraceHit hit = trace(camera, direction, 0, out);
    Vec3f origin = camera;
    // 3. Bounces.
    for (int bounce = 1; bounce <= o_.depth && hit.valid(); ++bounce) {
      const Vec3f x = origin + direction * hit.t;
      const Vec3f n = facingNormal(scene_, hit, direction);
      const uint32_t b = uint32_t(bounce);
      trace(x, cosineAbout(n, r(b, 0), r(b, 1)), epsilon_, out);  // shadow ray
      origin = x;
      direction = cosineAbout(n, r(b, 2), r(b, 3));
      hit = trace(origin, direction, epsilon_, out);
    }
  }

 private:
  // Traces one ray and keeps its segment (clipped to the box: nothing
  // outside it can be passed).
  TraceHit trace(Vec3f origin, Vec3f direction, float tnear, std::vector<RaySegment>& out) const {
    TraceRay ray;
    ray.origin = origin;
    ray.direction = direction;
    ray.tnear = tnear;
    const TraceHit hit = tracer_.intersect(ray);
    float enter = 0, exit = 0;
    boxSpan(box_, origin, direction, enter, exit);
    if (enter <= exit) out.push_back({origin, direction, std::min(hit.t, exit)});
    return hit;
  }

  const Scene& scene_;
  const TraceBackend& tracer_;
  RaySamplerOptions o_;
  Box3f box_;
  Vec3f centre_;
  float radius_ = 1, epsilon_ = 0;
};

}  // namespace

RaySample sampleSceneRays(const Scene& scene, const RaySamplerOptions& o) {
  const auto start = Clock::now();
  RaySample sample;
  sample.paths = o.paths;
  sample.seed = o.seed;
  if (scene.instances.empty() || scene.worldBounds().empty()) return sample;
  if (scene.meshStore)
    throw InputError(
        "the ray-guided partitioner traces its ray sample through the whole scene in memory: it "
        "does not partition with the geometry out of memory (use best, or a larger memory "
        "budget)");
  const std::unique_ptr<TraceBackend> tracer = makeEmbreeBackend(scene);
  const PathSampler sampler(scene, *tracer, o);
  // Per block of paths, then joined in path order: the same rays whatever
  // the threads.
  constexpr uint64_t kBlock = 256;
  const uint64_t blocks = (o.paths + kBlock - 1) / kBlock;
  std::vector<std::vector<RaySegment>> perBlock(blocks);
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, blocks), [&](const auto& range) {
    for (uint64_t b = range.begin(); b != range.end(); ++b)
      for (uint64_t i = b * kBlock; i < std::min(o.paths, (b + 1) * kBlock); ++i)
        sampler.sample(i, perBlock[b]);
  });
  for (const auto& block : perBlock)
    sample.rays.insert(sample.rays.end(), block.begin(), block.end());
  sample.seconds = secondsSince(start);
  return sample;
}

}  // namespace ferry
