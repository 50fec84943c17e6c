// The material family's seam: every built-in model writes and reads its own
// record, and a model that only this test defines (its parameters, its lobe,
// its record, nothing else in Ferry touched) is rendered and travels through
// a part file by its registered name.
#include "material/material_model.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/error.h"
#include "io/parts/part_file.h"
#include "material/models/coated_conductor.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"
#include "material/models/diffuse_transmission.h"
#include "material/models/fourier.h"
#include "material/models/fresnel_blend.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;
namespace fs = std::filesystem;

std::vector<uint8_t> recordOf(const MaterialModel& model) {
  MaterialRecordWriter w;
  model.write(w);
  return w.bytes();
}

TEST(MaterialModels, EveryBuiltInModelReadsBackWhatItWrites) {
  auto coated = std::make_shared<CoatedDiffuseModel>();
  coated->specular = {0.1f, 0.2f, 0.3f};
  coated->layered = true;
  coated->sigmaDegrees = 12;
  auto coatedMetal = std::make_shared<CoatedConductorModel>();
  coatedMetal->baseRoughness = 0.2f;
  auto blend = std::make_shared<FresnelBlendModel>();
  blend->roughness = 0.6f;
  const std::vector<std::shared_ptr<const MaterialModel>> models = {
      std::make_shared<DiffuseModel>(20.0f),
      std::make_shared<ConductorModel>(0.3f),
      std::make_shared<DielectricModel>(1.33f, 0.1f),
      coated,
      coatedMetal,
      blend,
      std::make_shared<DiffuseTransmissionModel>(Vec3f(0.1f, 0.2f, 0.3f)),
      std::make_shared<FourierModel>(2)};
  ASSERT_GE(materialModelKinds().size(), models.size());
  for (const auto& model : models) {
    const MaterialModelKind* kind = materialModelKind(model->name());
    ASSERT_NE(kind, nullptr) << model->name();
    const std::vector<uint8_t> bytes = recordOf(*model);
    MaterialRecordReader reader(bytes, "test", 3);
    const std::shared_ptr<const MaterialModel> back = kind->read(reader);
    reader.finish();
    EXPECT_EQ(back->name(), model->name());
    EXPECT_EQ(recordOf(*back), bytes) << model->describe();
    EXPECT_EQ(back->describe(), model->describe());
  }
}

TEST(MaterialModels, ABadRecordIsAnErrorNamingWhereItIs) {
  const std::vector<uint8_t> bytes = recordOf(DielectricModel(1.5f, 0));
  // Short.
  MaterialRecordReader shortRecord(std::span<const uint8_t>(bytes).first(5),
                                   "part.bin: material \"glass\"", 0);
  EXPECT_THROW(DielectricModel::read(shortRecord), InputError);
  // Long.
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  MaterialRecordReader longRecord(longer, "part.bin: material \"glass\"", 0);
  DielectricModel::read(longRecord);
  try {
    longRecord.finish();
    FAIL() << "a record with bytes left over was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("material \"glass\""), std::string::npos) << e.what();
  }
  // A table that is not there.
  const std::vector<uint8_t> table = recordOf(FourierModel(4));
  MaterialRecordReader missing(table, "t", 2);
  EXPECT_THROW(FourierModel::read(missing), InputError);
}

// ------------------------------------------------------------ a test-only model

// A retroreflector: every ray goes back the way it came, tinted. No model in
// Ferry scatters like this, so an image of it shows that its own lobe ran.
struct RetroreflectorLobe {
  Vec3f tint;
  Vec3f eval(Vec3f, Vec3f) const { return Vec3f(0); }
  float pdf(Vec3f, Vec3f) const { return 0; }
  bool sample(Vec3f wo, float, Vec2f, BsdfSample& out) const {
    if (wo.z <= 0) return false;
    out.wi = wo;
    out.weight = tint;
    out.pdf = 1;
    out.delta = true;
    return true;
  }
};

struct RetroreflectorModel final : MaterialModel {
  Vec3f tint{1};
  explicit RetroreflectorModel(Vec3f t) : tint(t) {}
  std::string_view name() const override { return "test-retroreflector"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override {
    return Bsdf(RetroreflectorLobe{color * tint}, true, false);
  }
  void write(MaterialRecordWriter& record) const override { record.pod(tint); }
  std::string describe() const override { return "retroreflector"; }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record) {
    return std::make_shared<RetroreflectorModel>(record.color());
  }
};

