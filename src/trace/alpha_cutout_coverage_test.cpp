// The coverage decides a footprint only where the exact test agrees: for
// every alpha test and wrap mode, at random uvs (including far outside
// [0, 1] and at texel edges), the cut-out with coverage answers as the one
// without; and it decides most footprints of a texture with large opaque
// and clear regions.
#include "trace/alpha_cutout_coverage.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "trace/alpha_cutout.h"

namespace ferry {
namespace {

// A w x h texture whose alpha is 0 left of a wavy edge and 255 right of it,
// with a band of in-between values along the edge and a few stray texels.
Texture edgeTexture(int w, int h, WrapMode wrap) {
  Texture t;
  t.name = "edge";
  t.width = w;
  t.height = h;
  t.wrap = wrap;
  std::vector<uint8_t> rgba(size_t(w) * size_t(h) * 4);
  std::mt19937 rng(7);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float edge = 0.5f * float(w) + 0.2f * float(w) * std::sin(float(y) * 0.3f);
      const float d = float(x) - edge;
      int a = d < -2 ? 0 : d > 2 ? 255 : int(64 * (d + 2));
      if (rng() % 50 == 0) a = int(rng() % 256);
      rgba[(size_t(y) * w + x) * 4 + 3] = uint8_t(std::clamp(a, 0, 255));
    }
  t.rgba = std::move(rgba);
  return t;
}

// A unit square mesh whose uvs reach far past [0, 1], so every wrap is
// exercised.
Mesh square() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.uvs = {{-3.3f, -2.1f}, {4.7f, -2.1f}, {4.7f, 5.2f}, {-3.3f, 5.2f}};
  m.indices = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(AlphaCoverage, DecidesOnlyWhereTheExactTestAgrees) {
  const Mesh mesh = square();
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0, 1);
  for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Mirror})
    for (AlphaTest test : {AlphaTest::Below, AlphaTest::Zero, AlphaTest::Stochastic})
      for (float cutoff : {0.5f, 128 / 255.0f, 0.0f, 1.0f}) {
        const Texture texture = edgeTexture(13, 9, wrap);
        const AlphaCoverage coverage(texture, cutoff, test);
        const AlphaCutout exact{&mesh, &texture, cutoff, test, AlphaRays::All};
        AlphaCutout fast = exact;
        fast.coverage = &coverage;
        int disagree = 0;
        for (int i = 0; i < 200000; ++i) {
          float u = unit(rng), v = unit(rng) * (1 - u);
          if (i % 4 == 0) {  // on texel edges of the uv plane
            u = std::round(u * 64) / 64;
            v = std::round(v * 64) / 64 * (1 - u);
          }
          const uint32_t prim = rng() % 2, hash = rng();
          disagree +=
              exact.isHole(prim, u, v, nullptr, hash) != fast.isHole(prim, u, v, nullptr, hash);
        }
        EXPECT_EQ(disagree, 0) << "wrap " << int(wrap) << " test " << int(test) << " cutoff "
                               << cutoff;
      }
}

TEST(AlphaCoverage, DecidesMostOfATextureWithLargeOpaqueAndClearRegions) {
  const Texture texture = edgeTexture(512, 256, WrapMode::Repeat);
  EXPECT_GT(AlphaCoverage(texture, 0.5f, AlphaTest::Below).decidedShare(), 0.8);
  EXPECT_GT(AlphaCoverage(texture, 0.5f, AlphaTest::Zero).decidedShare(), 0.8);
  // Stochastic decides only the clear texels (opaque ones may blend below 1).
  const double stochastic = AlphaCoverage(texture, 0.5f, AlphaTest::Stochastic).decidedShare();
  EXPECT_GT(stochastic, 0.3);
  EXPECT_LT(stochastic, 0.6);
  EXPECT_EQ(AlphaCoverage(texture, 0.5f, AlphaTest::Below).bytes(), 512u * 256 / 4);
}

}  // namespace
}  // namespace ferry
