// Light sampling for next-event estimation. All of this is small (suns, the
// environment's sampling tables, the emissive triangles in world space) and
// lives on every rank, whatever part of the geometry the rank owns.
//
// One light sample per path vertex: the light is chosen by weighted sampling
// over all candidates (each sun, the environment, each emissive triangle or,
// past a threshold, groups of them), candidate i with probability w_i / sum(w)
// (what a one-sample weighted reservoir gives), with a single uniform number,
// so the choice is a pure function of the path's random key.
#pragma once

#include <vector>

#include "core/math.h"
#include "render/distribution.h"
#include "scene/scene.h"

namespace ferry {

struct LightSample {
  Vec3f direction;             // unit, from the shading point to the light
  float distance = kInfinity;  // to the sampled point; infinity for sun and environment
  Vec3f normal;                // the emitter's unit normal there (either sign); zero at infinity
  Vec3f radiance;              // emitted radiance along -direction
  float pdf = 0;               // solid angle, including the light's selection probability
};

class LightSampler {
 public:
  explicit LightSampler(const Scene& scene);

  // Samples a light as seen from `p` (with normal `n` for the selection
  // weights). `twoSided` surfaces (dielectrics) receive light from both
  // hemispheres. False when the scene has no light or the sample is useless.
  bool sample(Vec3f p, Vec3f n, bool twoSided, float uSelect, Vec2f u, LightSample& out) const {
    return sample(p, Frame(n), twoSided, uSelect, u, out);
  }
  // The same, given the frame about n (shading has built it already).
  bool sample(Vec3f p, const Frame& frame, bool twoSided, float uSelect, Vec2f u,
              LightSample& out) const;

  // Radiance arriving along `direction` from infinitely far away: environment
  // plus any sun whose disk `direction` falls in.
  Vec3f background(Vec3f direction) const;

  bool empty() const;
  size_t emissiveTriangleCount() const { return triangles_.size(); }

 private:
  struct EmissiveTriangle {
    Vec3f p0, e1, e2;
    Vec3f radiance;
    float area;
    bool oneSided = false;  // emits only on the side of cross(e1, e2)
  };
  struct Group {  // emissive triangles beyond kMaxIndividualTriangles, chosen by power
    Box3f bounds;
    float power = 0;
    Distribution1D byPower;
    std::vector<uint32_t> triangles;
  };

  Vec3f environmentRadiance(Vec3f direction) const;
  Vec2f directionToUv(Vec3f d) const;
  Vec3f uvToDirection(Vec2f uv) const;
  bool sampleEnvironment(const Frame& frame, bool twoSided, Vec2f u, LightSample& out) const;
  bool sampleTriangle(const EmissiveTriangle& t, Vec3f p, Vec2f u, LightSample& out) const;

  std::vector<SunLight> suns_;
  // Per sun, what sampling and background() need, computed once (same values
  // as computing them per call).
  struct SunConstants {
    Vec3f radiance;
    float conePdf;
    float oneMinusCosRadius;
    float chordRadius;      // 2 sin(r / 2): the cone test on |d - s|
    float selectionWeight;  // luminance(irradiance)
    Frame frame;            // Frame(direction), for sampling the cone
  };
  std::vector<SunConstants> sunConstants_;
  EnvironmentLight environment_;
  Distribution2D environmentDistribution_;
  float environmentWeight_ = 0;
  std::vector<EmissiveTriangle> triangles_;
  std::vector<Group> groups_;  // empty when every triangle is its own candidate
};

}  // namespace ferry
