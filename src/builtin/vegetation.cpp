#include "builtin/vegetation.h"

#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry::builtin {

Scatter::Scatter(ScatterRule rule, Ground ground, uint32_t key, uint64_t count)
    : rule_(rule), ground_(std::move(ground)), key_(key) {
  clusters_ = rule_.clusterSize > 0
                  ? std::max<uint64_t>(
                        1, (count + uint64_t(rule_.clusterSize) / 2) / uint64_t(rule_.clusterSize))
                  : 0;
  // The last resort for instances whose candidates were all rejected; found
  // once, by trying candidates until one is accepted.
  HashRng rng(key_, 0xa2c0);
  for (int attempt = 0; attempt < 100000; ++attempt) {
    Vec2f spot = ground_.sample(rng);
    float y;
    if (ground_.accept(spot, y)) {
      anchor_ = spot;
      anchorY_ = y;
      return;
    }
  }
  throw InternalError(fmt::format("scatter {:#x}: no allowed spot found for a species", key_));
}

bool Scatter::tryCandidates(HashRng& rng, const std::function<Vec2f(HashRng&)>& propose,
                            Vec2f& spot, float& y) const {
  for (int attempt = 0; attempt < rule_.attempts; ++attempt) {
    Vec2f candidate = propose(rng);
    if (ground_.accept(candidate, y)) {
      spot = candidate;
      return true;
    }
  }
  return false;
}

Vec2f Scatter::clusterCentre(uint64_t c, float& y) const {
  HashRng rng(key_, 0xc1, uint32_t(c), uint32_t(c >> 32));
  Vec2f spot;
  if (tryCandidates(rng, ground_.sample, spot, y)) return spot;
  y = anchorY_;
  return anchor_;
}

Affine3f Scatter::transform(uint64_t i) const {
  HashRng rng(key_, 0x1a5, uint32_t(i), uint32_t(i >> 32));
  Vec2f spot;
  float y = 0;
  if (clusters_ > 0) {
    float centreY;
    Vec2f centre = clusterCentre(i % clusters_, centreY);
    auto nearCentre = [&](HashRng& r) { return centre + r.inDisc() * rule_.clusterRadius; };
    if (!tryCandidates(rng, nearCentre, spot, y)) {
      spot = centre;
      y = centreY;
    }
  } else if (!tryCandidates(rng, ground_.sample, spot, y)) {
    spot = anchor_;
    y = anchorY_;
  }
  // Random numbers are drawn in a fixed order whatever happened above, from
  // a separate stream, so the shape of an instance does not depend on how
  // many candidates its placement took.
  HashRng shape(key_, 0x5ca1e, uint32_t(i), uint32_t(i >> 32));
  float scale = shape.uniform(rule_.scaleMin, rule_.scaleMax);
  float yaw = shape.uniform(0, 2 * kPi);
  float tiltAzimuth = shape.uniform(0, 2 * kPi);
  float tilt = rule_.tiltDegrees * kPi / 180 * shape.uniform();
  Affine3f lean = Affine3f::identity();
  if (rule_.slopeAlign > 0 && ground_.normal) {
    Vec3f n = ground_.normal(spot);
    Vec3f up = normalize(lerp(Vec3f(0, 1, 0), n, rule_.slopeAlign));
    Vec3f axis = cross(Vec3f(0, 1, 0), up);
    float s = length(axis);
    if (s > 1e-6f) lean = Affine3f::rotate(axis / s, std::asin(std::min(s, 1.0f)));
  }
  Affine3f tiltRotation =
      tilt > 0 ? Affine3f::rotate(Vec3f(std::cos(tiltAzimuth), 0, std::sin(tiltAzimuth)), tilt)
               : Affine3f::identity();
  return Affine3f::translate({spot.x, y - rule_.sink * scale, spot.y}) * lean * tiltRotation *
         Affine3f::rotate({0, 1, 0}, yaw) * Affine3f::scale(Vec3f(scale));
}

uint64_t variantShare(uint64_t count, uint64_t variants, uint64_t variant) {
  return count / variants + (variant < count % variants ? 1 : 0);
}

int32_t addPlantObject(ScenePlan& plan, const std::string& name, const PlantDesign& design,
                       const std::function<int32_t(const PlantPart&)>& material) {
  std::vector<int32_t> meshes;
  for (const PlantPart& part : design) {
    MeshRecipe r;
    r.name = name + "/" + part.name;
    r.material = material(part);
    r.counts = part.counts;
    r.hasNormals = part.hasNormals;
    r.hasUvs = part.hasUvs;
    r.build = part.build;
    meshes.push_back(plan.addMesh(std::move(r)));
  }
  return plan.addObject(name, std::move(meshes));
}

uint64_t scaledCount(double base, double scale) {
  double n = std::round(base * scale);
  return uint64_t(std::clamp(n, 1.0, 9.0e15));
}

std::vector<int32_t> addSpecies(ScenePlan& plan, const Species& species, uint32_t key) {
  FERRY_CHECK_GE(species.count, 1);
  FERRY_CHECK_GE(species.variants, 1);
  const uint64_t variants = std::min<uint64_t>(uint64_t(species.variants), species.count);
  auto scatter = std::make_shared<const Scatter>(species.rule, species.ground, key, species.count);
  std::vector<int32_t> objects;
  uint64_t first = 0;
  for (uint64_t v = 0; v < variants; ++v) {
    int variant = int(v);
    int32_t object =
        addPlantObject(plan, fmt::format("{}/{}", species.name, v), species.design(variant),
                       [&](const PlantPart& part) { return species.material(part, variant); });
    uint64_t n = variantShare(species.count, variants, v);
    plan.addInstances(object, n,
                      [scatter, first](uint64_t i) { return scatter->transform(first + i); });
    first += n;
    objects.push_back(object);
  }
  return objects;
}

void addSpecies(ScenePlan& plan, const std::vector<Species>& species, uint32_t key) {
  for (size_t k = 0; k < species.size(); ++k)
    addSpecies(plan, species[k], streamKey(key, uint32_t(k)));
}

}  // namespace ferry::builtin
