#include "render/render_stats.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <iterator>
#include <set>
#include <string>

#include "core/error.h"
#include "path/path.h"

namespace ferry {
namespace {

// Every counter, bounce counter and stage time a different value, from `base` up.
FrameStats distinctStats(uint64_t base, size_t bounces) {
  FrameStats s;
  s.frame = 3;
  s.seconds = double(base) / 8;
  s.cpuSeconds = double(base) / 16;
  s.busiestRankCpuSeconds = double(base) / 32;
  uint64_t next = base;
  for (const auto& field : kFrameCounters) s.*field.member = next++;
  s.perBounce.resize(bounces);
  for (ExchangeCounters& c : s.perBounce)
    for (const auto& field : kExchangeCounters) c.*field.member = next++;
  for (const auto& field : kStageTimes) s.times.*field.member = double(next++) / 4;
  return s;
}

template <typename Owner, typename Value>
const nlohmann::json& at(const nlohmann::json& j, const StatsField<Owner, Value>& field) {
  return field.group ? j.at(field.group).at(field.key) : j.at(field.key);
}

std::set<std::string> keysOf(const nlohmann::json& j) {
  std::set<std::string> keys;
  for (const auto& item : j.items()) keys.insert(item.key());
  return keys;
}

TEST(RenderStats, EveryCounterAppearsInTheJsonUnderItsKey) {
  const FrameStats s = distinctStats(100, 2);
  const nlohmann::json j = s.toJson();
  for (const auto& field : kFrameCounters)
    EXPECT_EQ(at(j, field).get<uint64_t>(), s.*field.member) << field.key;
  ASSERT_EQ(j.at("exchange_per_bounce").size(), 2u);
  for (size_t b = 0; b < 2; ++b)
    for (const auto& field : kExchangeCounters)
      EXPECT_EQ(at(j.at("exchange_per_bounce")[b], field).get<uint64_t>(),
                s.perBounce[b].*field.member)
          << field.key;
  for (const auto& field : kExchangeCounters)
    EXPECT_EQ(at(j.at("exchange"), field).get<uint64_t>(),
              s.perBounce[0].*field.member + s.perBounce[1].*field.member)
        << field.key;
  for (const auto& field : kStageTimes)
    EXPECT_EQ(at(j, field).get<double>(), s.times.*field.member) << field.key;
  EXPECT_EQ(j.at("traces").at("total").get<uint64_t>(), s.raysTraced());
  EXPECT_EQ(j.at("frame").get<int>(), 3);
  EXPECT_EQ(j.at("cpu_seconds").get<double>(), s.cpuSeconds);
}

// The layout scripts read (bench/, tests/tools/check_stats.py): nothing more, nothing less.
TEST(RenderStats, JsonKeysAreTheDocumentedOnes) {
  const nlohmann::json j = distinctStats(1, 1).toJson();
  EXPECT_EQ(keysOf(j), (std::set<std::string>{
                           "frame", "seconds", "cpu_seconds", "busiest_rank_cpu_seconds",
                           "camera_paths", "light_paths", "continuation_rays", "shadow_rays",
                           "traces", "rays_per_second", "exchange", "exchange_per_bounce",
                           "stage_seconds", "primary_bytes_sent", "termination_waves", "media"}));
  EXPECT_EQ(keysOf(j.at("media")),
            (std::set<std::string>{"real_collisions", "null_collisions", "majorant_cells"}));
  EXPECT_EQ(keysOf(j.at("traces")),
            (std::set<std::string>{"closest", "occlusion", "retrace", "retrace_misses",
                                   "proxy_queries", "replay_queries", "primary_queries",
                                   "replica_queries", "skipped_queries", "total"}));
  const std::set<std::string> exchange = {"rays_forwarded",
                                          "shadow_rays_forwarded",
                                          "forwarded_to_shade",
                                          "visits_without_hit",
                                          "bytes_sent",
                                          "rounds",
                                          "messages"};
  EXPECT_EQ(keysOf(j.at("exchange")), exchange);
  EXPECT_EQ(keysOf(j.at("exchange_per_bounce")[0]), exchange);
  EXPECT_EQ(keysOf(j.at("stage_seconds")),
            (std::set<std::string>{"generate", "trace", "exchange", "shade", "wait", "composite"}));
}

TEST(RenderStats, MergeAddsEveryCounterAndCpuTimeAndKeepsTheSlowestSeconds) {
  FrameStats a = distinctStats(10, 1);
  const FrameStats b = distinctStats(1000, 3);
  const FrameStats before = a;
  a.merge(b);
  EXPECT_EQ(a.seconds, std::max(before.seconds, b.seconds));
  EXPECT_EQ(a.cpuSeconds, before.cpuSeconds + b.cpuSeconds);
  EXPECT_EQ(a.busiestRankCpuSeconds, before.busiestRankCpuSeconds + b.busiestRankCpuSeconds);
  for (const auto& field : kFrameCounters)
    EXPECT_EQ(a.*field.member, before.*field.member + b.*field.member) << field.key;
  ASSERT_EQ(a.perBounce.size(), 3u);
  for (size_t i = 0; i < 3; ++i)
    for (const auto& field : kExchangeCounters)
      EXPECT_EQ(a.perBounce[i].*field.member,
                (i < 1 ? before.perBounce[i].*field.member : 0) + b.perBounce[i].*field.member)
          << field.key << " bounce " << i;
  for (const auto& field : kStageTimes)
    EXPECT_EQ(a.times.*field.member, before.times.*field.member + b.times.*field.member)
        << field.key;
}

TEST(RenderStats, CounterArraysRoundTrip) {
  const FrameStats s = distinctStats(7, 4);
  const std::vector<uint64_t> counters = s.counterValues();
  ASSERT_EQ(counters.size(), std::size(kFrameCounters) + 4 * std::size(kExchangeCounters));
  FrameStats back;
  back.setCounterValues(counters);
  back.setStageTimeValues(s.stageTimeValues());
  back.frame = s.frame;
  back.seconds = s.seconds;
  back.cpuSeconds = s.cpuSeconds;
  back.busiestRankCpuSeconds = s.busiestRankCpuSeconds;
  EXPECT_EQ(back.toJson(), s.toJson());
  EXPECT_THROW(back.setCounterValues(std::span<const uint64_t>(counters).first(2)), InternalError);
}

}  // namespace
}  // namespace ferry

namespace ferry {

// The kinds of the rays sent are counted from their flags: shadow rays, and
// rays sent only to be shaded (traversed); a traversed shadow ray is a shadow ray.
TEST(RenderStats, SentRaysAreCountedByKind) {
  std::vector<Path8> rays(7);
  rays[0].setPixelAndFlags(0, kPathShadow);
  rays[1].setPixelAndFlags(1, kPathShadow | kPathOccluded);
  rays[2].setPixelAndFlags(2, kPathTraversed);
  rays[3].setPixelAndFlags(3, kPathTraversed | kPathAfterSpecular);
  rays[4].setPixelAndFlags(4, kPathShadow | kPathTraversed);
  rays[5].setPixelAndFlags(5, 0);
  rays[6].setPixelAndFlags(6, kPathAfterSpecular);
  ExchangeCounters c;
  c.countSent(rays.data(), rays.size(), sizeof(Path8));
  c.countSent(rays.data() + 2, 1, sizeof(Path8));
  EXPECT_EQ(c.raysForwarded, 8u);
  EXPECT_EQ(c.bytesSent, 8 * sizeof(Path8));
  EXPECT_EQ(c.shadowRaysForwarded, 3u);
  EXPECT_EQ(c.forwardedToShade, 3u);
}

}  // namespace ferry
