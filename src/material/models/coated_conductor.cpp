#include "material/models/coated_conductor.h"

#include <fmt/format.h>

#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"

namespace ferry {

Bsdf coatedConductorBsdf(Vec3f f0, float baseRoughness, Vec3f specular, float roughness,
                         float eta) {
  CoatLobe lobe(f0, specular, roughness, eta, true, 0);
  lobe.baseAlpha = std::max(baseRoughness * baseRoughness, 2e-3f);
  return Bsdf(lobe, false, false);
}

Bsdf CoatedConductorModel::bsdf(Vec3f color, const MaterialResources&) const {
  if (!(maxComponent(specular) > 0)) return conductorBsdf(color, baseRoughness);
  return coatedConductorBsdf(color, baseRoughness, specular, roughness, eta);
}

void CoatedConductorModel::write(MaterialRecordWriter& record) const {
  record.pod(baseRoughness);
  record.pod(specular);
  record.pod(roughness);
  record.pod(eta);
}

std::shared_ptr<const MaterialModel> CoatedConductorModel::read(MaterialRecordReader& record) {
  auto m = std::make_shared<CoatedConductorModel>();
  m->baseRoughness = record.number();
  m->specular = record.color();
  m->roughness = record.number();
  m->eta = record.number();
  return m;
}

std::string CoatedConductorModel::describe() const {
  return fmt::format(
      "coated conductor (roughness {:g}, coat ({:g}, {:g}, {:g}), roughness {:g}, "
      "eta {:g})",
      baseRoughness, specular.x, specular.y, specular.z, roughness, eta);
}

}  // namespace ferry
