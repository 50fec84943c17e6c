// A ray's way through the scene's participating media: the media it passes
// between surfaces, found by tracing the surfaces that only bound media
// (Scene::mediumBoundaries, in a small trace structure of their own, which
// nothing else sees), each segment tracked in the medium it lies in
// (media/tracking.h). Every rank holds it whole: shading anywhere can ask.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/math.h"
#include "media/medium.h"
#include "media/tracking.h"
#include "trace/trace_backend.h"

namespace ferry {

struct Scene;
struct MediumBoundary;

// What became of a ray between its origin and the surface it hits (or
// infinity): passed, scattered or absorbed in a medium.
struct MediaFlight {
  FreeFlight::Event event = FreeFlight::Event::Passed;
  float t = 0;                 // where it scattered or was absorbed
  int32_t medium = kNoMedium;  // the medium it is in there (or at the end)
  Vec3f weight{1, 1, 1};       // throughput factor up to there
  Vec3f emitted{0, 0, 0};      // light the media emit along it, weighed
};

class MediaAlongRays {
 public:
  explicit MediaAlongRays(const Scene& scene);
  ~MediaAlongRays();

  // The ray o + t d (d unit) from t = 0 to tEnd, starting in `medium`.
  MediaFlight flight(Vec3f o, Vec3f d, float tEnd, int32_t medium, TrackingRandom& random,
                     MediumCounts& counts) const;
  // Its transmittance (an unbiased estimate), from `medium` on, through the
  // boundaries it passes.
  Vec3f transmittance(Vec3f o, Vec3f d, float tEnd, int32_t medium,
                      TransmittanceEstimator estimator, TrackingRandom& random,
                      MediumCounts& counts) const;

  const Medium& medium(int32_t m) const { return media_[size_t(m)]; }

 private:
  // Calls segment(medium, t0, t1) for each piece of [0, tEnd] between
  // boundaries, in order, until it returns false.
  template <typename Segment>
  void walk(Vec3f o, Vec3f d, float tEnd, int32_t medium, Segment&& segment) const;

  const std::vector<Medium>& media_;
  std::vector<MediumInterface> interfaces_;    // per boundary (its instance)
  std::vector<const MediumBoundary*> meshes_;  // per boundary, for the normal at a hit
  std::unique_ptr<Scene>
      boundaryScene_;  // the boundaries as a scene (the backend shares its arrays)
  std::unique_ptr<TraceBackend> boundaries_;  // null: no boundaries
};

}  // namespace ferry
