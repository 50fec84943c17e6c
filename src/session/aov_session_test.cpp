// AOVs composited over ranks (render/aov.h, compositing/compositor.h): the
// Cornell box's AOVs on 1 rank and on several in-process ranks, on both
// exchanges, the replay layout, data groups and light paths, are the same
// bit for bit, as its colour is; the colour with AOVs is the colour
// without; the file sink writes them.
#include <gtest/gtest.h>

#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "io/images/image_io.h"
#include "io/scene_loader.h"
#include "partition/partitioner.h"
#include "session/image_file_sink.h"
#include "session/render_session.h"

namespace ferry {
namespace {

struct Rendered {
  std::vector<Vec3f> linear;
  std::vector<Aov> aovs;
  std::vector<float> aovValues;
};

Rendered render(const Scene& scene, const SessionSettings& settings, int ranks) {
  Rendered out;
  runRanks(ranks, [&](const Communicator& comm) {
    RenderSession session(scene, settings, comm);
    struct Sink final : FrameSink {
      Frames frames() const override { return Frames::Last; }
      Pixels pixels() const override { return Pixels::Linear; }
      void receive(const FrameImage& image) override {
        got.linear = image.linear;
        got.aovs = image.aovs;
        got.aovValues = image.aovValues;
      }
      Rendered got;
    } sink;
    session.run(sink);
    if (comm.isRoot()) out = std::move(sink.got);
  });
  return out;
}

SessionSettings small() {
  SessionSettings s;
  s.render.width = 40;
  s.render.height = 30;
  s.render.samplesPerPixel = 3;
  s.render.frames = 2;
  s.render.maxDepth = 4;
  s.render.aovs = parseAovList("albedo,normal,geometric-normal,depth,position,uv");
  return s;
}

TEST(AovSession, TheAovsAreTheSameBitForBitOnAnyRankCount) {
  const Scene scene = loadScene("builtin:cornell");
  const Rendered one = render(scene, small(), 1);
  ASSERT_EQ(one.aovs, small().render.aovs);
  ASSERT_EQ(one.aovValues.size(), size_t(40 * 30 * 15));
  // Not all zero: the box fills the view.
  size_t nonzero = 0;
  for (float v : one.aovValues) nonzero += v != 0;
  EXPECT_GT(nonzero, one.aovValues.size() / 2);
  struct Case {
    int ranks;
    ExchangeMode exchange;
    PathLayout layout;
    int groups;
    bool lightPaths;
  };
  for (const Case& c : {Case{2, ExchangeMode::Auto, PathLayout::Auto, 1, false},
                        Case{3, ExchangeMode::Auto, PathLayout::Auto, 1, false},
                        Case{3, ExchangeMode::Bulk, PathLayout::Auto, 1, false},
                        Case{4, ExchangeMode::Auto, PathLayout::Replay, 1, false},
                        Case{4, ExchangeMode::Auto, PathLayout::Auto, 2, false},
                        Case{3, ExchangeMode::Auto, PathLayout::Auto, 1, true}}) {
    SessionSettings s = small();
    s.exchange = c.exchange;
    s.pathLayout = c.layout;
    s.dataGroups = c.groups;
    s.partitioner = &bestPartitioner();
    if (c.lightPaths) s.lightPaths = true;
    const Rendered many = render(scene, s, c.ranks);
    SCOPED_TRACE(::testing::Message()
                 << c.ranks << " ranks, exchange " << int(c.exchange) << ", layout "
                 << int(c.layout) << ", " << c.groups << " groups, light paths " << c.lightPaths);
    EXPECT_TRUE(many.aovValues == one.aovValues);
    if (!c.lightPaths) {
      EXPECT_TRUE(many.linear == one.linear);
    }
  }
}

TEST(AovSession, TheColourIsTheColourWithoutAovs) {
  const Scene scene = loadScene("builtin:cornell");
  SessionSettings without = small();
  without.render.aovs.clear();
  for (int ranks : {1, 3}) {
    const Rendered a = render(scene, small(), ranks), b = render(scene, without, ranks);
    EXPECT_TRUE(a.linear == b.linear) << ranks << " ranks";
    EXPECT_TRUE(b.aovs.empty());
    EXPECT_TRUE(b.aovValues.empty());
  }
}

// The file sink writes what the session composited: the albedo file beside
// a .pfm holds the albedo channels, and a .png is refused.
TEST(AovSession, TheFileSinkWritesTheAovsBesideAPfm) {
  const Scene scene = loadScene("builtin:cornell");
  SessionSettings s = small();
  s.render.aovs = {Aov::Depth, Aov::Albedo};
  const Rendered expected = render(scene, s, 1);
  const std::string path = ::testing::TempDir() + "aov_sink.pfm";
  runRanks(1, [&](const Communicator& comm) {
    RenderSession session(scene, s, comm);
    ImageFileSink sink(path);
    session.run(sink);
  });
  const LinearImage albedo = readPfm(sideFilePath(path, "albedo"));
  const LinearImage depth = readPfm(sideFilePath(path, "depth"));
  ASSERT_EQ(albedo.rgb.size(), size_t(40 * 30));
  for (size_t i = 0; i < albedo.rgb.size(); ++i) {
    EXPECT_EQ(depth.rgb[i].x, expected.aovValues[4 * i]);
    EXPECT_EQ(albedo.rgb[i].x, expected.aovValues[4 * i + 1]);
    EXPECT_EQ(albedo.rgb[i].z, expected.aovValues[4 * i + 3]);
  }
  EXPECT_THROW(runRanks(1,
                        [&](const Communicator& comm) {
                          RenderSession session(scene, s, comm);
                          ImageFileSink sink(::testing::TempDir() + "aov_sink.png");
                          session.run(sink);
                        }),
               InputError);
}

}  // namespace
}  // namespace ferry
