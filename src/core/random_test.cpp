#include "core/random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace ferry {

TEST(Random, IsAPureFunctionOfItsKey) {
  RandomKey a{12345, 7, 3, 99};
  EXPECT_EQ(random01(a, RandomDim::BsdfU), random01(a, RandomDim::BsdfU));
  RandomKey b = a;
  b.sample = 8;
  EXPECT_NE(random01(a, RandomDim::BsdfU), random01(b, RandomDim::BsdfU));
  EXPECT_NE(random01(a, RandomDim::BsdfU), random01(a, RandomDim::BsdfV));
}

TEST(Random, StreamGivesTheSameNumbersAsRandom01) {
  for (uint32_t i = 0; i < 2000; ++i) {
    RandomKey key{i * 7919u, i % 13, i % 6, 1 + i % 3};
    RandomStream stream(key);
    for (uint32_t d = 0; d < uint32_t(RandomDim::Count); ++d)
      ASSERT_EQ(stream(RandomDim(d)), random01(key, RandomDim(d))) << i << " " << d;
  }
}

TEST(Random, UniformInUnitIntervalByChiSquare) {
  constexpr int kBins = 64, kSamples = 640000;
  std::vector<int> bins(kBins, 0);
  for (int i = 0; i < kSamples; ++i) {
    float u = random01(RandomKey{uint32_t(i), 0, 0, 1}, RandomDim::LightSelect);
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    ++bins[int(u * kBins)];
  }
  double expected = double(kSamples) / kBins, chi2 = 0;
  for (int c : bins) chi2 += (c - expected) * (c - expected) / expected;
  // 63 degrees of freedom: the 0.999 quantile is about 103.4.
  EXPECT_LT(chi2, 103.4);
}

TEST(Random, DimensionsOfOneKeyAreUncorrelated) {
  // The numbers of one vertex (lobe, direction, light) must not move together.
  for (uint32_t d = 0; d + 1 < uint32_t(RandomDim::Count); ++d) {
    double sum = 0;
    constexpr int n = 100000;
    for (int i = 0; i < n; ++i) {
      RandomStream stream(RandomKey{uint32_t(i) * 31u, uint32_t(i) % 7, uint32_t(i) % 5, 1});
      sum += (stream(RandomDim(d)) - 0.5) * (stream(RandomDim(d + 1)) - 0.5);
    }
    EXPECT_LT(std::abs(sum / n * 12.0), 0.02) << "dimensions " << d << " and " << d + 1;
  }
}

TEST(Random, NeighbouringKeysAreUncorrelated) {
  // Adjacent pixels' numbers must not be correlated (a weak hash shows up as patterns).
  double sum = 0;
  constexpr int n = 100000;
  for (int i = 0; i < n; ++i) {
    float a = random01(RandomKey{uint32_t(i), 0, 0, 1}, RandomDim::BsdfU) - 0.5f;
    float b = random01(RandomKey{uint32_t(i + 1), 0, 0, 1}, RandomDim::BsdfU) - 0.5f;
    sum += a * b;
  }
  double correlation = sum / n / (1.0 / 12.0);
  EXPECT_LT(std::abs(correlation), 0.02);
}

}  // namespace ferry
