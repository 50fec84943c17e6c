#include "material/models/fresnel_blend.h"

#include <fmt/format.h>

#include "material/models/coated_diffuse.h"
#include "material/models/diffuse.h"

namespace ferry {

Bsdf fresnelBlendBsdf(Vec3f rd, Vec3f rs, float roughness) {
  CoatLobe lobe(rd, rs, roughness, 1.5f, false, 0);
  lobe.fresnelBlend = true;
  return Bsdf(lobe, false, false);
}

Bsdf FresnelBlendModel::bsdf(Vec3f color, const MaterialResources&) const {
  if (!(maxComponent(specular) > 0)) return diffuseBsdf(color);
  return fresnelBlendBsdf(color, specular, roughness);
}

std::shared_ptr<const MaterialModel> FresnelBlendModel::read(MaterialRecordReader& record) {
  auto m = std::make_shared<FresnelBlendModel>();
  m->specular = record.color();
  m->roughness = record.number();
  return m;
}

std::string FresnelBlendModel::describe() const {
  return fmt::format("FresnelBlend (coat ({:g}, {:g}, {:g}), roughness {:g})", specular.x,
                     specular.y, specular.z, roughness);
}

}  // namespace ferry
