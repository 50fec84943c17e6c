// Catmull-Rom splines (core/catmull_rom.h): a linear function is
// reproduced and integrated exactly at irregular nodes, and a 2D table is
// sampled in proportion to the row interpolated between its rows.
#include "core/catmull_rom.h"

#include <gtest/gtest.h>

#include <vector>

namespace ferry {
namespace {

const std::vector<float> kNodes = {0, 0.1f, 0.35f, 0.5f, 1.2f, 2};

TEST(CatmullRom, ALinearFunctionIsInterpolatedAndIntegratedExactly) {
  std::vector<float> values;
  for (float x : kNodes) values.push_back(1 + 3 * x);
  for (float x : {0.0f, 0.05f, 0.3f, 0.77f, 1.9f, 2.0f}) {
    int32_t offset;
    float w[4];
    ASSERT_TRUE(catmullRomWeights(kNodes.data(), int32_t(kNodes.size()), x, offset, w));
    float v = 0;
    for (int k = 0; k < 4; ++k)
      if (w[k] != 0) v += w[k] * values[size_t(offset + k)];
    EXPECT_NEAR(v, 1 + 3 * x, 1e-5f) << x;
  }
  int32_t offset;
  float w[4];
  EXPECT_FALSE(catmullRomWeights(kNodes.data(), int32_t(kNodes.size()), 2.01f, offset, w));
  std::vector<float> cdf(kNodes.size());
  const float total =
      integrateCatmullRom(kNodes.data(), int32_t(kNodes.size()), values.data(), cdf.data());
  EXPECT_NEAR(total, 2 + 1.5f * 4, 1e-5f);
  EXPECT_NEAR(cdf[2], 0.35f + 1.5f * 0.35f * 0.35f, 1e-5f);
}

// Rows f(x) = 1 + a x at a = 0 and a = 4: at alpha 2 (halfway) the row is
// 1 + 2 x, whose mean over [0, 2] is (2 + 16 / 3) / 6.
TEST(CatmullRom, SamplesATableInProportionToTheInterpolatedRow) {
  const std::vector<float> alphas = {0, 4};
  const int32_t n = int32_t(kNodes.size());
  std::vector<float> values, cdf(2 * kNodes.size());
  for (float a : alphas)
    for (float x : kNodes) values.push_back(1 + a * x);
  for (int row = 0; row < 2; ++row)
    integrateCatmullRom(kNodes.data(), n, &values[size_t(row) * kNodes.size()],
                        &cdf[size_t(row) * kNodes.size()]);
  constexpr int samples = 100000;
  double mean = 0;
  for (int i = 0; i < samples; ++i) {
    float x, value, density;
    ASSERT_TRUE(sampleCatmullRom2D(alphas.data(), 2, kNodes.data(), n, values.data(), cdf.data(), 2,
                                   (i + 0.5f) / samples, x, &value, &density));
    EXPECT_NEAR(value, 1 + 2 * x, 1e-3f);
    EXPECT_NEAR(density, (1 + 2 * x) / 6, 1e-3f);
    mean += x / samples;
  }
  EXPECT_NEAR(mean, (2 + 16.0 / 3) / 6, 1e-3);
  float x;
  EXPECT_FALSE(sampleCatmullRom2D(alphas.data(), 2, kNodes.data(), n, values.data(), cdf.data(), 5,
                                  0.5f, x));
}

}  // namespace
}  // namespace ferry
