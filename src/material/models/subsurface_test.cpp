// The subsurface model's surface (material/models/subsurface.h): a walk
// arriving from inside is mirrored back with the inside Fresnel reflectance
// or leaves by Sw, whose weights average to exactly what leaves (no light is
// made or lost at the surface); Sw's normalization is its cosine integral;
// and pbrt's diffuse-reflectance inversion is the inverse of the photon beam
// diffusion reflectance.
#include "material/models/subsurface.h"

#include <gtest/gtest.h>

#include <cmath>

#include "render/render_test_util.h"

namespace ferry {
namespace {

TEST(Subsurface, FromInsideAWalkIsMirroredOrLeavesWithAllItCarries) {
  const SubsurfaceModel model(1.33f, 0, Vec3f(1));
  const Bsdf bsdf = model.bsdf(Vec3f(1), {});
  EXPECT_TRUE(bsdf.transmits());
  for (float cosInside : {0.95f, 0.6f, 0.3f}) {
    const Vec3f wo{std::sqrt(1 - cosInside * cosInside), 0, -cosInside};
    const float reflectance = fresnelDielectric(cosInside, 1 / 1.33f);
    testing::TestRng rng(uint64_t(cosInside * 1000));
    auto u = [&] { return rng.uniform(); };
    constexpr int n = 200000;
    double weight = 0, mirrored = 0, worst = 0;
    for (int i = 0; i < n; ++i) {
      BsdfSample s;
      ASSERT_TRUE(bsdf.sample(wo, u(), {u(), u()}, s));
      weight += s.weight.x;
      if (s.delta) {
        mirrored += 1;
        EXPECT_LT(s.wi.z, 0);
        continue;
      }
      ASSERT_GT(s.wi.z, 0);
      // A leaving sample's weight is eval / pdf.
      const float pdf = bsdf.pdf(wo, s.wi);
      worst = std::max(worst, double(std::abs(s.weight.x - bsdf.eval(wo, s.wi).x / pdf)));
      EXPECT_NEAR(s.pdf, pdf, 1e-5f);
    }
    EXPECT_LT(worst, 1e-4);
    EXPECT_NEAR(mirrored / n, reflectance, 4 * std::sqrt(reflectance / n) + 1e-3) << cosInside;
    EXPECT_NEAR(weight / n, 1.0, 0.01) << cosInside;
  }
  // Beyond the critical angle every walk is mirrored back in.
  const Vec3f grazing{0.9f, 0, -std::sqrt(1 - 0.81f)};
  BsdfSample s;
  ASSERT_TRUE(bsdf.sample(grazing, 0.999f, {0.5f, 0.5f}, s));
  EXPECT_TRUE(s.delta);
}

TEST(Subsurface, ExitLobeIntegratesToOne) {
  // c = 1 - 2 x (the first Fresnel moment seen from outside).
  EXPECT_NEAR(subsurfaceExitNormalization(1.33f), 1 - 2 * 0.0329654f, 1e-4f);
  for (float ior : {1.2f, 1.33f, 1.5f}) {
    const float c = subsurfaceExitNormalization(ior);
    double integral = 0;
    constexpr int n = 4096;
    for (int i = 0; i < n; ++i) {
      const double mu = (i + 0.5) / n;  // cos: the hemisphere's integral is 2 pi mu dmu
      integral += 2 * kPi * mu * (1 - fresnelDielectric(float(mu), ior)) / (c * kPi) / n;
    }
    EXPECT_NEAR(integral, 1.0, 1e-3) << ior;
  }
}

TEST(Subsurface, DiffuseReflectanceInvertsThePhotonBeamDiffusionProfile) {
  float previous = -1;
  for (float albedo : {0.1f, 0.5f, 0.8f, 0.95f, 0.99f}) {
    const float r = photonBeamDiffusionReflectance(albedo, 0, 1.33f);
    EXPECT_GT(r, previous) << albedo;
    EXPECT_LT(r, 1.0f);
    previous = r;
    const Vec3f back = subsurfaceAlbedoFromReflectance(Vec3f(r), 0, 1.33f);
    EXPECT_NEAR(back.x, albedo, 2e-3f) << albedo;
  }
  EXPECT_EQ(subsurfaceAlbedoFromReflectance(Vec3f(0), 0, 1.33f).x, 0);
}

}  // namespace
}  // namespace ferry

