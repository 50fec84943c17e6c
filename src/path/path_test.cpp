// The compact path: layout is checked by static_asserts in path.h; here, that
// what is stored is what is read back, quantized once when the ray is made.
#include "path/path.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstring>

#include "core/random.h"

namespace ferry {
namespace {

template <typename P>
void checkQuantizedAtCreation() {
  RandomKey key{0, 0, 0, 99};
  for (uint32_t i = 0; i < 20000; ++i) {
    key.pixel = i;
    // Unit directions all over the sphere, and some unnormalised.
    float z = 1 - 2 * random01(key, RandomDim::BsdfU),
          phi = 2 * kPi * random01(key, RandomDim::BsdfV);
    float r = std::sqrt(std::max(0.0f, 1 - z * z));
    float scale = i % 7 == 0 ? 3.7f : 1.0f;
    Vec3f d{r * std::cos(phi) * scale, r * std::sin(phi) * scale, z * scale};
    Vec3f w{random01(key, RandomDim::LightSampleU) * 100, random01(key, RandomDim::LightSampleV),
            random01(key, RandomDim::Roulette) * 1e-3f};
    P p{};
    p.setDir(d);
    p.setWeight(w);
    Vec3f got = p.dir(), weight = p.weight();
    EXPECT_EQ(got, decodeOctahedral(encodeOctahedral(d))) << i;
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(weight[k], halfToFloat(floatToHalf(w[k]))) << i << " component " << k;
    }
    P copy{};
    // A ray read and stored again (as when it is forwarded) points the same
    // way within the quantization (the octahedral grid is not idempotent to
    // the bit, so forwarding never re-stores a direction: it copies the path).
    copy.setDir(p.dir());
    ASSERT_LT(length(copy.dir() - p.dir()), 1e-4f);
    // And it stays close to what was asked, and unit length.
    ASSERT_LT(length(got - normalize(d)), 1e-4f) << i;
    ASSERT_NEAR(length(got), 1.0f, 1e-6f);
    // The BSDF density is stored to 1/256.
    const float pdf = 0.01f + 100 * random01(key, RandomDim::BsdfLobe);
    const float stored = p.setBsdfPdf(pdf);
    ASSERT_EQ(stored, p.bsdfPdf());
    ASSERT_NEAR(p.bsdfPdf() / pdf, 1.0f, 1.0f / 256);
  }
}

TEST(Path, DirectionThroughputAndDensityAreQuantizedAtCreation) {
  checkQuantizedAtCreation<Path8>();
  checkQuantizedAtCreation<Path64>();
  checkQuantizedAtCreation<PathReplay>();
}

TEST(Path, PixelAndFlagsRoundTrip) {
  for (uint32_t pixel : {0u, 1u, 12345u, kMaxPixels - 1}) {
    for (uint32_t flags : {0u, uint32_t(kPathShadow), uint32_t(kPathAfterSpecular),
                           uint32_t(kPathShadow | kPathOccluded), uint32_t(kPathFlagMask)}) {
      Path8 p{};
      p.setPixelAndFlags(pixel, flags);
      EXPECT_EQ(p.pixel(), pixel);
      EXPECT_EQ(p.flags(), flags);
      p.set(kPathOccluded);
      EXPECT_EQ(p.pixel(), pixel) << "setting a flag must not touch the pixel";
      EXPECT_TRUE(p.has(kPathOccluded));
      EXPECT_EQ(p.isShadow(), (flags & kPathShadow) != 0);
    }
  }
}

// The replay layout keeps the mask layouts' shared fields where they are (the
// first 32 bytes), so the ray itself travels identically in every layout.
TEST(Path, ReplayLayoutSharesTheRayAndKeepsTwoRankIds) {
  EXPECT_EQ(sizeof(PathReplay), 40u);
  auto bytesAt = [](const auto& path, size_t offset) {
    uint16_t v;
    std::memcpy(&v, reinterpret_cast<const char*>(&path) + offset, 2);
    return v;
  };
  PathReplay ids{};
  ids.generatingRank = 0x1234;
  ids.hitRank = 0x5678;
  EXPECT_EQ(bytesAt(ids, 32), 0x1234);
  EXPECT_EQ(bytesAt(ids, 34), 0x5678);
  Path8 m8{};
  m8.visited = 0x12;
  EXPECT_EQ(bytesAt(m8, 32) & 0xff, 0x12);
  PathReplay p{};
  p.clearHistory();
  EXPECT_FALSE(p.hasHit());
  EXPECT_EQ(p.generatingRank, PathReplay::kNoRank);
  p.markTraced(65534);  // the largest rank id
  EXPECT_EQ(p.generatingRank, 65534);
  p.setHit(1000, 0);
  EXPECT_TRUE(p.hasHit());
  EXPECT_EQ(p.hitRank, 1000);
}

TEST(Path, MaskLayoutsRecordTheHitOwners) {
  Path8 p{};
  p.clearHistory();
  p.setHit(3, 0);  // no owner table: this rank
  EXPECT_EQ(p.hitOwners, 1u << 3);
  p.setHit(3, 0b1010);  // replicated content: every owner
  EXPECT_EQ(p.hitOwners, 0b1010);
  p.markTraced(5);
  EXPECT_EQ(p.visited, 1u << 5);
}

TEST(Path, HitIsRecordedByOwnerMask) {
  Path64 p{};
  EXPECT_FALSE(p.hasHit());
  p.hitOwners = uint64_t(1) << 63;
  EXPECT_TRUE(p.hasHit());
}

}  // namespace
}  // namespace ferry
