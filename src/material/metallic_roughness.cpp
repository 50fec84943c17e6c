#include "material/metallic_roughness.h"

#include "material/models/coated_conductor.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"

namespace ferry {

std::shared_ptr<const MaterialModel> modelOf(const MetallicRoughness& s) {
  const bool coated = maxComponent(s.coat) > 0;
  if (s.transmission >= 0.5f) return std::make_shared<DielectricModel>(s.ior, s.roughness);
  if (s.metallic >= 0.5f && coated) {
    auto m = std::make_shared<CoatedConductorModel>();
    m->baseRoughness = s.roughness;
    m->specular = s.coat;
    m->roughness = s.coatRoughness;
    m->eta = s.coatEta;
    return m;
  }
  if (s.metallic >= 0.5f) return std::make_shared<ConductorModel>(s.roughness);
  if (coated) {
    auto m = std::make_shared<CoatedDiffuseModel>();
    m->specular = s.coat;
    m->roughness = s.coatRoughness;
    m->eta = s.coatEta;
    m->layered = s.coatLayered;
    return m;
  }
  return defaultMaterialModel();
}

}  // namespace ferry
