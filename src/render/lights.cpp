#include "render/lights.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/hash64.h"
#include "material/bsdf.h"

namespace ferry {
namespace {

// Up to this many emissive triangles are candidates one by one; more are
// grouped, so a light sample stays cheap however many emitters a scene has.
constexpr size_t kMaxIndividualTriangles = 64;
constexpr size_t kTrianglesPerGroup = 256;

Vec3f sunRadiance(const SunLight& sun) {
  float s = std::sin(sun.angularRadius);
  return sun.irradiance * (1.0f / (kPi * s * s));
}

// 1 - cos(r) without cancellation: in float, 1 - cos(0.00465) is off by 0.2%
// (and by 1.3% at r = 0.002), which would bias every sunlit pixel by as much.
float oneMinusCos(float r) {
  float s = std::sin(0.5f * r);
  return 2 * s * s;
}

float sunConePdf(const SunLight& sun) {
  return 1.0f / (2 * kPi * oneMinusCos(sun.angularRadius));
}

// (2 sin(r / 2))^2: the squared chord a cone of half-angle r subtends on the unit sphere.
float chordSquared(float r) {
  const float chord = 2 * std::sin(0.5f * r);
  return chord * chord;
}

// emitterIndex's key: the corners' bits, sorted (a mesh may start a triangle
// at any corner), -0 counted as +0 (placing by the identity transform, as
// the light scene does, turns -0 into +0).
uint64_t cornersKey(std::array<Vec3f, 3> corners) {
  std::array<std::array<uint32_t, 3>, 3> bits;
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) {
      const float v = corners[c][k] + 0.0f;
      std::memcpy(&bits[c][k], &v, 4);
    }
  std::sort(bits.begin(), bits.end());
  return hash64(bits.data(), sizeof(bits));
}

}  // namespace

LightSampler::LightSampler(const Scene& scene, LightChoice choice)
    : suns_(scene.suns),
      points_(scene.pointLights),
      environment_(scene.environment),
      choice_(choice) {
  for (const SunLight& sun : suns_)
    sunConstants_.push_back({sunRadiance(sun), sunConePdf(sun), oneMinusCos(sun.angularRadius),
                             chordSquared(sun.angularRadius), luminance(sun.irradiance),
                             std::sin(std::min(sun.angularRadius, 0.5f * kPi)),
                             Frame(sun.direction)});
  if (environment_.image) {
    const HdrImage& img = *environment_.image;
    std::vector<float> weights(size_t(img.width) * img.height);
    double sum = 0;
    for (int y = 0; y < img.height; ++y) {
      float sinTheta = std::sin(kPi * (y + 0.5f) / img.height);
      for (int x = 0; x < img.width; ++x) {
        float l = luminance(img.at(x, y) * environment_.color);
        weights[size_t(y) * img.width + x] = l * sinTheta;
        sum += l * sinTheta;
      }
    }
    environmentDistribution_ = Distribution2D(weights, img.width, img.height);
    // Average radiance over the sphere: sum(L sin) * dtheta dphi / 4pi.
    environmentWeight_ = float(sum * (kPi / img.height) * (2 * kPi / img.width) / (4 * kPi)) * kPi;
  } else {
    environmentWeight_ = luminance(environment_.color) * kPi;
  }
  // The suns and a constant environment: the share that sample() divides
  // by the surface's normal.
  constantEnvironmentSelected_ = !environment_.isBlack() && !environmentTakesPartInMis();
  distantWeight_ = constantEnvironmentSelected_ ? environmentWeight_ : 0.0f;
  for (const SunConstants& c : sunConstants_) distantWeight_ += std::max(c.selectionWeight, 0.0f);

  // Emissive triangles in world space, from every instance of every emissive mesh.
  std::vector<std::vector<int32_t>> emissiveMeshesPerObject(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o)
    for (int32_t m : scene.objects[o].meshes)
      if (scene.materials[scene.meshes[m].material].isEmissive())
        emissiveMeshesPerObject[o].push_back(m);
  for (const Instance& inst : scene.instances) {
    for (int32_t m : emissiveMeshesPerObject[inst.object]) {
      const Mesh& mesh = scene.meshes[m];
      const Material& material = scene.materials[mesh.material];
      const Vec3f radiance = material.emission;
      // The emitting side is the object's winding normal transformed as a
      // normal (as at a hit, render/surface.h): the world edges' cross
      // product, turned around where the transform swaps handedness.
      // (Two-sided emitters keep their edges: where a sample lands does not
      // change for them.)
      const bool oneSided = !material.emitsBackSide;
      const bool swapEdges =
          oneSided && ((inst.transform.determinant() < 0) != material.lightSampledOnBackSide);
      for (const Vec3i& tri : mesh.indices) {
        const std::array<Vec3f, 3> corners{inst.transform.transformPoint(mesh.positions[tri.x]),
                                           inst.transform.transformPoint(mesh.positions[tri.y]),
                                           inst.transform.transformPoint(mesh.positions[tri.z])};
        const Vec3f p0 = corners[0];
        Vec3f e1 = corners[1] - p0, e2 = corners[2] - p0;
        float area = 0.5f * length(cross(e1, e2));
        if (!(area > 0)) continue;
        if (swapEdges) std::swap(e1, e2);  // the same triangle, its normal turned
        triangleByCorners_.emplace(cornersKey(corners), uint32_t(triangles_.size()));
        triangles_.push_back({p0, e1, e2, radiance, area, luminance(radiance) * area,
                              p0 + (e1 + e2) * (1.0f / 3), normalize(cross(e1, e2)), oneSided});
      }
    }
  }
  if (!triangles_.empty()) {
    std::vector<float> powers;
    double sum = 0;
    for (const EmissiveTriangle& t : triangles_) {
      powers.push_back(t.power);
      sum += t.power;
    }
    emittedPower_ = float(sum * kPi);
    trianglePower_ = float(sum);
    emissionByPower_ = Distribution1D(std::move(powers));
  }
  if (triangles_.size() > kMaxIndividualTriangles) {
    for (size_t begin = 0; begin < triangles_.size(); begin += kTrianglesPerGroup) {
      Group g;
      std::vector<float> powers;
      for (size_t i = begin; i < std::min(triangles_.size(), begin + kTrianglesPerGroup); ++i) {
        const EmissiveTriangle& t = triangles_[i];
        g.triangles.push_back(uint32_t(i));
        powers.push_back(t.power);
        g.power += t.power;
        g.bounds.extend(t.p0);
        g.bounds.extend(t.p0 + t.e1);
        g.bounds.extend(t.p0 + t.e2);
      }
      g.byPower = Distribution1D(std::move(powers));
      groups_.push_back(std::move(g));
    }
  }
  // Without emissive triangles every candidate's weight is the same
  // everywhere: sum them once, in selectionTotal's order.
  if (triangles_.empty() && points_.empty()) {
    distantOnlyTotal_ = 0;
    forEachCandidate(Vec3f(0), [&](int, float w) {
      if (w > 0) distantOnlyTotal_ += w;
      return false;
    });
  }
}

