// pbrt-v3's FourierBSDF: a tabulated BSDF (scene/fourier_bsdf_table.h)
// evaluated, sampled and given a density as pbrt-v3 does, in Ferry's local
// shading frame (normal +z, wo and wi pointing away from the surface).
//
// f(wo, wi): the coefficients Catmull-Rom interpolated at mu_i = cos(-wi)
// and mu_o = cos(wo) (16 entries), the series summed at cos(phi) between -wi
// and wo; luminance clamped at 0, and with three channels red and blue summed
// too and green derived from them (pbrt-v3's weights), clamped at 0. It is
// divided by |mu_i| and, for radiance crossing the interface (mu_i mu_o > 0),
// scaled by (1/eta)^2 entering the top or eta^2 leaving it, as pbrt-v3 does
// for radiance transport. eval() returns f |cos(wi)|, so the 1/|mu_i| cancels.
//
// Sampling: mu_i from the 2D Catmull-Rom spline of the zeroth luminance
// coefficient over (mu_o, mu_i), by inverting the table's cdf row
// interpolated at mu_o; phi from the luminance series at that (mu_i, mu_o).
// Its density is Y(phi) / (2 pi rho(mu_o)), rho the interpolated last cdf
// entry: what pdf() returns (0 where Y <= 0).
#pragma once

#include "core/math.h"
#include "render/bsdf.h"
#include "scene/fourier_bsdf_table.h"

namespace ferry {

// f(wo, wi) |cos(wi)|.
Vec3f fourierEval(const FourierBsdfTable& table, Vec3f wo, Vec3f wi);
float fourierPdf(const FourierBsdfTable& table, Vec3f wo, Vec3f wi);
// Draws wi from u; false when no direction is produced (or its value is 0).
bool fourierSample(const FourierBsdfTable& table, Vec3f wo, Vec2f u, BsdfSample& out);

// The spline and series pieces, exposed for tests.
namespace fourier {
// Catmull-Rom weights of the 4 nodes from `offset` for x (pbrt's
// CatmullRomWeights: finite-difference derivatives, end nodes clamped);
// false when x is outside the nodes.
bool catmullRomWeights(const float* nodes, int32_t n, float x, int32_t& offset, float weights[4]);
// sum_k a[k] cos(k phi).
float series(const float* a, int32_t m, double cosPhi);
}  // namespace fourier

}  // namespace ferry
