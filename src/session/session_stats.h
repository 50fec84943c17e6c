// The --stats JSON of a render session: the scene, the settings as run, the
// counters summed over ranks (render_stats.h), memory per rank and seconds.
// Scripts read it (bench/, tests/tools/check_stats.py): keys only ever grow.
// "seconds" holds the command's "total" and the set-up's intervals to the
// first pixel (kSetupTimes, render_session.h): rank 0's, the slowest rank's
// ("slowest", slowestSetup) and each rank's ("per_rank").
#pragma once

#include <string>
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
// Writes `stats` to `path` through a temporary file and a rename.
void writeStatsFile(const std::string& path, const nlohmann::json& stats);

}  // namespace ferry
