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

// The points of one pair of a Sobol' stream over samples [first, first + n).
std::vector<std::pair<float, float>> sobolPoints(const RandomKey& key, RandomDim u, RandomDim v,
                                                 uint32_t first, uint32_t n) {
  std::vector<std::pair<float, float>> points;
  for (uint32_t s = first; s < first + n; ++s) {
    RandomKey k = key;
    k.sample = s;
    RandomStream stream(k, SamplerKind::Sobol);
    points.emplace_back(stream(u), stream(v));
  }
  return points;
}

// Whether n = 2^m points are a (0, m, 2)-net: every elementary box of area 1/n holds one.
bool isNet(const std::vector<std::pair<float, float>>& points) {
  const uint32_t n = uint32_t(points.size());
  for (uint32_t cols = 1; cols <= n; cols *= 2) {
    const uint32_t rows = n / cols;
    std::vector<int> boxes(n, 0);
    for (auto [x, y] : points)
      ++boxes[uint32_t(x * float(cols)) * rows + uint32_t(y * float(rows))];
    for (int b : boxes)
      if (b != 1) return false;
  }
  return true;
}

TEST(SobolStream, EveryPairsPowerOfTwoPrefixIsANet) {
  // Each 2D pair, and each 1D number alone, for 2^m samples from any multiple of 2^m.
  const std::pair<RandomDim, RandomDim> pairs[] = {
      {RandomDim::PixelJitterX, RandomDim::PixelJitterY},
      {RandomDim::LightSampleU, RandomDim::LightSampleV},
      {RandomDim::BsdfU, RandomDim::BsdfV},
      {RandomDim::LensU, RandomDim::LensV},
      {RandomDim::LightSelect, RandomDim::BsdfLobe},
      {RandomDim::Roulette, RandomDim::MaterialSelect}};
  for (uint32_t pixel : {0u, 17u, 123457u})
    for (uint32_t m : {0u, 2u, 5u, 8u})
      for (uint32_t block : {0u, 3u}) {
        const RandomKey key{pixel, 0, pixel % 4, 9};
        const uint32_t n = 1u << m;
        for (size_t p = 0; p < 4; ++p)
          EXPECT_TRUE(isNet(sobolPoints(key, pairs[p].first, pairs[p].second, block * n, n)))
              << pixel << " " << m << " " << p;
        // Two first numbers of different pairs: each stratified alone.
        for (size_t p = 4; p < 6; ++p) {
          std::vector<int> strata(n, 0);
          for (auto [a, b] : sobolPoints(key, pairs[p].first, pairs[p].second, block * n, n)) {
            ++strata[uint32_t(a * float(n))];
            ++strata[uint32_t(b * float(n))];
          }
          for (int c : strata) EXPECT_EQ(c, 2) << pixel << " " << m << " " << p;
        }
      }
}

TEST(SobolStream, PairsArePaddedNotCopies) {
  // Different pairs of one vertex, the same pair at other bounces or pixels:
  // unrelated sequences (a shared sequence correlates them fully).
  constexpr int kPixels = 20000, kSamples = 4;
  double sameKey = 0, otherBounce = 0, otherPixel = 0;
  for (uint32_t pixel = 0; pixel < kPixels; ++pixel)
    for (uint32_t s = 0; s < kSamples; ++s) {
      RandomStream a(RandomKey{pixel, s, 1, 3}, SamplerKind::Sobol);
      RandomStream b(RandomKey{pixel, s, 2, 3}, SamplerKind::Sobol);
      RandomStream c(RandomKey{pixel + 1, s, 1, 3}, SamplerKind::Sobol);
      sameKey += (a(RandomDim::BsdfU) - 0.5) * (a(RandomDim::LightSampleU) - 0.5);
      otherBounce += (a(RandomDim::BsdfU) - 0.5) * (b(RandomDim::BsdfU) - 0.5);
      otherPixel += (a(RandomDim::BsdfU) - 0.5) * (c(RandomDim::BsdfU) - 0.5);
    }
  const double n = kPixels * kSamples / 12.0;
  EXPECT_LT(std::abs(sameKey / n), 0.02);
  EXPECT_LT(std::abs(otherBounce / n), 0.02);
  EXPECT_LT(std::abs(otherPixel / n), 0.02);
}

TEST(SobolStream, EachNumberIsUniformOverPixels) {
  // Sample 0 of every pixel (the first point of each shuffled, shifted sequence): uniform.
  constexpr int kBins = 64, kPixels = 640000;
  for (RandomDim d : {RandomDim::PixelJitterY, RandomDim::LightSelect, RandomDim::BsdfV}) {
    std::vector<int> bins(kBins, 0);
    for (uint32_t pixel = 0; pixel < kPixels; ++pixel) {
      const float u = RandomStream(RandomKey{pixel, 0, 0, 1}, SamplerKind::Sobol)(d);
      ASSERT_GE(u, 0.0f);
      ASSERT_LT(u, 1.0f);
      ++bins[int(u * kBins)];
    }
    double expected = double(kPixels) / kBins, chi2 = 0;
    for (int c : bins) chi2 += (c - expected) * (c - expected) / expected;
    EXPECT_LT(chi2, 103.4) << int(d);  // the 0.999 quantile at 63 degrees of freedom
  }
}

TEST(SobolStream, IntegratesASmoothFunctionBetterThanIndependentNumbers) {
  // The mean over pixels of the squared error of a 64-sample estimate of
  // the integral of x*y over the unit square (1/4): Sobol' points beat
  // independent ones by far (the variance falls faster than 1/n).
  double sobol = 0, independent = 0;
  constexpr int kPixels = 2000, kSamples = 64;
  for (uint32_t pixel = 0; pixel < kPixels; ++pixel) {
    double s = 0, i = 0;
    for (uint32_t k = 0; k < kSamples; ++k) {
      const RandomKey key{pixel, k, 0, 5};
      RandomStream q(key, SamplerKind::Sobol), r(key, SamplerKind::Independent);
      s += q(RandomDim::BsdfU) * q(RandomDim::BsdfV);
      i += r(RandomDim::BsdfU) * r(RandomDim::BsdfV);
    }
    sobol += std::pow(s / kSamples - 0.25, 2);
    independent += std::pow(i / kSamples - 0.25, 2);
  }
  EXPECT_LT(sobol, independent / 10);
}

TEST(SobolStream, NamesRoundTrip) {
  for (SamplerKind k : {SamplerKind::Sobol, SamplerKind::Independent})
    EXPECT_EQ(samplerNamed(samplerName(k)), k);
  EXPECT_FALSE(samplerNamed("halton"));
}

}  // namespace ferry