bool LightSampler::empty() const {
  return suns_.empty() && environment_.isBlack() && triangles_.empty() && points_.empty();
}

Vec2f LightSampler::directionToUv(Vec3f d) const {
  float theta = std::acos(std::clamp(d.y, -1.0f, 1.0f));
  float phi = std::atan2(d.z, d.x) + environment_.rotation;
  float u = phi / (2 * kPi);
  u -= std::floor(u);
  return {u, theta / kPi};
}

Vec3f LightSampler::uvToDirection(Vec2f uv) const {
  float theta = uv.y * kPi;
  float phi = uv.x * 2 * kPi - environment_.rotation;
  float s = std::sin(theta);
  return {s * std::cos(phi), std::cos(theta), s * std::sin(phi)};
}

Vec3f LightSampler::environmentMapRadiance(Vec3f d) const {
  Vec2f uv = directionToUv(d);
  // HdrImage rows go top (theta = 0) to bottom; its sampler takes v = 0 at the bottom.
  return environment_.image->sampleBilinear({uv.x, 1 - uv.y}) * environment_.color;
}

bool LightSampler::sampleEnvironment(const Frame& frame, bool twoSided, Vec2f u,
                                     LightSample& out) const {
  if (!environment_.image && twoSided) {
    // Uniform over the sphere: light arrives from both sides.
    float z = 1 - 2 * u.x;
    float r = std::sqrt(std::max(0.0f, 1 - z * z));
    float sinPhi, cosPhi;
    sinCosTwoPi(u.y, sinPhi, cosPhi);
    out.direction = {r * cosPhi, r * sinPhi, z};
    out.pdf = 1 / (4 * kPi);
    out.radiance = environment_.color;
  } else if (!environment_.image) {
    // Constant: cosine-weighted around the normal is the ideal density.
    Vec3f local = sampleCosineHemisphere(u);
    out.direction = frame.toWorld(local);
    out.pdf = local.z / kPi;
    out.radiance = environment_.color;
  } else {
    float pdfUv;
    Vec2f uv = environmentDistribution_.sample(u, pdfUv);
    float sinTheta = std::sin(uv.y * kPi);
    if (sinTheta <= 0 || pdfUv <= 0) return false;
    out.direction = uvToDirection(uv);
    out.pdf = pdfUv / (2 * kPi * kPi * sinTheta);
    out.radiance = environmentRadiance(out.direction);
  }
  out.distance = kInfinity;
  return out.pdf > 0;
}

