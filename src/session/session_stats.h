// The --stats JSON of a render session: the scene, the settings as run, the
// counters summed over ranks (render_stats.h), memory per rank and seconds.
// Scripts read it (bench/, tests/tools/check_stats.py): keys only ever grow.
// "seconds" holds the command's "total" and the set-up's intervals to the
// first pixel (kSetupTimes, render_session.h): rank 0's, the slowest rank's
// ("slowest", slowestSetup) and each rank's ("per_rank").
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "session/render_session.h"

namespace ferry {

// What the session does not know: where its image went and how long the
// whole command took.
struct StatsContext {
  std::string output;
  double totalSeconds = 0;
};

// The rank whose own set-up took longest (first pixel less the wait in
// "agree"): the one the others waited for, whose intervals say what held up
// the first pixel (0 when `setup` is empty).
size_t slowestSetup(const std::vector<SetupTimes>& setup);

nlohmann::json sessionStatsJson(const RenderSession& session, const SessionReport& report,
                                const StatsContext& context);
// The table `ferry render` prints after a render: counters, memory per
// rank, time to first pixel, compositing (rank 0's view of every rank).
std::string sessionSummaryText(const RenderSession& session, const SessionReport& report);
// A set-up's intervals up to (not including) the one named `until`, as
// "start 0.10, load 7.28, build 2.93" (kSetupTimes; intervals of 0 left out).
std::string setupIntervalsText(const SetupTimes& times, std::string_view until);

// Writes `stats` to `path` through a temporary file and a rename.
void writeStatsFile(const std::string& path, const nlohmann::json& stats);

}  // namespace ferry
