// The registry: every material model by name. A new model adds its line here.
#include "core/error.h"
#include "core/registry.h"
#include "material/material_model.h"
#include "material/models/coated_conductor.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"
#include "material/models/diffuse_transmission.h"
#include "material/models/fourier.h"
#include "material/models/fresnel_blend.h"
#include "material/models/hair.h"
#include "material/models/layered.h"
#include "material/models/subsurface.h"
#include "material/models/thin_dielectric.h"

namespace ferry {
namespace {

Registry<MaterialModelKind>& registry() {
  static Registry<MaterialModelKind> all(
      "material model",
      {
          {"diffuse", "Lambertian, or Oren-Nayar (pbrt's matte, diffuse)", DiffuseModel::read},
          {"conductor", "a metal: Schlick Fresnel, mirror or GGX (pbrt's metal, conductor, mirror)",
           ConductorModel::read},
          {"dielectric", "glass, water: smooth or GGX reflection and refraction (pbrt's glass)",
           DielectricModel::read},
          {"coated-diffuse",
           "a diffuse base under a GGX coat (pbrt's plastic, coateddiffuse, uber)",
           CoatedDiffuseModel::read},
          {"coated-conductor", "a GGX conductor under a layered coat (pbrt's coatedconductor)",
           CoatedConductorModel::read},
          {"thin-dielectric",
           "a thin sheet: mirror reflection of both faces, the rest straight through (pbrt-v4's "
           "thindielectric)",
           ThinDielectricModel::read},
          {"layered",
           "a diffuse or conductor base under a dielectric interface, a random walk between "
           "them (pbrt-v4's coateddiffuse, coatedconductor)",
           LayeredModel::read},
          {"fresnel-blend", "Ashikhmin-Shirley's FresnelBlend (pbrt-v3's substrate)",
           FresnelBlendModel::read},
          {"diffuse-transmission", "a thin diffuse sheet (pbrt's translucent, diffusetransmission)",
           DiffuseTransmissionModel::read},
          {"hair", "a fibre: Chiang et al.'s R, TT, TRT lobes (pbrt's hair)", HairModel::read},
          {"subsurface",
           "a dielectric surface over a scattering medium, walked through (pbrt's subsurface, "
           "kdsubsurface)",
           SubsurfaceModel::read},
          {"fourier", "a tabulated BSDF, pbrt-v3's fourier material (.bsdf files)",
           FourierModel::read},
      });
  return all;
}

}  // namespace

const std::deque<MaterialModelKind>& materialModelKinds() {
  return registry().all();
}

const MaterialModelKind* materialModelKind(std::string_view name) {
  return registry().find(name);
}

void registerMaterialModel(MaterialModelKind kind) {
  registry().add(std::move(kind));
}

std::string materialModelNames() {
  return registry().names();
}

std::shared_ptr<const MaterialModel> withBsdfTablesRenumbered(
    const std::shared_ptr<const MaterialModel>& model,
    const MaterialRecordWriter::TableIndex& newIndex) {
  if (model->bsdfTable() == kNoBsdfTable) return model;
  MaterialRecordWriter record(newIndex);
  model->write(record);
  const MaterialModelKind* kind = materialModelKind(model->name());
  if (!kind)
    throw InternalError(fmt::format("material model \"{}\" is not registered", model->name()));
  MaterialRecordReader reader(record.bytes(), std::string(model->name()), SIZE_MAX);
  return kind->read(reader);
}

std::shared_ptr<const MaterialModel> defaultMaterialModel() {
  static const std::shared_ptr<const MaterialModel> lambertian = std::make_shared<DiffuseModel>();
  return lambertian;
}

}  // namespace ferry