void registerRetroreflector() {
  static const bool once = [] {
    registerMaterialModel(
        {"test-retroreflector", "a test's retroreflector", RetroreflectorModel::read});
    return true;
  }();
  (void)once;
}

// A square of `material` filling a narrow view under a white sky.
Scene squareUnderWhiteSky(const Material& material) {
  Scene scene;
  scene.name = "retroreflector";
  const int32_t m = scene.addMaterial(material);
  scene.addSingleInstanceMesh(makeQuad({-5, -5, 0}, {10, 0, 0}, {0, 10, 0}, m));
  scene.environment.color = Vec3f(1);
  CameraView view;
  view.from = {0.3f, 0.2f, 10};
  view.at = {0, 0, 0};
  view.fovY = 20;
  scene.views.push_back(view);
  return scene;
}

std::vector<Vec3f> render(const Scene& scene) {
  RenderSettings settings;
  settings.width = settings.height = 8;
  settings.samplesPerPixel = 4;
  settings.maxDepth = 3;
  RenderSetup setup(scene, settings);
  return setup.frameMean(0);
}

TEST(MaterialModels, ATestOnlyModelIsRenderedByItsOwnLobe) {
  registerRetroreflector();
  Material retro = diffuseMaterial(Vec3f(0.5f));
  retro.model = std::make_shared<RetroreflectorModel>(Vec3f(1, 0.5f, 0.25f));
  const std::vector<Vec3f> image = render(squareUnderWhiteSky(retro));
  // Every camera ray comes back to the sky behind the camera: colour x tint.
  const Vec3f expected{0.5f, 0.25f, 0.125f};
  for (const Vec3f& p : image)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(p[k], expected[k], 2 * kHalfRelativeError) << k;
  // Lambertian of the same colour shows the colour, not the tint.
  const std::vector<Vec3f> lambert = render(squareUnderWhiteSky(diffuseMaterial(Vec3f(0.5f))));
  double blue = 0;
  for (const Vec3f& p : lambert) blue += p.z / double(lambert.size());
  EXPECT_GT(blue, 0.3);
}

TEST(MaterialModels, ATestOnlyModelTravelsThroughAPartFileByItsName) {
  registerRetroreflector();
  Material retro = diffuseMaterial(Vec3f(0.5f));
  retro.name = "retro";
  retro.model = std::make_shared<RetroreflectorModel>(Vec3f(1, 0.5f, 0.25f));
  const Scene scene = squareUnderWhiteSky(retro);
  const fs::path path = fs::temp_directory_path() / fmt::format("ferry-model-{}.part", ::getpid());
  writePartFile(path.string(), scene, {0}, {RankSet::single(0)}, 0, 1);
  LoadedPart part = readPartFile(path.string());
  fs::remove(path);
  ASSERT_EQ(part.scene.materials.size(), 1u);
  const auto* back = dynamic_cast<const RetroreflectorModel*>(part.scene.materials[0].model.get());
  ASSERT_NE(back, nullptr) << part.scene.materials[0].model->name();
  EXPECT_EQ(back->tint, Vec3f(1, 0.5f, 0.25f));
  part.scene.environment = scene.environment;
  part.scene.views = scene.views;
  EXPECT_EQ(render(part.scene), render(scene));
}

// A model this Ferry does not know, in a part file: one error naming the
// file, the material and the model.
struct UnregisteredModel final : MaterialModel {
  std::string_view name() const override { return "test-unregistered"; }
  Bsdf bsdf(Vec3f, const MaterialResources&) const override { return Bsdf(); }
  void write(MaterialRecordWriter&) const override {}
  std::string describe() const override { return "unregistered"; }
};

TEST(MaterialModels, APartFileWithAnUnknownModelIsAnError) {
  Material odd = diffuseMaterial(Vec3f(0.5f));
  odd.name = "odd";
  odd.model = std::make_shared<UnregisteredModel>();
  const Scene scene = squareUnderWhiteSky(odd);
  const fs::path path = fs::temp_directory_path() / fmt::format("ferry-odd-{}.part", ::getpid());
  writePartFile(path.string(), scene, {0}, {RankSet::single(0)}, 0, 1);
  try {
    readPartFile(path.string());
    FAIL() << "an unknown model was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("\"odd\""), std::string::npos) << what;
    EXPECT_NE(what.find("test-unregistered"), std::string::npos) << what;
  }
  fs::remove(path);
}

}  // namespace
}  // namespace ferry