// A point uniform on `t` from (u.x, u.y) (light samples and emission alike).
Vec3f LightSampler::uniformPoint(const EmissiveTriangle& t, Vec2f u) {
  const float su = std::sqrt(u.x);
  return t.p0 + t.e1 * (1 - su) + t.e2 * (u.y * su);
}

bool LightSampler::sampleTriangle(const EmissiveTriangle& t, Vec3f p, Vec2f u,
                                  LightSample& out) const {
  Vec3f d = uniformPoint(t, u) - p;
  float dist2 = dot(d, d);
  if (dist2 <= 0) return false;
  float dist = std::sqrt(dist2);
  out.direction = d * (1 / dist);
  const Vec3f ng = t.normal;
  const float facing = dot(ng, out.direction);
  // A one-sided emitter lights only points on the side its normal faces
  // (the direction runs from the point to the light: facing < 0).
  if (t.oneSided && !(facing < 0)) return false;
  float cosLight = std::abs(facing);
  if (cosLight <= 1e-7f) return false;
  out.distance = dist;
  out.normal = ng;
  out.radiance = t.radiance;
  out.pdf = dist2 / (cosLight * t.area);
  return true;
}

// Candidate weights estimate each light's unshadowed contribution but are
// never zero for a light that could contribute, which keeps the estimator
// unbiased. Suns weigh their irradiance, the environment its mean radiance
// times pi, triangles (or groups) their power over the squared distance.
float LightSampler::triangleWeight(const EmissiveTriangle& t, Vec3f p) const {
  const Vec3f d = t.centroid - p;
  return t.power / std::max(dot(d, d), t.area);
}

float LightSampler::groupWeight(size_t group, Vec3f p) const {
  const Group& g = groups_[group];
  const Vec3f d = g.bounds.center() - p;
  return g.power / std::max(dot(d, d), g.bounds.surfaceArea() * 0.25f);
}

// A point light: its intensity towards p over the squared distance (the
// irradiance it gives p), zero outside a spot's cone.
float LightSampler::pointWeight(const PointLight& l, Vec3f p) const {
  const Vec3f d = p - l.position;
  const float d2 = dot(d, d);
  if (!(d2 > 0)) return 0;
  return luminance(l.intensity) * l.falloffTowards(d * (1 / std::sqrt(d2))) / d2;
}

// LightChoice::Power: the emitters' share as Near gives it at p, split by
// power alone: each triangle's weight is its power times this.
float LightSampler::emittersPerPower(Vec3f p) const {
  if (!(trianglePower_ > 0)) return 0;
  float share = 0;
  if (groups_.empty())
    for (const EmissiveTriangle& t : triangles_) share += triangleWeight(t, p);
  else
    for (size_t g = 0; g < groups_.size(); ++g) share += groupWeight(g, p);
  return share / trianglePower_;
}

template <typename Visit>
void LightSampler::forEachCandidate(Vec3f p, Visit&& visit) const {
  const int sunCount = int(suns_.size());
  for (int i = 0; i < sunCount; ++i)
    if (visit(i, sunConstants_[i].selectionWeight)) return;
  int next = sunCount;
  if (!environment_.isBlack() && visit(next, environmentWeight_)) return;
  ++next;
  const bool byPower = choice_ == LightChoice::Power;
  const float perPower = byPower ? emittersPerPower(p) : 0.0f;
  if (groups_.empty()) {
    for (const EmissiveTriangle& t : triangles_)
      if (visit(next++, byPower ? t.power * perPower : triangleWeight(t, p))) return;
  } else {
    for (size_t g = 0; g < groups_.size(); ++g)
      if (visit(next++, byPower ? groups_[g].power * perPower : groupWeight(g, p))) return;
  }
  for (const PointLight& l : points_)
    if (visit(next++, pointWeight(l, p))) return;
}

float LightSampler::selectionTotal(Vec3f p) const {
  if (distantOnlyTotal_ >= 0) return distantOnlyTotal_;
  float total = 0;
  forEachCandidate(p, [&](int, float w) {
    if (w > 0) total += w;
    return false;
  });
  return total;
}

