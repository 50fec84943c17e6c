// Light sampling for next-event estimation. All of this is small (suns, the
// environment's sampling tables, the emissive triangles in world space) and
// lives on every rank, whatever part of the geometry the rank owns.
//
// One light sample per path vertex, chosen with a single uniform number over
// every candidate with probability w_i / sum(w), so the choice is a pure
// function of the path's random key. The emitters' and an environment map's
// share depends only on the shading point, not on its normal, so a path that
// finds one by BSDF sampling can recompute the light sample's density there
// (emitterPdf, environmentPdf): the other half of the MIS weight. Suns are
// left to the light sample alone, and so is a constant environment at a
// diffuse surface (there they share their part by the normal); elsewhere
// (`twoSided`) it is drawn over the sphere and weighed by MIS
// (constantEnvironmentPdf). docs/path-tracer.md, "Light sampling".
#pragma once

#include <array>
#include <cstdint>
#include <unordered_map>
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
  bool mis = false;            // a BSDF sample can find it too (an emitter or environment map)
  uint32_t emitter = 0xffffffffu;  // the emissive triangle sampled (else kNotAnEmitter)
};

// Light leaving an emitter (light tracing's first vertex and direction).
struct EmissionSample {
  Vec3f position;
  Vec3f normal;     // the emitting side's unit normal
  Vec3f direction;  // unit, leaving the emitter
  Vec3f radiance;   // emitted along direction
  uint32_t emitter = 0;
  float pdfPosition = 0;   // area density, selection included (emissionPositionPdf)
  float pdfDirection = 0;  // solid angle: cos / pi, halved for a two-sided emitter
};

// How a light sample chooses among the emissive triangles: Near (the
// default) by power over squared distance from the shading point; Power by
// power alone (pbrt's "power" light sample strategy). Either way the distant
// lights (suns, environment) keep their share, and the estimate is unbiased.
enum class LightChoice { Near, Power };
inline const char* lightChoiceName(LightChoice c) {
  return c == LightChoice::Near ? "near" : "power";
}

class LightSampler {
 public:
  explicit LightSampler(const Scene& scene, LightChoice choice = LightChoice::Near);

  // Samples a light as seen from `p` (with normal `n` for the selection
  // weights). `twoSided`: a constant environment is drawn over the whole
  // sphere (dielectrics, media, glossy lobes: render/path_shading.h).
  // False when the scene has no light or the sample is useless.
  bool sample(Vec3f p, Vec3f n, bool twoSided, float uSelect, Vec2f u, LightSample& out) const {
    return sample(p, Frame(n), twoSided, uSelect, u, out);
  }
  static constexpr uint32_t kNotAnEmitter = 0xffffffffu;
  // The same, given the frame about n (shading has built it already).
  // `facing`, when not zero, is the geometric normal of a surface that only
  // reflects: a sun wholly below its horizon cannot light it and is not
  // chosen, and the suns and a constant environment share their selection
  // by what each can give there (suns by their cosine). The emitters' and an
  // environment map's selection is the same either way, so their MIS
  // densities do not depend on it.
  bool sample(Vec3f p, const Frame& frame, bool twoSided, float uSelect, Vec2f u, LightSample& out,
              Vec3f facing = Vec3f(0)) const;

  // Radiance arriving along `direction` from infinitely far away: environment
  // plus any sun whose disk `direction` falls in.
  // (Inline: every escaped path asks, and a constant sky is the common case.)
  Vec3f background(Vec3f direction) const {
    Vec3f l = environmentRadiance(direction);
    for (size_t i = 0; i < suns_.size(); ++i)
      // |d - s|^2 <= (2 sin(r / 2))^2 is the cone test without 1 - cos cancellation.
      if (const Vec3f v = direction - suns_[i].direction;
          dot(v, v) <= sunConstants_[i].chordRadiusSquared)
        l += sunConstants_[i].radiance;
    return l;
  }

  // For MIS. The emissive triangle with these world-space corners (in any
  // order; as computed by Affine3f::transformPoint from the mesh and its
  // instance), or kNotAnEmitter when light sampling does not know it (then
  // only BSDF sampling finds it, and its emission counts in full).
  uint32_t emitterIndex(const std::array<Vec3f, 3>& corners) const;
  // The solid-angle density with which sample(from, ...) picks `point` on
  // emitter `index` (selection included); 0 where it never does.
  float emitterPdf(Vec3f from, uint32_t index, Vec3f point) const;
  // Whether escaped paths weigh the environment against light samples: true
  // for an environment map (a constant one is sampled about the normal,
  // except where light arrives from both sides: constantEnvironmentPdf).
  bool environmentTakesPartInMis() const { return environment_.image != nullptr; }
  // The density with which sample(from, ...) at a two-sided point (one that
  // transmits, or in a medium) picks `direction` of a constant environment,
  // which it draws uniformly over the sphere, selection included; 0 for an
  // environment map or none.
  float constantEnvironmentPdf(Vec3f from) const;
  // The environment alone (no suns) along `direction`, and the density with
  // which sample(from, ...) picks that direction (selection included).
  Vec3f environmentAlong(Vec3f direction) const { return environmentRadiance(direction); }
  float environmentPdf(Vec3f from, Vec3f direction) const;

