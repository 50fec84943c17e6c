#include "material/models/dielectric.h"

#include <fmt/format.h>

#include "material/microfacet.h"
#include "material/models/dielectric_lobe.h"

namespace ferry {

Bsdf dielectricBsdf(float ior, float roughness, Vec3f tint) {
  const DielectricLobe lobe = DielectricLobe::make(ior, roughness, tint);
  return Bsdf(lobe, lobe.smooth, true);
}

std::shared_ptr<const MaterialModel> DielectricModel::read(MaterialRecordReader& record) {
  const float ior = record.number();
  const float roughness = record.number();
  return std::make_shared<DielectricModel>(ior, roughness);
}

std::string DielectricModel::describe() const {
  return fmt::format("dielectric (ior {:g}, roughness {:g})", ior, roughness);
}

}  // namespace ferry