bool LightSampler::sample(Vec3f p, const Frame& frame, bool twoSided, float uSelect, Vec2f u,
                          LightSample& out, Vec3f facing) const {
  // Candidate i is chosen with probability w_i / sum(w): one pass sums the
  // weights, a second stops at the first candidate whose running sum passes
  // uSelect * sum (two cheap passes instead of a division per candidate,
  // which a streaming reservoir needs).
  const int envIndex = int(suns_.size());
  const int triangleBase = envIndex + 1;
  const float total = selectionTotal(p);
  if (!(total > 0)) return false;
  const float target = uSelect * total;
  float running = 0, chosenWeight = 0;
  int chosen = -1;
  float selection = 0;
  // The suns and a constant environment come first. At a diffuse surface
  // (`facing`, not `twoSided`), where neither takes part in MIS, their share
  // (distantWeight_, the same as without `facing`) goes among them by what
  // each can give there.
  if (!twoSided && !(facing == Vec3f(0)) && target < distantWeight_) {
    auto facingWeight = [&](int i) {
      if (i == envIndex) return environmentWeight_;
      const SunConstants& c = sunConstants_[size_t(i)];
      return std::max(c.selectionWeight, 0.0f) *
             std::max(dot(facing, c.frame.n) + c.sinRadius, 0.0f);
    };
    const int count = envIndex + (constantEnvironmentSelected_ ? 1 : 0);
    float facingTotal = 0;
    for (int i = 0; i < count; ++i) facingTotal += facingWeight(i);
    if (!(facingTotal > 0)) return false;  // no distant light reaches this side
    const float facingTarget = target / distantWeight_ * facingTotal;
    for (int i = 0; i < count; ++i) {
      const float w = facingWeight(i);
      if (!(w > 0)) continue;
      running += w;
      chosen = i;
      chosenWeight = w;
      if (running > facingTarget) break;
    }
    selection = distantWeight_ / total * (chosenWeight / facingTotal);
  } else {
    forEachCandidate(p, [&](int i, float w) {
      if (!(w > 0)) return false;
      running += w;
      chosen = i;  // the last positive one if rounding keeps running <= target
      chosenWeight = w;
      return running > target;
    });
    selection = chosenWeight / total;
  }

  if (chosen < envIndex) {
    const SunConstants& constants = sunConstants_[chosen];
    // Uniform in the sun's cone, in terms of 1 - cos(theta) so that a small
    // cone keeps its precision.
    float oneMinusCosTheta = u.x * constants.oneMinusCosRadius;
    float cosTheta = 1 - oneMinusCosTheta;
    float sinTheta = std::sqrt(std::max(0.0f, oneMinusCosTheta * (2 - oneMinusCosTheta)));
    float sinPhi, cosPhi;
    sinCosTwoPi(u.y, sinPhi, cosPhi);
    out.direction = constants.frame.toWorld({sinTheta * cosPhi, sinTheta * sinPhi, cosTheta});
    out.distance = kInfinity;
    out.radiance = constants.radiance;
    out.pdf = constants.conePdf * selection;
    out.mis = false;
    return true;
  }
  if (chosen == envIndex) {
    if (!sampleEnvironment(frame, twoSided, u, out)) return false;
    out.pdf *= selection;
    out.mis = environmentTakesPartInMis() || twoSided;  // (see constantEnvironmentPdf)
    return true;
  }
  const int pointBase = triangleBase + int(groups_.empty() ? triangles_.size() : groups_.size());
  if (chosen >= pointBase) {
    // A delta light: its direction and distance are the sample.
    const PointLight& l = points_[size_t(chosen - pointBase)];
    const Vec3f toLight = l.position - p;
    const float d2 = dot(toLight, toLight);
    if (!(d2 > 0)) return false;
    out.distance = std::sqrt(d2);
    out.direction = toLight * (1 / out.distance);
    out.normal = Vec3f(0);
    out.radiance = l.intensity * (l.falloffTowards(-out.direction) / d2);
    out.pdf = selection;
    out.mis = false;
    out.emitter = kNotAnEmitter;
    return maxComponent(out.radiance) > 0;
  }
  out.mis = true;
  int index = chosen - triangleBase;
  if (groups_.empty()) {
    if (!sampleTriangle(triangles_[index], p, u, out)) return false;
    out.pdf *= selection;
    out.emitter = uint32_t(index);
    return true;
  }
  const Group& g = groups_[index];
  // Reuse u.x for the triangle choice, then stretch it back to [0, 1).
  float probability;
  int local = g.byPower.sampleDiscrete(u.x, probability);
  float lo = 0;
  for (int i = 0; i < local; ++i) lo += g.byPower.discreteProbability(i);
  Vec2f uTriangle{std::clamp((u.x - lo) / std::max(probability, 1e-12f), 0.0f, 0.99999994f), u.y};
  if (!sampleTriangle(triangles_[g.triangles[local]], p, uTriangle, out)) return false;
  out.pdf *= selection * probability;
  out.emitter = g.triangles[local];
  return true;
}

