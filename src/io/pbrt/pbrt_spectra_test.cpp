#include "io/pbrt/pbrt_spectra.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "core/error.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

TEST(PbrtSpectra, ConstantReflectanceIsWhiteBalanced) {
  SampledSpectrum one{{400.0f, 700.0f}, {1.0f, 1.0f}};
  Vec3f rgb = spectrumToRgb(one, SpectrumUse::Reflectance);
  EXPECT_NEAR(rgb.x, 1, 1e-4);
  EXPECT_NEAR(rgb.y, 1, 1e-4);
  EXPECT_NEAR(rgb.z, 1, 1e-4);
  SampledSpectrum half{{550.0f}, {0.5f}};
  EXPECT_NEAR(spectrumToRgb(half, SpectrumUse::Reflectance).y, 0.5f, 1e-4);
}

TEST(PbrtSpectra, ColoursLandInTheRightChannels) {
  SampledSpectrum red{{400.0f, 590.0f, 610.0f, 700.0f}, {0, 0, 1, 1}};
  Vec3f r = spectrumToRgb(red, SpectrumUse::Reflectance);
  EXPECT_GT(r.x, 3 * r.y);
  EXPECT_GT(r.x, 3 * r.z);
  SampledSpectrum blue{{400.0f, 480.0f, 500.0f, 700.0f}, {1, 1, 0, 0}};
  Vec3f b = spectrumToRgb(blue, SpectrumUse::Reflectance);
  EXPECT_GT(b.z, 3 * b.x);
}

TEST(PbrtSpectra, BlackbodiesGoFromRedToBlue) {
  Vec3f warm = spectrumToRgb(blackbodySpectrum(2000), SpectrumUse::Illuminant);
  Vec3f d65 = spectrumToRgb(blackbodySpectrum(6504), SpectrumUse::Illuminant);
  Vec3f cold = spectrumToRgb(blackbodySpectrum(15000), SpectrumUse::Illuminant);
  EXPECT_GT(warm.x, 2 * warm.z);
  EXPECT_GT(cold.z, cold.x);
  // Near 6500 K the colour is close to white.
  EXPECT_NEAR(d65.x / d65.y, 1, 0.1);
  EXPECT_NEAR(d65.z / d65.y, 1, 0.15);
  // Peak-normalised: the peak is 1.
  SampledSpectrum s = blackbodySpectrum(5000);
  float peak = 0;
  for (float v : s.value) peak = std::max(peak, v);
  EXPECT_NEAR(peak, 1, 0.01);
}

TEST(PbrtSpectra, MetalsLookLikeMetals) {
  auto f0 = [](const char* metal) {
    std::string m = metal;
    return conductorReflectance(*namedSpectrum("metal-" + m + "-eta"),
                                *namedSpectrum("metal-" + m + "-k"));
  };
  Vec3f al = f0("Al"), au = f0("Au"), cu = f0("Cu"), ag = f0("Ag");
  EXPECT_GT(al.x, 0.88f);
  EXPECT_GT(al.z, 0.88f);
  EXPECT_GT(ag.y, 0.9f);
  EXPECT_GT(au.x, 0.9f);
  EXPECT_LT(au.z, 0.45f);  // gold is yellow
  EXPECT_GT(cu.x, cu.y);
  EXPECT_GT(cu.y, cu.z);  // copper is orange
  EXPECT_FALSE(namedSpectrum("metal-Unobtainium-eta"));
  EXPECT_NEAR(namedSpectrum("glass-BK7")->at(550), 1.5185f, 1e-4);
}

TEST(PbrtSpectra, SpdFileMatchesTheNamedSpectrum) {
  fs::path dir = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "pbrt" / "spds";
  SampledSpectrum eta = readSpdFile((dir / "al_eta.spd").string());
  SampledSpectrum k = readSpdFile((dir / "al_k.spd").string());
  ASSERT_EQ(eta.lambda.size(), 7u);
  ASSERT_EQ(k.lambda.size(), 7u);
  Vec3f fromFiles = conductorReflectance(eta, k);
  Vec3f named = conductorReflectance(*namedSpectrum("metal-Al-eta"), *namedSpectrum("metal-Al-k"));
  EXPECT_NEAR(fromFiles.x, named.x, 1e-5);
  EXPECT_NEAR(fromFiles.z, named.z, 1e-5);
}

TEST(PbrtSpectra, BadSpdFiles) {
  fs::path dir = fs::temp_directory_path() / ("ferry_spd_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  };
  auto error = [](const std::string& path) {
    try {
      readSpdFile(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(write("odd.spd", "400 1\n500\n")).find("wavelength-value pairs"),
            std::string::npos);
  EXPECT_NE(error(write("word.spd", "400 1\n500 x\n")).find("word.spd:2: 'x' is not a number"),
            std::string::npos);
  EXPECT_NE(error(write("order.spd", "500 1 400 1")).find("wavelengths must increase"),
            std::string::npos);
  EXPECT_NE(error(write("empty.spd", "# nothing\n")).find("no values"), std::string::npos);
  EXPECT_NE(error((dir / "missing.spd").string()).find("no such file"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ferry
