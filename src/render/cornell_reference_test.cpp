// The Cornell box against a stored high-spp reference, the way Mitsuba 3
// tests its integrators: a render with a different seed must agree with the
// reference within its noise.
//
// The reference (tests/reference/cornell_64_*.pfm, made by the disabled test
// below) holds the per-pixel mean and the per-pixel variance of one sample
// (from the spread of its batch means); cornell_64.txt says how it was made.
// The test renders `kTestBatches` batches of `kTestSpp` samples with another
// seed and runs Welch's t-test on 4x4-pixel blocks, per channel, each side's
// variance of the mean from its own batches (degrees of freedom: batches - 1,
// conservative for a block), the test's at least what the reference's
// per-sample variance gives for its sample count. Two checks, each at 0.01:
//  - no block is rejected at the Sidak-corrected level over all blocks and
//    channels (a local error: one wall, light leaking at an edge);
//  - the number of blocks rejected at 0.01 (any channel, Sidak over three)
//    is not more than a Binomial(blocks, 0.01) allows (a small bias spread
//    over the image).
// Removing 2% of next-event estimation or one bounce fails it (17 to 25 and
// 14 of 256 blocks rejected), while nine seeds of the unchanged renderer
// pass with either sampler (no block rejected).
//
// Why blocks and Welch, not pixels against the reference's variance: the
// samples are heavy-tailed. Emitters are two-sided (docs/architecture.md) and
// the built-in light hangs 0.5 below the ceiling, so its upper side floods the
// gap above it and grazes the ceiling next to it; the rare paths that get
// there carry huge samples (one of 4 M was 43904, in a pixel at the light's
// edge whose mean is about 1.5; the image mean of a 64x64, 1024 spp render
// varies by several percent between seeds). Per pixel,
// the mean of a few hundred such samples is skewed (usually below the true
// mean, with a small sample variance), so a per-pixel t-test rejected ~90 of
// 4096 pixels at 0.01 instead of ~41. A 4x4 block averages 16x more samples,
// and a block that caught a firefly has a large variance of its own. A block
// that caught none has too small a one (against a reference from an estimator
// with fewer large samples, nine seeds rejected 5 to 13 blocks), hence the
// reference's per-sample variance as the test's floor.
//
// Regenerate (after a change that is meant to change the image):
//   ferry_tests --gtest_also_run_disabled_tests --gtest_filter=*GenerateCornellReference
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "builtin/builtin.h"
#include "io/images/image_io.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

constexpr int kSize = 64;
constexpr int kBlock = 4;  // compared in kBlock x kBlock pixel blocks (see above)
constexpr int kMaxDepth = 6;
constexpr double kAlpha = 0.01;

// Reference: many batches, independent of the test's by the seed.
constexpr uint32_t kReferenceSeed = 1000;
constexpr int kReferenceSpp = 16;  // per batch (frame)
constexpr int kReferenceBatches = 1024;
// Independent numbers: its batches are independent, so their spread gives the
// variance of its mean. The test renders with Sobol' numbers (the default),
// whose batches are strata of one sequence: their spread overstates the
// variance of its mean, so the test errs towards passing on its side.
constexpr SamplerKind kReferenceSampler = SamplerKind::Independent;

constexpr uint32_t kTestSeed = 7;
constexpr int kTestSpp = 8;
constexpr int kTestBatches = 128;

std::string referenceDir() {
  if (const char* dir = std::getenv("FERRY_REFERENCE_DIR")) return dir;
  return std::string(FERRY_SOURCE_DIR) + "/tests/reference";
}

RenderSettings cornellSettings(uint32_t seed, int spp, SamplerKind sampler) {
  RenderSettings s;
  s.sampler = sampler;
  s.width = s.height = kSize;
  s.samplesPerPixel = spp;
  s.maxDepth = kMaxDepth;
  s.seed = seed;
  return s;
}