bool LightSampler::sampleEmission(float uSelect, Vec2f uPosition, Vec2f uDirection,
                                  EmissionSample& out) const {
  if (triangles_.empty()) return false;
  float selection;
  const int index = emissionByPower_.sampleDiscrete(uSelect, selection);
  const EmissiveTriangle& t = triangles_[size_t(index)];
  if (!(selection > 0)) return false;
  out.position = uniformPoint(t, uPosition);
  out.normal = t.normal;
  out.emitter = uint32_t(index);
  out.radiance = t.radiance;
  out.pdfPosition = selection / t.area;
  Vec2f u = uDirection;
  if (!t.oneSided) {
    // Either side with probability 1/2, u.x stretched back to [0, 1).
    if (u.x < 0.5f) {
      out.normal = -out.normal;
      u.x = u.x * 2;
    } else {
      u.x = std::min((u.x - 0.5f) * 2, 0.99999994f);
    }
  }
  const Vec3f local = sampleCosineHemisphere(u);
  if (!(local.z > 0)) return false;
  out.direction = Frame(out.normal).toWorld(local);
  out.pdfDirection = local.z * (t.oneSided ? (1 / kPi) : (0.5f / kPi));
  return out.pdfPosition > 0 && out.pdfDirection > 0;
}

float LightSampler::emissionPositionPdf(uint32_t emitter) const {
  if (emitter >= triangles_.size()) return 0;
  return emissionByPower_.discreteProbability(int(emitter)) / triangles_[emitter].area;
}

uint32_t LightSampler::emitterIndex(const std::array<Vec3f, 3>& corners) const {
  const auto found = triangleByCorners_.find(cornersKey(corners));
  return found == triangleByCorners_.end() ? kNotAnEmitter : found->second;
}

float LightSampler::emitterPdf(Vec3f from, uint32_t index, Vec3f point) const {
  if (index >= triangles_.size()) return 0;
  const EmissiveTriangle& t = triangles_[index];
  const Vec3f d = point - from;
  const float dist2 = dot(d, d);
  if (!(dist2 > 0)) return 0;
  const float facing = dot(t.normal, d) / std::sqrt(dist2);
  // sampleTriangle's rules: a one-sided emitter is sampled only from its
  // front, and never at grazing angles.
  if (t.oneSided && !(facing < 0)) return 0;
  const float cosLight = std::abs(facing);
  if (cosLight <= 1e-7f) return 0;
  const float total = selectionTotal(from);
  if (!(total > 0)) return 0;
  float selection;
  if (choice_ == LightChoice::Power) {
    selection = t.power * emittersPerPower(from) / total;
  } else if (groups_.empty()) {
    selection = triangleWeight(t, from) / total;
  } else {
    // Groups are consecutive runs of kTrianglesPerGroup triangles.
    const size_t group = index / kTrianglesPerGroup;
    selection = groupWeight(group, from) / total *
                groups_[group].byPower.discreteProbability(int(index % kTrianglesPerGroup));
  }
  return selection * dist2 / (cosLight * t.area);
}

float LightSampler::constantEnvironmentPdf(Vec3f from) const {
  if (environment_.image || environment_.isBlack()) return 0;
  const float total = selectionTotal(from);
  if (!(total > 0)) return 0;
  return environmentWeight_ / total / (4 * kPi);
}

float LightSampler::environmentPdf(Vec3f from, Vec3f direction) const {
  if (!environmentTakesPartInMis() || environment_.isBlack()) return 0;
  const float total = selectionTotal(from);
  if (!(total > 0)) return 0;
  const Vec2f uv = directionToUv(direction);
  const float sinTheta = std::sin(uv.y * kPi);
  if (!(sinTheta > 0)) return 0;
  return environmentDistribution_.pdf(uv) / (2 * kPi * kPi * sinTheta) *
         (environmentWeight_ / total);
}

}  // namespace ferry
