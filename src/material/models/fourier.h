// pbrt-v3's FourierBSDF: a tabulated BSDF (material/fourier_bsdf_table.h)
// evaluated, sampled and given a density as pbrt-v3 does, in Ferry's local
// shading frame (normal +z, wo and wi pointing away from the surface):
// Catmull-Rom interpolation of the coefficients at (mu_i, mu_o), the Fourier
// series in the azimuth, pbrt-v3's radiance scaling across the interface.
// pdf() is exactly the density sampling has (0 where the series is <= 0).
// docs/path-tracer.md, "Materials" (Tabulated (Fourier) BSDF).
#pragma once

#include "core/math.h"
#include "material/bsdf.h"
#include "material/fourier_bsdf_table.h"
#include "material/material_model.h"

namespace ferry {

// pbrt-v3's FourierBSDF over `table` (which must outlive the Bsdf).
Bsdf fourierBsdf(const FourierBsdfTable& table);

// The table is the whole BSDF: the material's colour is used only where the
// table is not there (a grey diffuse).
struct FourierModel final : MaterialModel {
  int32_t table = kNoBsdfTable;  // in MaterialResources::bsdfTables

  FourierModel() = default;
  explicit FourierModel(int32_t table) : table(table) {}
  std::string_view name() const override { return "fourier"; }
  Bsdf bsdf(Vec3f color, const MaterialResources& resources) const override;
  int32_t bsdfTable() const override { return table; }
  void write(MaterialRecordWriter& record) const override { record.table(table); }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

// f(wo, wi) |cos(wi)|.
Vec3f fourierEval(const FourierBsdfTable& table, Vec3f wo, Vec3f wi);
float fourierPdf(const FourierBsdfTable& table, Vec3f wo, Vec3f wi);
// fourierEval, and fourierPdf into `pdf`, from one interpolation.
Vec3f fourierEvalPdf(const FourierBsdfTable& table, Vec3f wo, Vec3f wi, float& pdf);
// Draws wi from u; false when no direction is produced (or its value is 0).
bool fourierSample(const FourierBsdfTable& table, Vec3f wo, Vec2f u, BsdfSample& out);

// The spline and series pieces, exposed for tests.
namespace fourier {
// sum_k a[k] cos(k phi).
float series(const float* a, int32_t m, double cosPhi);
}  // namespace fourier

}  // namespace ferry