// Per-pixel mean over all samples and per-sample variance (batch-mean variance x spp).
struct MeanAndVariance {
  LinearImage mean, variance;
  int spp = 0, batches = 0;
  double samples() const { return double(spp) * batches; }
  // Variance of the mean of pixel i, channel k, and its degrees of freedom.
  double varianceOfMean(size_t i, int k) const { return variance.rgb[i][k] / samples(); }
  double dof() const { return batches - 1; }
};

MeanAndVariance renderCornell(uint32_t seed, int spp, int batches, SamplerKind sampler) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  PixelStatistics stats = renderStatistics(scene, cornellSettings(seed, spp, sampler), batches);
  EXPECT_EQ(stats.retraceMisses, 0u);
  MeanAndVariance r;
  r.spp = spp;
  r.batches = batches;
  for (LinearImage* img : {&r.mean, &r.variance}) {
    img->width = img->height = kSize;
    img->rgb.resize(size_t(kSize) * kSize);
  }
  for (size_t i = 0; i < r.mean.rgb.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      r.mean.rgb[i][k] = float(stats.channel[k][i].mean);
      r.variance.rgb[i][k] = float(stats.channel[k][i].variance() * spp);
    }
  return r;
}

// P(K >= k) for K ~ Binomial(n, p).
double binomialUpperTail(int n, double p, int k) {
  double sum = 0;
  for (int i = std::max(k, 0); i <= n; ++i)
    sum += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) +
                    i * std::log(p) + (n - i) * std::log1p(-p));
  return sum;
}

TEST(CornellReference, DISABLED_GenerateCornellReference) {
  MeanAndVariance ref =
      renderCornell(kReferenceSeed, kReferenceSpp, kReferenceBatches, kReferenceSampler);
  std::filesystem::create_directories(referenceDir());
  writePfm(referenceDir() + "/cornell_64_mean.pfm", ref.mean);
  writePfm(referenceDir() + "/cornell_64_variance.pfm", ref.variance);
  std::ofstream info(referenceDir() + "/cornell_64.txt");
  info << "builtin:cornell width " << kSize << " height " << kSize << " maxDepth " << kMaxDepth
       << " seed " << kReferenceSeed << " spp " << kReferenceSpp << " batches " << kReferenceBatches
       << " sampler " << samplerName(kReferenceSampler) << "\n";
  std::printf("wrote the reference (%.0f samples per pixel) to %s\n", ref.samples(),
              referenceDir().c_str());
}

