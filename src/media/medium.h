// A participating medium as pbrt defines one: absorption and scattering
// coefficients per RGB channel (per unit of world length, at density 1), a
// Henyey-Greenstein phase function, emitted radiance, and a density that
// scales the coefficients: 1 everywhere (homogeneous) or a grid over a box
// (pbrt-v3's heterogeneous, pbrt-v4's uniformgrid), 0 outside the box.
// Where a medium is, is said by the surfaces that bound it (their
// MediumInterface) and the camera's medium; a medium itself is unbounded.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "media/density_grid.h"
#include "media/majorant_grid.h"
#include "media/transfer_function.h"

namespace ferry {

// Which medium is on each side of a surface: indices into Scene::media,
// kNoMedium for vacuum. `outside` is on the side the surface's geometric
// normal points to. A surface with inside == outside bounds no medium: a
// ray scattering there stays in the medium it was in (pbrt's rule).
constexpr int32_t kNoMedium = -1;
struct MediumInterface {
  int32_t inside = kNoMedium;
  int32_t outside = kNoMedium;

  bool isTransition() const { return inside != outside; }
  // The medium a ray leaving the surface along `direction` enters.
  int32_t along(Vec3f direction, Vec3f geometricNormal) const {
    return dot(direction, geometricNormal) > 0 ? outside : inside;
  }
  bool operator==(const MediumInterface&) const = default;
};

// pbrt-v4's rgbgrid: sigma_a, sigma_s and Le per voxel, each channel a grid
// over the unit cube (a null grid: sigma 1, Le 0 in every channel).
struct RgbGrids {
  using Channels = std::array<std::shared_ptr<const DensityGrid>, 3>;
  Channels sigmaA, sigmaS, emission;
  // The three channels of `grids` at `unit`, `absent` where a grid is null.
  static Vec3f lookup(const Channels& grids, Vec3f unit, float absent) {
    Vec3f v;
    for (int c = 0; c < 3; ++c) v[c] = grids[c] ? grids[c]->lookup(unit) : absent;
    return v;
  }
  size_t bytes() const;
};

// pbrt-v4's cloud: a density in [0, 1] made of noise and thinning with
// height, a function of the medium's own space over its box.
struct CloudDensity {
  float density = 1;    // pbrt's "density"
  float wispiness = 1;  // how far noise displaces the lookup
  float frequency = 5;  // of the noise, per unit of the medium's space
  Box3f box;            // the medium's box (the unit cube's corners in medium space)
  float at(Vec3f unit) const;
};

// Light emitted by temperature (pbrt-v4's grid and nanovdb media): a
// blackbody (Planck's law, 1 at its peak, as RGB) at (T - offset) x scale
// kelvin, T looked up in its own grid; nothing at 100 K or below.
struct TemperatureEmission {
  std::shared_ptr<const DensityGrid> kelvin;
  Vec3f unitOffset{0, 0, 0}, unitScale{1, 1, 1};  // its unit cube from the medium's
  float offset = 0, scale = 1;
  // Blackbody RGB every `step` kelvin from 0 (linear in between, held beyond the last).
  std::vector<Vec3f> table;
  float step = 1;
  Vec3f at(Vec3f unit) const;
};

struct Medium {
  std::string name;
  Vec3f sigmaA{0, 0, 0};  // absorption at density 1 (pbrt's sigma_a times scale)
  Vec3f sigmaS{0, 0, 0};  // scattering at density 1
  float g = 0;            // Henyey-Greenstein asymmetry, in (-1, 1)
  // Radiance emitted where light is absorbed (pbrt-v4's Le x Lescale); for
  // a grid medium times emissionScale there, for rgbgrid times its Le grids,
  // with a temperature the blackbody's scale.
  Vec3f emission{0, 0, 0};
  // Null: homogeneous (density 1 everywhere). Else the density over the box
  // that gridFromWorld maps to the unit cube, with its majorants.
  std::shared_ptr<const DensityGrid> density;
  std::shared_ptr<const MajorantGrid> majorants;
  Affine3f gridFromWorld;
  // A sci-vis volume: the grid holds values in [0, 1] that this maps to
  // extinction and albedo (sigmaA and sigmaS are then unused).
  std::shared_ptr<const TransferFunction> transfer;
  // pbrt-v4's rgbgrid (sigmaA and sigmaS are then the scales of its grids;
  // `density` holds each voxel's largest extinction, for the majorants).
  std::shared_ptr<const RgbGrids> rgb;
  // pbrt-v4's cloud (no `density`; one majorant, the largest sigma_t).
  std::shared_ptr<const CloudDensity> cloud;
  // Grid media: pbrt-v4's "Lescale" grid (null: 1 everywhere), and emission
  // by temperature instead of a constant Le.
  std::shared_ptr<const DensityGrid> emissionScale;
  std::shared_ptr<const TemperatureEmission> temperature;
  // The inside of a subsurface material (material/models/subsurface.h),
  // homogeneous: paths walk through it without light samples, and its
  // scattering events do not count as bounces.
  bool subsurface = false;

