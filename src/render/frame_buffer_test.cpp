// The frame buffer's sample clamp (pbrt's Film maxsampleluminance and
// maxcomponentvalue): on each camera sample's total, in any order, with
// splats clamped alone; the ranks' partial totals summed first.
#include "render/frame_buffer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace ferry {
namespace {

constexpr float kLimit = 2;

FrameBuffer clamped(SampleClamp::Measure measure) {
  FrameBuffer fb(2, 1);
  fb.setSampleClamp({measure, kLimit});
  return fb;
}

float luminance3(Vec3f v) {
  return 0.212671f * v.x + 0.715160f * v.y + 0.072169f * v.z;
}

TEST(SampleClamp, ScalesTheSampleTotalNotEachContribution) {
  FrameBuffer fb = clamped(SampleClamp::Measure::Luminance);
  // Two contributions of luminance 1.5 each: each within the limit, their
  // total (3) not: the total is scaled to luminance 2.
  fb.add(0, Vec3f(1.5f));
  fb.add(0, Vec3f(1.5f));
  fb.add(1, Vec3f(0.5f));  // within the limit: unchanged
  EXPECT_EQ(fb.sum()[0], Vec3f(0)) << "nothing lands before the sample ends";
  fb.finishSample(true);
  const std::vector<Vec3f> image = fb.sum();
  EXPECT_NEAR(luminance3(image[0]), kLimit, 1e-5f);
  EXPECT_NEAR(image[0].x, image[0].y, 1e-6f);  // the colour kept
  EXPECT_EQ(image[1], Vec3f(0.5f));
  // The next sample starts from zero.
  fb.add(0, Vec3f(0.25f));
  fb.finishSample(true);
  EXPECT_NEAR(fb.sum()[0].x, image[0].x + 0.25f, 1e-6f);
}

TEST(SampleClamp, MaxComponentIsPbrtV4s) {
  FrameBuffer fb = clamped(SampleClamp::Measure::MaxComponent);
  fb.add(0, Vec3f(4, 1, 0.5f));
  fb.finishSample(true);
  EXPECT_NEAR(fb.sum()[0].x, 2, 1e-6f);
  EXPECT_NEAR(fb.sum()[0].y, 0.5f, 1e-6f);
}

TEST(SampleClamp, SplatsAreClampedAlone) {
  FrameBuffer fb = clamped(SampleClamp::Measure::Luminance);
  fb.addSplat(0, Vec3f(1.5f));
  fb.addSplat(0, Vec3f(1.5f));  // each within the limit: 3 in all
  fb.addSplat(1, Vec3f(10));    // scaled to luminance 2
  fb.finishSample(true);
  EXPECT_NEAR(fb.sum()[0].x, 3, 1e-5f);
  EXPECT_NEAR(luminance3(fb.sum()[1]), kLimit, 1e-5f);
}

TEST(SampleClamp, OrderAndRanksDoNotChangeTheResult) {
  const std::vector<Vec3f> parts = {{0.7f, 0.1f, 3}, {2, 0.3f, 0.2f}, {0.01f, 5, 0.4f}};
  FrameBuffer one = clamped(SampleClamp::Measure::Luminance);
  for (const Vec3f& v : parts) one.add(0, v);
  one.finishSample(true);
  // The same contributions on two "ranks" in another order: their partial
  // totals summed (as sumOverRanks does), then one adds them.
  FrameBuffer a = clamped(SampleClamp::Measure::Luminance);
  FrameBuffer b = clamped(SampleClamp::Measure::Luminance);
  a.add(0, parts[2]);
  b.add(0, parts[1]);
  a.add(0, parts[0]);
  std::vector<int64_t> total = a.sampleSums();
  for (size_t i = 0; i < total.size(); ++i) total[i] += b.sampleSums()[i];
  a.sampleSums() = total;
  b.sampleSums() = total;
  a.finishSample(true);
  b.finishSample(false);
  EXPECT_EQ(a.fixedSum(), one.fixedSum());
  EXPECT_TRUE(
      std::all_of(b.fixedSum().begin(), b.fixedSum().end(), [](int64_t v) { return v == 0; }));
}

TEST(SampleClamp, OffAddsStraightToTheSums) {
  FrameBuffer fb(1, 1);
  fb.add(0, Vec3f(100));
  EXPECT_EQ(fb.sum()[0], Vec3f(100));
  fb.finishSample(true);  // nothing to do
  EXPECT_EQ(fb.sum()[0], Vec3f(100));
}

}  // namespace
}  // namespace ferry
