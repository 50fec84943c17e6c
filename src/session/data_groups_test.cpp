// Data groups (SessionSettings::dataGroups): the ranks split into groups
// that each hold the whole scene and render every G-th sample (or, with fewer
// samples a frame than groups, a slice of a sample's pixels); the image is
// the one-rank image bit for bit, with surfaces and with volume bricks, on
// both exchanges; a rank count the groups do not divide is refused.
#include <gtest/gtest.h>

#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "io/scene_loader.h"
#include "partition/partitioner.h"
#include "session/render_session.h"
#include "session/session_test_util.h"

namespace ferry {
namespace {

std::vector<Vec3f> render(const Scene& scene, const SessionSettings& settings, int ranks) {
  return testing::renderOnRanks(scene, settings, ranks);
}

SessionSettings small() {
  SessionSettings s;
  s.render.width = 36;
  s.render.height = 28;
  s.render.samplesPerPixel = 4;
  s.render.maxDepth = 4;
  return s;
}

TEST(DataGroups, TheImageIsTheOneRankImage) {
  const Scene scene = loadScene("builtin:cornell");
  const std::vector<Vec3f> one = render(scene, small(), 1);
  ASSERT_FALSE(one.empty());
  struct Case {
    int ranks, groups;
    ExchangeMode exchange;
  };
  for (const Case& c : {Case{2, 2, ExchangeMode::Auto}, Case{4, 2, ExchangeMode::Auto},
                        Case{4, 2, ExchangeMode::Bulk}, Case{6, 3, ExchangeMode::Auto},
                        Case{8, 2, ExchangeMode::Auto}}) {
    SessionSettings s = small();
    s.dataGroups = c.groups;
    s.exchange = c.exchange;
    s.partitioner = &bestPartitioner();
    EXPECT_TRUE(render(scene, s, c.ranks) == one)
        << c.ranks << " ranks in " << c.groups << " groups";
  }
}

// With fewer samples a frame than groups (the viewer's one sample a frame),
// the groups that take a sample split its pixels: still the one-rank image,
// and no group idles.
TEST(DataGroups, FewerSamplesThanGroupsSplitThePixels) {
  const Scene scene = loadScene("builtin:cornell");
  for (int spp : {1, 2}) {
    SessionSettings base = small();
    base.render.samplesPerPixel = spp;
    base.render.frames = 2;
    const std::vector<Vec3f> one = render(scene, base, 1);
    ASSERT_FALSE(one.empty());
    struct Case {
      int ranks, groups;
      ExchangeMode exchange;
    };
    for (const Case& c : {Case{2, 2, ExchangeMode::Auto}, Case{4, 2, ExchangeMode::Bulk},
                          Case{3, 3, ExchangeMode::Auto}, Case{8, 4, ExchangeMode::Auto}}) {
      SessionSettings s = base;
      s.dataGroups = c.groups;
      s.exchange = c.exchange;
      s.partitioner = &bestPartitioner();
      EXPECT_TRUE(render(scene, s, c.ranks) == one)
          << spp << " spp, " << c.ranks << " ranks in " << c.groups << " groups";
    }
  }
}

TEST(DataGroups, ARankCountTheGroupsDoNotDivideIsRefused) {
  SessionSettings s = small();
  s.dataGroups = 2;
  try {
    render(loadScene("builtin:cornell"), s, 3);
    FAIL() << "3 ranks in 2 groups were accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 data groups"), std::string::npos) << e.what();
  }
}

TEST(InProcessSplit, GroupsTalkAmongThemselvesAndAnAbortEndsEveryRank) {
  runRanks(5, [](const Communicator& comm) {
    const auto group = comm.split(comm.rank() % 2);  // {0, 2, 4} and {1, 3}
    EXPECT_EQ(group->size(), comm.rank() % 2 == 0 ? 3 : 2);
    EXPECT_EQ(group->rank(), comm.rank() / 2);
    EXPECT_EQ(group->sum(uint64_t(comm.rank())), comm.rank() % 2 == 0 ? 6u : 4u);
    EXPECT_EQ(comm.sum(uint64_t(1)), 5u);
  });
  // A rank that fails inside its group's collective ends the ranks of the other group too.
  EXPECT_THROW(runRanks(4,
                        [](const Communicator& comm) {
                          const auto group = comm.split(comm.rank() / 2);
                          if (comm.rank() == 3) throw InputError("rank 3 fails");
                          group->barrier();  // rank 2 waits for rank 3 here
                          comm.barrier();
                        }),
               InputError);
}

}  // namespace
}  // namespace ferry