TEST(CornellReference, MatchesReferencePerPixel) {
  const std::string dir = referenceDir();
  if (!std::filesystem::exists(dir + "/cornell_64_mean.pfm"))
    GTEST_SKIP() << "no reference in " << dir << "; run DISABLED_GenerateCornellReference";
  // The reference must have been made with the settings this test uses.
  std::ifstream infoFile(dir + "/cornell_64.txt");
  std::stringstream info;
  info << infoFile.rdbuf();
  std::ostringstream expectedInfo;
  expectedInfo << "builtin:cornell width " << kSize << " height " << kSize << " maxDepth "
               << kMaxDepth << " seed " << kReferenceSeed << " spp " << kReferenceSpp << " batches "
               << kReferenceBatches << " sampler " << samplerName(kReferenceSampler) << "\n";
  ASSERT_EQ(info.str(), expectedInfo.str()) << "reference made with other settings: regenerate it";
  MeanAndVariance ref;
  ref.mean = readPfm(dir + "/cornell_64_mean.pfm");
  ref.variance = readPfm(dir + "/cornell_64_variance.pfm");
  ref.spp = kReferenceSpp;
  ref.batches = kReferenceBatches;
  ASSERT_EQ(ref.mean.width, kSize);
  ASSERT_EQ(ref.variance.height, kSize);

  MeanAndVariance test = renderCornell(kTestSeed, kTestSpp, kTestBatches, SamplerKind::Sobol);
  const int blocksPerSide = kSize / kBlock, blocks = blocksPerSide * blocksPerSide;

  // Block means and their variances (pixels are independent, so the
  // variance of a block mean is the sum of its pixels' over kBlock^4).
  struct Block {
    double mean[3] = {0, 0, 0}, varianceOfMean[3] = {0, 0, 0};
  };
  auto blocksOf = [&](const MeanAndVariance& image) {
    std::vector<Block> out(static_cast<size_t>(blocks));
    const double n = double(kBlock) * kBlock;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        Block& b = out[size_t((y / kBlock) * blocksPerSide + x / kBlock)];
        size_t i = size_t(y) * kSize + x;
        for (int k = 0; k < 3; ++k) {
          b.mean[k] += image.mean.rgb[i][k] / n;
          b.varianceOfMean[k] += image.varianceOfMean(i, k) / (n * n);
        }
      }
    return out;
  };
  const std::vector<Block> testBlocks = blocksOf(test), refBlocks = blocksOf(ref);

  const double pSidak = sidak(kAlpha, 3.0 * blocks);
  const double pBlock = sidak(kAlpha, 3);  // any of three channels at 0.01
  int rejected = 0, worstBlock = 0;
  double worstP = 1;
  double testSum = 0, refSum = 0;
  LinearImage pImage;  // -log10 p per block, for a person to look at
  pImage.width = pImage.height = blocksPerSide;
  pImage.rgb.resize(size_t(blocks));
  for (int b = 0; b < blocks; ++b) {
    bool reject = false;
    for (int k = 0; k < 3; ++k) {
      const Block &t = testBlocks[b], &r = refBlocks[b];
      testSum += t.mean[k];
      refSum += r.mean[k];
      // The test's variance of its mean: at least what the reference's
      // per-sample variance (from 16 times the samples, so more of the rare
      // large ones) gives for the test's sample count.
      const double testVariance =
          std::max(t.varianceOfMean[k], r.varianceOfMean[k] * ref.samples() / test.samples());
      double p =
          welchP(t.mean[k], testVariance, test.dof(), r.mean[k], r.varianceOfMean[k], ref.dof());
      pImage.rgb[b][k] = float(-std::log10(std::max(p, 1e-300)));
      if (p < pBlock) reject = true;
      if (p < worstP) {
        worstP = p;
        worstBlock = b;
      }
    }
    rejected += reject;
  }
  // Under the null hypothesis, rejections are Binomial(pixels, 0.01): allow up
  // to the count whose upper tail is below 0.01.
  int allowed = 0;
  while (binomialUpperTail(blocks, kAlpha, allowed + 1) > kAlpha) ++allowed;
  std::printf(
      "[ cornell  ] image mean test %.5f reference %.5f; smallest p %.2e at block (%d, %d) (Sidak "
      "threshold %.2e); %d of %d blocks rejected at 0.01 (expected %.1f, allowed %d)\n",
      testSum / (3.0 * blocks), refSum / (3.0 * blocks), worstP, worstBlock % blocksPerSide,
      worstBlock / blocksPerSide, pSidak, rejected, blocks, kAlpha * blocks, allowed);
  bool ok = worstP >= pSidak && rejected <= allowed;
  if (!ok) {
    // For a person to look at: the test image and -log10(p) per pixel.
    std::string out = ::testing::TempDir() + "cornell_failed";
    writePfm(out + "_mean.pfm", test.mean);
    writePfm(out + "_log10p.pfm", pImage);
    std::printf("[ cornell  ] wrote %s_mean.pfm and %s_log10p.pfm\n", out.c_str(), out.c_str());
  }
  EXPECT_GE(worstP, pSidak) << "block (" << worstBlock % blocksPerSide << ", "
                            << worstBlock / blocksPerSide << ") of " << kBlock << "x" << kBlock
                            << " pixels differs from the reference";
  EXPECT_LE(rejected, allowed) << "too many blocks differ from the reference";
}

}  // namespace
}  // namespace ferry
