#include "render/media_along_rays.h"

#include "scene/scene.h"
#include "trace/embree_backend.h"

namespace ferry {
namespace {

// A ray crossing more boundaries than this is caught in a degenerate mesh.
constexpr int kMaxCrossings = 4096;

}  // namespace

MediaAlongRays::MediaAlongRays(const Scene& scene) : media_(scene.media) {
  if (scene.mediumBoundaries.empty()) return;
  boundaryScene_ = std::make_unique<Scene>();
  Scene& bounds = *boundaryScene_;
  bounds.name = scene.name + " (medium boundaries)";
  bounds.materials.emplace_back();
  for (const MediumBoundary& b : scene.mediumBoundaries) {
    Mesh mesh = b.mesh;
    mesh.material = 0;
    bounds.addSingleInstanceMesh(std::move(mesh));
    interfaces_.push_back(b.media);
    meshes_.push_back(&b);
  }
  boundaries_ = makeEmbreeBackend(bounds, {}, Instancing::Shared);
}

MediaAlongRays::~MediaAlongRays() = default;

template <typename Segment>
void MediaAlongRays::walk(Vec3f o, Vec3f d, float tEnd, int32_t medium, Segment&& segment) const {
  float t = 0;
  for (int crossings = 0;; ++crossings) {
    TraceHit hit;
    if (boundaries_ && crossings < kMaxCrossings)
      hit = boundaries_->intersect(TraceRay{o, d, t, tEnd});
    const float end = hit.valid() ? hit.t : tEnd;
    if (!segment(medium, t, end) || !hit.valid()) return;
    const MediumBoundary& b = *meshes_[size_t(hit.instance)];
    const Vec3i tri = b.mesh.indices[hit.primitive];
    const Vec3f p0 = b.mesh.positions[size_t(tri.x)];
    const Vec3f n =
        cross(b.mesh.positions[size_t(tri.y)] - p0, b.mesh.positions[size_t(tri.z)] - p0);
    medium = interfaces_[size_t(hit.instance)].along(d, n);
    // Past this crossing (and past a neighbour triangle's at the same edge).
    t = hit.t + 1e-5f * (hit.t + 1);
    if (!(t < tEnd)) return;
  }
}

MediaFlight MediaAlongRays::flight(Vec3f o, Vec3f d, float tEnd, int32_t medium,
                                   TrackingRandom& random, MediumCounts& counts) const {
  MediaFlight out;
  out.medium = medium;
  walk(o, d, tEnd, medium, [&](int32_t m, float t0, float t1) {
    out.medium = m;
    if (m == kNoMedium) return true;
    const FreeFlight f = sampleFreeFlight(media_[size_t(m)], o, d, t0, t1, random, counts);
    out.emitted += out.weight * f.emitted;
    out.weight = out.weight * f.weight;
    if (f.event == FreeFlight::Event::Passed) return maxComponent(out.weight) > 0;
    out.event = f.event;
    out.t = f.t;
    return false;
  });
  // Passing with no weight left is as good as absorbed.
  if (out.event == FreeFlight::Event::Passed && !(maxComponent(out.weight) > 0))
    out.event = FreeFlight::Event::Absorbed;
  return out;
}

Vec3f MediaAlongRays::transmittance(Vec3f o, Vec3f d, float tEnd, int32_t medium,
                                    TransmittanceEstimator estimator, TrackingRandom& random,
                                    MediumCounts& counts) const {
  Vec3f tr{1, 1, 1};
  walk(o, d, tEnd, medium, [&](int32_t m, float t0, float t1) {
    if (m == kNoMedium) return true;
    tr = tr * ferry::transmittance(media_[size_t(m)], o, d, t0, t1, estimator, random, counts);
    return maxComponent(tr) > 0;
  });
  return tr;
}

}  // namespace ferry