  bool homogeneous() const { return density == nullptr && cloud == nullptr; }
  Vec3f sigmaT() const { return sigmaA + sigmaS; }
  // A grid medium's coefficients at `unit` (the unit cube's coordinates).
  void coefficients(Vec3f unit, Vec3f& sa, Vec3f& ss) const {
    if (rgb) {
      sa = RgbGrids::lookup(rgb->sigmaA, unit, 1) * sigmaA;
      ss = RgbGrids::lookup(rgb->sigmaS, unit, 1) * sigmaS;
      return;
    }
    const float v = cloud ? cloud->at(unit) : density->lookup(unit);
    if (transfer) {
      const float t = transfer->scale() * transfer->opacity(v);
      ss = transfer->color(v) * t;
      sa = Vec3f(t) - ss;
    } else {
      sa = sigmaA * v;
      ss = sigmaS * v;
    }
  }
  bool emits() const { return maxComponent(emission) > 0; }
  // A grid medium's emitted radiance at `unit` (per unit of absorption).
  Vec3f emittedAt(Vec3f unit) const;
  // Bytes it holds (its grid and majorants).
  size_t bytes() const;
};

// The bytes gridMedium's result holds for an nx x ny x nz density (its
// Medium::bytes(), known before the grid is made).
size_t gridMediumBytes(int nx, int ny, int nz);

// A grid medium: the density over `box` (in the medium's space, which
// `worldFromMedium` places; pbrt's p0 and p1 under the CTM at MakeNamedMedium).
Medium gridMedium(std::string name, Vec3f sigmaA, Vec3f sigmaS, float g,
                  std::shared_ptr<const DensityGrid> density, const Affine3f& worldFromMedium,
                  const Box3f& box);
// The box's corners to the unit cube's (a grid's gridFromWorld over `box`).
Affine3f unitFromBox(const Box3f& box);
// A sci-vis volume: values in [0, 1] over `box` (world space), rendered
// through `transfer` (isotropic scattering).
Medium transferFunctionMedium(std::string name, std::shared_ptr<const DensityGrid> values,
                              std::shared_ptr<const TransferFunction> transfer, const Box3f& box);
// pbrt-v4's rgbgrid over `box` (medium space, placed by `worldFromMedium`):
// `grids` times `sigmaScale`, emission times `emissionScale`.
Medium rgbGridMedium(std::string name, std::shared_ptr<const RgbGrids> grids, float sigmaScale,
                     float emissionScale, float g, const Affine3f& worldFromMedium,
                     const Box3f& box);
// pbrt-v4's cloud over `cloud.box` (medium space, placed by `worldFromMedium`).
Medium cloudMedium(std::string name, Vec3f sigmaA, Vec3f sigmaS, float g, CloudDensity cloud,
                   const Affine3f& worldFromMedium);
// Rebuilds the majorants after the transfer function changed.
void setTransferFunction(Medium& medium, std::shared_ptr<const TransferFunction> transfer);

}  // namespace ferry
