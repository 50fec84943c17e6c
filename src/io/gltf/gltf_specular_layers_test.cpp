#include "io/gltf/gltf_specular_layers.h"

#include <gtest/gtest.h>

#include "material/bsdf.h"

namespace ferry {
namespace {

TEST(GltfSpecularLayers, PlainMaterialIsAWhiteCoatWithItsIorAndRoughness) {
  GltfSpecularLayers layers;
  layers.roughness = 0.4f;
  FerryCoat coat = ferryCoatOf(layers);
  EXPECT_EQ(coat.tint, Vec3f(1));
  EXPECT_EQ(coat.eta, 1.5f);
  EXPECT_EQ(coat.roughness, 0.4f);
  layers.ior = 1.33f;
  EXPECT_EQ(ferryCoatOf(layers).eta, 1.33f);
}

TEST(GltfSpecularLayers, F0AndEtaAreInverses) {
  EXPECT_NEAR(f0OfEta(1.5f), 0.04f, 1e-7);
  EXPECT_EQ(f0OfEta(0), 1.0f);  // glTF's legacy ior 0
  for (float eta : {1.0f, 1.2f, 1.5f, 2.4f, 10.0f})
    EXPECT_NEAR(etaOfF0(f0OfEta(eta)), eta, 1e-4f * eta);
  // Ferry's Fresnel term at normal incidence is the F0 the spec asks for.
  EXPECT_NEAR(fresnelDielectric(1, etaOfF0(0.08f)), 0.08f, 1e-5);
}

// At normal incidence Ferry's coat reflects tint * F0(eta): glTF's
// specularFactor * min(F0(ior) * specularColor, 1), channel by channel.
Vec3f normalIncidence(const FerryCoat& coat) {
  return coat.tint * fresnelDielectric(1, coat.eta);
}

TEST(GltfSpecularLayers, SpecularFactorAndColourKeepNormalIncidenceReflectance) {
  GltfSpecularLayers layers;
  layers.specularFactor = 0.5f;
  layers.specularColor = {0.5f, 1, 0.25f};
  FerryCoat coat = ferryCoatOf(layers);
  EXPECT_EQ(coat.eta, 1.5f);  // the largest channel is 1: the ior itself
  EXPECT_EQ(coat.tint, Vec3f(0.25f, 0.5f, 0.125f));

  // A colour whose largest channel is not 1 moves it into eta: a grey
  // colour keeps glTF's f90 (the tint stays specularFactor).
  for (Vec3f color : {Vec3f(0.5f), Vec3f(2.0f), Vec3f(3, 1.5f, 0)}) {
    layers.specularColor = color;
    coat = ferryCoatOf(layers);
    Vec3f want = min(color * 0.04f, Vec3f(1)) * layers.specularFactor;
    Vec3f got = normalIncidence(coat);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-5f) << c;
    EXPECT_NEAR(maxComponent(coat.tint), layers.specularFactor, 1e-6f);
  }
}

TEST(GltfSpecularLayers, NoSpecularIsNoCoat) {
  GltfSpecularLayers layers;
  layers.specularFactor = 0;
  EXPECT_EQ(ferryCoatOf(layers).tint, Vec3f(0));
  layers.specularFactor = 1;
  layers.specularColor = Vec3f(0);
  EXPECT_EQ(ferryCoatOf(layers).tint, Vec3f(0));
  layers.specularColor = Vec3f(1);
  layers.ior = 1;  // no interface
  EXPECT_EQ(ferryCoatOf(layers).tint, Vec3f(0));
}

TEST(GltfSpecularLayers, LegacyIorZeroMakesTheColourTheReflectance) {
  GltfSpecularLayers layers;
  layers.ior = 0;
  layers.specularColor = {0.5f, 0.25f, 0};
  FerryCoat coat = ferryCoatOf(layers);
  Vec3f got = normalIncidence(coat);
  EXPECT_NEAR(got.x, 0.5f, 1e-5f);
  EXPECT_NEAR(got.y, 0.25f, 1e-5f);
  EXPECT_EQ(got.z, 0);
  // F0 = 1 (white): capped at 0.99, a finite index.
  layers.specularColor = Vec3f(1);
  coat = ferryCoatOf(layers);
  EXPECT_TRUE(std::isfinite(coat.eta));
  EXPECT_NEAR(fresnelDielectric(1, coat.eta), 0.99f, 1e-4f);
}

TEST(GltfSpecularLayers, ClearcoatMixesIntoTheOneCoat) {
  GltfSpecularLayers layers;
  layers.roughness = 0.8f;
  layers.ior = 1.33f;
  layers.specularFactor = 0.5f;
  layers.clearcoatRoughness = 0.1f;
  layers.clearcoat = 1;  // the clear coat alone
  FerryCoat coat = ferryCoatOf(layers);
  EXPECT_EQ(coat.tint, Vec3f(1));
  EXPECT_EQ(coat.eta, 1.5f);
  EXPECT_FLOAT_EQ(coat.roughness, 0.1f);
  layers.clearcoat = 0.5f;  // half way
  coat = ferryCoatOf(layers);
  EXPECT_FLOAT_EQ(coat.tint.x, 0.75f);
  EXPECT_FLOAT_EQ(coat.eta, (1.33f + 1.5f) / 2);
  EXPECT_FLOAT_EQ(coat.roughness, 0.45f);
  layers.clearcoat = 0;  // none: the specular layer
  coat = ferryCoatOf(layers);
  EXPECT_EQ(coat.tint, Vec3f(0.5f));
  EXPECT_EQ(coat.eta, 1.33f);
  EXPECT_EQ(coat.roughness, 0.8f);
}

}  // namespace
}  // namespace ferry