  // Light tracing: an emissive triangle chosen by power, a point uniform on
  // it, a cosine-weighted direction on its emitting side (either side of a
  // two-sided one, by uDirection.x). False when there is no emissive triangle.
  bool sampleEmission(float uSelect, Vec2f uPosition, Vec2f uDirection, EmissionSample& out) const;
  // The area density with which sampleEmission picks a point on `emitter`.
  float emissionPositionPdf(uint32_t emitter) const;
  // The emissive triangles' total power (pi times the sum of luminance times
  // area): a light path's throughput is about this.
  float totalEmittedPower() const { return emittedPower_; }
  // Whether `emitter` emits from both sides (its direction density halves).
  bool emitsBothSides(uint32_t emitter) const { return !triangles_[emitter].oneSided; }

  bool empty() const;
  size_t emissiveTriangleCount() const { return triangles_.size(); }

 private:
  struct EmissiveTriangle {
    Vec3f p0, e1, e2;
    Vec3f radiance;
    float area;
    float power;  // luminance(radiance) * area
    Vec3f centroid;
    Vec3f normal;           // unit, cross(e1, e2)
    bool oneSided = false;  // emits only on the side of cross(e1, e2)
  };
  struct Group {  // emissive triangles beyond kMaxIndividualTriangles, chosen by power
    Box3f bounds;
    float power = 0;
    Distribution1D byPower;
    std::vector<uint32_t> triangles;
  };

  Vec3f environmentRadiance(Vec3f direction) const {
    return environment_.image ? environmentMapRadiance(direction) : environment_.color;
  }
  Vec3f environmentMapRadiance(Vec3f direction) const;  // environment_.image set
  // Each candidate's selection weight as seen from `p`, in order, until
  // visit(index, weight) returns true.
  template <typename Visit>
  void forEachCandidate(Vec3f p, Visit&& visit) const;
  float selectionTotal(Vec3f p) const;
  float triangleWeight(const EmissiveTriangle& t, Vec3f p) const;
  float groupWeight(size_t group, Vec3f p) const;
  float pointWeight(const PointLight& l, Vec3f p) const;
  float emittersPerPower(Vec3f p) const;
  Vec2f directionToUv(Vec3f d) const;
  Vec3f uvToDirection(Vec2f uv) const;
  bool sampleEnvironment(const Frame& frame, bool twoSided, Vec2f u, LightSample& out) const;
  static Vec3f uniformPoint(const EmissiveTriangle& t, Vec2f u);
  bool sampleTriangle(const EmissiveTriangle& t, Vec3f p, Vec2f u, LightSample& out) const;

  std::vector<SunLight> suns_;
  std::vector<PointLight> points_;  // chosen after the emitters, never found by BSDF samples
  // Per sun, what sampling and background() need, computed once (same values
  // as computing them per call).
  struct SunConstants {
    Vec3f radiance;
    float conePdf;
    float oneMinusCosRadius;
    float chordRadiusSquared;  // (2 sin(r / 2))^2: the cone test on |d - s|^2
    float selectionWeight;     // luminance(irradiance)
    float sinRadius;           // of the cone: how far below a horizon part of the disk still shows
    Frame frame;               // Frame(direction), for sampling the cone
  };
  std::vector<SunConstants> sunConstants_;
  EnvironmentLight environment_;
  Distribution2D environmentDistribution_;
  float environmentWeight_ = 0;
  // The lights chosen first, which take no part in MIS: the suns and a
  // constant environment (when it is one), and their summed weight.
  bool constantEnvironmentSelected_ = false;
  float distantWeight_ = 0;
  // selectionTotal's answer when no emissive triangle or point light makes it
  // depend on the point, else -1.
  float distantOnlyTotal_ = -1;
  LightChoice choice_ = LightChoice::Near;
  float trianglePower_ = 0;  // the sum of triangles_' power (LightChoice::Power)
  std::vector<EmissiveTriangle> triangles_;
  std::vector<Group> groups_;       // empty when every triangle is its own candidate
  Distribution1D emissionByPower_;  // over triangles_, for sampleEmission
  float emittedPower_ = 0;
  // emitterIndex's table: a hash of the sorted corners' bits -> triangle.
  std::unordered_map<uint64_t, uint32_t> triangleByCorners_;
};

}  // namespace ferry
