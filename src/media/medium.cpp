#include "media/medium.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/perlin_noise.h"

namespace ferry {

size_t RgbGrids::bytes() const {
  size_t b = 0;
  for (const Channels* g : {&sigmaA, &sigmaS, &emission})
    for (const auto& channel : *g)
      if (channel) b += channel->bytes();
  return b;
}

float CloudDensity::at(Vec3f unit) const {
  const Vec3f p = box.lower + unit * box.size();
  Vec3f pp = p * frequency;
  if (wispiness > 0) {
    // Noise displaces the lookup, in two octaves.
    float omega = 0.05f * wispiness, lambda = 10;
    for (int i = 0; i < 2; ++i) {
      pp = pp + perlinNoiseSlope(pp * lambda) * omega;
      omega *= 0.5f;
      lambda *= 1.99f;
    }
  }
  float d = 0, omega = 0.5f, lambda = 1;
  for (int i = 0; i < 5; ++i) {
    d += omega * perlinNoise(pp * lambda);
    omega *= 0.5f;
    lambda *= 1.99f;
  }
  // Thinning with height (the medium's y).
  d = std::clamp((1 - p.y) * 4.5f * density * d, 0.0f, 1.0f);
  d += 2 * std::max(0.0f, 0.5f - p.y);
  return std::clamp(d, 0.0f, 1.0f);
}

Vec3f TemperatureEmission::at(Vec3f unit) const {
  const float t = (kelvin->lookup(unitOffset + unit * unitScale) - offset) * scale;
  if (!(t > 100) || table.empty()) return Vec3f(0);
  const float x = t / step;
  const size_t i = size_t(x);
  if (i + 1 >= table.size()) return table.back();
  const float f = x - float(i);
  return table[i] * (1 - f) + table[i + 1] * f;
}

Vec3f Medium::emittedAt(Vec3f unit) const {
  if (rgb) return RgbGrids::lookup(rgb->emission, unit, 0) * emission;
  Vec3f e = temperature ? temperature->at(unit) * emission : emission;
  if (emissionScale) e = e * emissionScale->lookup(unit);
  return e;
}

Affine3f unitFromBox(const Box3f& box) {
  const Vec3f size = box.size();
  return Affine3f::scale({1 / size.x, 1 / size.y, 1 / size.z}) * Affine3f::translate(-box.lower);
}

namespace {

size_t majorantBytes(size_t cx, size_t cy, size_t cz) {
  return cx * cy * cz * (sizeof(float) + sizeof(Vec3f));
}

}  // namespace

size_t Medium::bytes() const {
  size_t b = sizeof(Medium);
  if (density) b += density->bytes();
  if (rgb) b += rgb->bytes();
  if (emissionScale) b += emissionScale->bytes();
  if (temperature) b += temperature->kelvin->bytes() + temperature->table.size() * sizeof(Vec3f);
  if (majorants)
    b += majorantBytes(size_t(majorants->cells(0)), size_t(majorants->cells(1)),
                       size_t(majorants->cells(2)));
  return b;
}

size_t gridMediumBytes(int nx, int ny, int nz) {
  // The majorant grid: one cell a voxel, at most kMajorantCells a side.
  auto cells = [](int n) { return size_t(std::clamp(n, 1, kMajorantCells)); };
  return sizeof(Medium) + size_t(nx) * size_t(ny) * size_t(nz) * sizeof(float) +
         majorantBytes(cells(nx), cells(ny), cells(nz));
}

Medium gridMedium(std::string name, Vec3f sigmaA, Vec3f sigmaS, float g,
                  std::shared_ptr<const DensityGrid> density, const Affine3f& worldFromMedium,
                  const Box3f& box) {
  Medium m;
  m.name = std::move(name);
  m.sigmaA = sigmaA;
  m.sigmaS = sigmaS;
  m.g = g;
  const Vec3f sigmaT = sigmaA + sigmaS;
  m.majorants =
      std::make_shared<MajorantGrid>(*density, [sigmaT](float /*lo*/, float hi, float mean) {
        return std::pair{hi * maxComponent(sigmaT), sigmaT * mean};
      });
  m.density = std::move(density);
  m.gridFromWorld = unitFromBox(box) * worldFromMedium.inverse();
  return m;
}

Medium rgbGridMedium(std::string name, std::shared_ptr<const RgbGrids> grids, float sigmaScale,
                     float emissionScale, float g, const Affine3f& worldFromMedium,
                     const Box3f& box) {
  // Each voxel's largest extinction (pbrt-v4's: the largest sigma_a and the
  // largest sigma_s of any channel, added), for the majorants and for info.
  const DensityGrid* shape = nullptr;
  for (const RgbGrids::Channels* c : {&grids->sigmaA, &grids->sigmaS})
    if ((*c)[0]) shape = (*c)[0].get();
  if (!shape) throw std::invalid_argument("an rgb grid needs sigma_a or sigma_s");
  std::vector<float> largest(shape->values().size());
  for (size_t i = 0; i < largest.size(); ++i) {
    float a = 1, s = 1;
    if (grids->sigmaA[0])
      a = std::max({grids->sigmaA[0]->values()[i], grids->sigmaA[1]->values()[i],
                    grids->sigmaA[2]->values()[i]});
    if (grids->sigmaS[0])
      s = std::max({grids->sigmaS[0]->values()[i], grids->sigmaS[1]->values()[i],
                    grids->sigmaS[2]->values()[i]});
    largest[i] = (a + s) * sigmaScale;
  }
  Medium m;
  m.name = std::move(name);
  m.sigmaA = m.sigmaS = Vec3f(sigmaScale);
  m.g = g;
  m.emission = grids->emission[0] ? Vec3f(emissionScale) : Vec3f(0);
  m.density =
      std::make_shared<DensityGrid>(shape->nx(), shape->ny(), shape->nz(), std::move(largest));
  m.majorants = std::make_shared<MajorantGrid>(*m.density, [](float, float hi, float) {
    return std::pair{hi, Vec3f(0)};
  });
  m.rgb = std::move(grids);
  m.gridFromWorld = unitFromBox(box) * worldFromMedium.inverse();
  return m;
}

Medium cloudMedium(std::string name, Vec3f sigmaA, Vec3f sigmaS, float g, CloudDensity cloud,
                   const Affine3f& worldFromMedium) {
  Medium m;
  m.name = std::move(name);
  m.sigmaA = sigmaA;
  m.sigmaS = sigmaS;
  m.g = g;
  // The density is at most 1: sigma_t bounds it everywhere (as in pbrt-v4).
  m.majorants = std::make_shared<MajorantGrid>(maxComponent(sigmaA + sigmaS), Vec3f(0));
  m.gridFromWorld = unitFromBox(cloud.box) * worldFromMedium.inverse();
  m.cloud = std::make_shared<CloudDensity>(cloud);
  return m;
}

Medium transferFunctionMedium(std::string name, std::shared_ptr<const DensityGrid> values,
                              std::shared_ptr<const TransferFunction> transfer, const Box3f& box) {
  Medium m;
  m.name = std::move(name);
  m.density = std::move(values);
  m.gridFromWorld = unitFromBox(box);
  setTransferFunction(m, std::move(transfer));
  return m;
}

void setTransferFunction(Medium& m, std::shared_ptr<const TransferFunction> transfer) {
  const TransferFunction& tf = *transfer;
  auto extinction = [&tf](float lo, float hi, float mean) {
    const auto [smallest, largest] = tf.opacityRange(lo, hi);
    return std::pair{largest * tf.scale(), Vec3f(tf.opacity(mean) * tf.scale())};
  };
  // A change keeps the cells' value ranges: no pass over the grid.
  m.majorants = m.majorants ? std::make_shared<MajorantGrid>(*m.majorants, extinction)
                            : std::make_shared<MajorantGrid>(*m.density, extinction);
  m.transfer = std::move(transfer);
}

}  // namespace ferry
