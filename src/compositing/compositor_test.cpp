#include "compositing/compositor.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "comm/in_process_communicator.h"

namespace ferry {
namespace {

// Rank r's partial buffer: random radiance, some pixels left black, a few bright.
FrameBuffer randomPartial(int width, int height, int rank) {
  FrameBuffer fb(width, height);
  std::mt19937 rng(1234u + 77u * uint32_t(rank) + uint32_t(width * 131 + height));
  std::uniform_real_distribution<float> value(0.0f, 2.0f);
  for (uint32_t pixel = 0; pixel < fb.pixelCount(); ++pixel) {
    if (rng() % 5 == 0) continue;
    Vec3f v(value(rng), value(rng), value(rng));
    if (rng() % 17 == 0) v = v * 100.0f;
    fb.add(pixel, v);
  }
  return fb;
}

// Every rank's contributions added to one buffer: what the compositor must
// give bit for bit (fixed-point sums do not depend on how they are split
// over ranks).
FrameBuffer allPartials(int width, int height, int ranks) {
  FrameBuffer all(width, height);
  for (int r = 0; r < ranks; ++r) {
    const FrameBuffer fb = randomPartial(width, height, r);
    for (size_t i = 0; i < fb.fixedSum().size(); ++i) all.fixedSum()[i] += fb.fixedSum()[i];
  }
  return all;
}
std::vector<Vec3f> plainSum(int width, int height, int ranks, float scale) {
  return allPartials(width, height, ranks).sum(scale);
}

bool sameBits(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3f)) == 0;
}

struct ImageSize {
  int width, height;
};

class Compositor : public ::testing::TestWithParam<int> {};

// Heights 1 and 3 leave some ranks an empty slice; 29 rows split unevenly.
TEST_P(Compositor, LinearAndToneMappedEqualThePlainSum) {
  const int ranks = GetParam();
  const float scale = 1.0f / 3.0f;
  ToneMapping toneMapping;
  toneMapping.exposure = 0.5f;
  for (ImageSize size : {ImageSize{5, 1}, ImageSize{7, 3}, ImageSize{16, 29}}) {
    SCOPED_TRACE(testing::Message()
                 << size.width << "x" << size.height << ", " << ranks << " ranks");
    const std::vector<Vec3f> expected = plainSum(size.width, size.height, ranks, scale);
    std::vector<Vec3f> linear;
    std::vector<uint8_t> rgba;
    std::vector<uint64_t> linearBytes(ranks), rgbaBytes(ranks);
    runRanks(ranks, [&](const Communicator& comm) {
      FrameBuffer partial = randomPartial(size.width, size.height, comm.rank());
      uint64_t sentLinear = 0, sentRgba = 0;
      std::vector<Vec3f> l = compositeLinear(comm, partial, scale, sentLinear);
      std::vector<uint8_t> t = compositeToneMapped(comm, partial, scale, toneMapping, sentRgba);
      linearBytes[comm.rank()] = sentLinear;
      rgbaBytes[comm.rank()] = sentRgba;
      if (comm.isRoot()) {
        linear = std::move(l);
        rgba = std::move(t);
      } else {
        EXPECT_TRUE(l.empty());
        EXPECT_TRUE(t.empty());
      }
    });
    EXPECT_TRUE(sameBits(linear, expected));
    // The exact sums, as a checkpoint stores them.
    const FrameBuffer all = allPartials(size.width, size.height, ranks);
    runRanks(ranks, [&](const Communicator& comm) {
      uint64_t sent = 0;
      const std::vector<int64_t> sums =
          compositeFixed(comm, randomPartial(size.width, size.height, comm.rank()), sent);
      if (comm.isRoot())
        EXPECT_EQ(sums, all.fixedSum());
      else
        EXPECT_TRUE(sums.empty());
    });
    EXPECT_EQ(rgba, toneMapToRgba8(expected, toneMapping));

    // Bytes sent: every rank's pixels of other ranks' slices, then every
    // slice but rank 0's to rank 0.
    int firstRow, rootRows;
    compositeSlice(size.height, ranks, 0, firstRow, rootRows);
    const uint64_t pixels = uint64_t(size.width) * size.height;
    const uint64_t others = pixels - uint64_t(size.width) * rootRows;
    uint64_t totalLinear = 0, totalRgba = 0;
    for (int r = 0; r < ranks; ++r) {
      totalLinear += linearBytes[r];
      totalRgba += rgbaBytes[r];
    }
    // Direct send moves fixed-point sums (3 x 8 bytes a pixel); the gather
    // moves linear floats or RGBA8.
    const uint64_t directSend = uint64_t(ranks - 1) * pixels * 3 * sizeof(int64_t);
    EXPECT_EQ(totalLinear, directSend + others * sizeof(Vec3f));
    EXPECT_EQ(totalRgba, directSend + others * 4);
  }
}

INSTANTIATE_TEST_SUITE_P(Ranks, Compositor, ::testing::Values(1, 2, 3, 4, 5),
                         [](const auto& info) { return std::to_string(info.param) + "ranks"; });

TEST(CompositeSlice, SlicesCoverTheImageInOrder) {
  for (int height : {1, 2, 3, 7, 720})
    for (int ranks = 1; ranks <= 9; ++ranks) {
      int expectedFirst = 0;
      for (int r = 0; r < ranks; ++r) {
        int first, last;
        compositeSlice(height, ranks, r, first, last);
        EXPECT_EQ(first, expectedFirst);
        EXPECT_LE(first, last);
        EXPECT_LE(last - first, (height + ranks - 1) / ranks);
        expectedFirst = last;
      }
      EXPECT_EQ(expectedFirst, height);
    }
}

}  // namespace
}  // namespace ferry