namespace ferry {
namespace {

SubsurfaceModel ketchup() {
  // pbrt's measured Ketchup (mm^-1) times 10, as in the oracle case.
  return SubsurfaceModel(1.33f, 0, Vec3f(1), Vec3f(0.061f, 0.97f, 1.45f) * 10,
                         Vec3f(0.18f, 0.07f, 0.03f) * 10, 0, 7);
}

// The table's effective albedos grow with the albedo from 0 to the profile's
// integral for a white medium, and a
// radius drawn from a channel's profile has the density pdfSr says (its
// histogram over rings).
TEST(Subsurface, TheProfileIsSampledWithTheDensityItStates) {
  const SubsurfaceModel model = ketchup();
  const SubsurfaceProfile profile = model.profile();
  const BssrdfTable& t = *profile.table;
  EXPECT_EQ(t.effectiveAlbedo.front(), 0.0f);
  for (size_t i = 1; i < t.effectiveAlbedo.size(); ++i)
    EXPECT_GE(t.effectiveAlbedo[i], t.effectiveAlbedo[i - 1]) << i;
  // (The table ends at 200 mean free paths, the integral at 2000: the tail
  // of a white medium's profile is the difference.)
  EXPECT_NEAR(t.effectiveAlbedo.back(), photonBeamDiffusionReflectance(1, 0, 1.33f), 0.02f);
  for (int ch = 0; ch < 3; ++ch) {
    const float rMax = profile.sampleSr(ch, 0.999f);
    ASSERT_GT(rMax, 0);
    constexpr int rings = 16, n = 200000;
    std::vector<int> counts(rings);
    testing::TestRng rng(ch + 1);
    for (int i = 0; i < n; ++i) {
      const float r = profile.sampleSr(ch, rng.uniform());
      ASSERT_GE(r, 0);
      if (r < rMax) counts[std::min(int(r / rMax * rings), rings - 1)]++;
    }
    for (int k = 0; k < rings; ++k) {
      // The ring's probability from the density: 2 pi r pdfSr(r) over r.
      double expected = 0;
      constexpr int steps = 200;
      for (int s = 0; s < steps; ++s) {
        const float r = rMax * (k + (s + 0.5f) / steps) / rings;
        expected += 2 * kPi * r * profile.pdfSr(ch, r) * rMax / rings / steps;
      }
      const double seen = double(counts[k]) / n;
      EXPECT_NEAR(seen, expected, 0.004 + 0.03 * expected) << "channel " << ch << " ring " << k;
    }
  }
}

// On a plane through the entry point, probes estimate the profile's
// integral over the plane: each probe along the normal finds the plane once
// (the tangent ones never do), and Sp over the probe's density averages to
// the effective albedo of each channel (pbrt's estimator, checked end to end).
TEST(Subsurface, ProbesOnAPlaneIntegrateTheProfile) {
  const SubsurfaceModel model = ketchup();
  const SubsurfaceProfile profile = model.profile();
  const Frame frame(Vec3f(0, 0, 1));
  const Vec3f entry(0.25f, -0.5f, 0);
  testing::TestRng rng(5);
  constexpr int n = 400000;
  Vec3f sum(0);
  for (int i = 0; i < n; ++i) {
    ProbeSegment s;
    if (!sampleProbeSegment(profile, entry, frame, rng.uniform(), {rng.uniform(), rng.uniform()},
                            s))
      continue;
    const Vec3f d = s.end - s.start;
    if (!(std::abs(d.z) > 0) || s.start.z * s.end.z > 0) continue;  // parallel, or no crossing
    const Vec3f exit = s.start + d * (-s.start.z / d.z);
    const float pdf = probeDensity(profile, entry, frame, exit, Vec3f(0, 0, 1));
    ASSERT_GT(pdf, 0);
    sum += profile.sr(length(exit - entry)) * (1 / pdf);
  }
  for (int ch = 0; ch < 3; ++ch) {
    // The table's effective albedo at this channel's albedo (interpolated linearly).
    const BssrdfTable& t = *profile.table;
    size_t i = 1;
    while (i + 1 < t.albedo.size() && t.albedo[i] < profile.albedo[ch]) ++i;
    const float w = (profile.albedo[ch] - t.albedo[i - 1]) / (t.albedo[i] - t.albedo[i - 1]);
    const float rhoEff = t.effectiveAlbedo[i - 1] * (1 - w) + t.effectiveAlbedo[i] * w;
    EXPECT_NEAR(sum[ch] / n, rhoEff, 0.01f + 0.02f * rhoEff) << "channel " << ch;
  }
}

// A record keeps the medium and the probe id; a record of format 14 and
// before (no medium) reads as a walked model.
TEST(Subsurface, ARecordKeepsTheMediumAndTheProbeId) {
  const SubsurfaceModel model = ketchup();
  MaterialRecordWriter writer;
  model.write(writer);
  MaterialRecordReader reader(writer.bytes(), "test", 0);
  const auto read = std::dynamic_pointer_cast<const SubsurfaceModel>(SubsurfaceModel::read(reader));
  ASSERT_NE(read, nullptr);
  EXPECT_TRUE(read->hasMedium);
  EXPECT_EQ(read->sigmaA, model.sigmaA);
  EXPECT_EQ(read->sigmaS, model.sigmaS);
  EXPECT_EQ(read->probeId, 7u);
  const SubsurfaceModel old(1.5f, 0.1f, Vec3f(1));
  MaterialRecordWriter oldWriter;
  old.write(oldWriter);
  MaterialRecordReader oldReader(oldWriter.bytes(), "test", 0);
  const auto walked =
      std::dynamic_pointer_cast<const SubsurfaceModel>(SubsurfaceModel::read(oldReader));
  ASSERT_NE(walked, nullptr);
  EXPECT_FALSE(walked->hasMedium);
}

}  // namespace
}  // namespace ferry
