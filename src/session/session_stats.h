// The --stats JSON of a render session: the scene, the settings as run, the
// counters summed over ranks (render_stats.h), memory per rank and seconds.
// Scripts read it (bench/, tests/tools/check_stats.py): keys only ever grow.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "session/render_session.h"

namespace ferry {

// What the session does not know: where its image went and how long the
// whole command took.
struct StatsContext {
  std::string output;
  double totalSeconds = 0;
};

nlohmann::json sessionStatsJson(const RenderSession& session, const SessionReport& report,
                                const StatsContext& context);
// Writes `stats` to `path` through a temporary file and a rename.
void writeStatsFile(const std::string& path, const nlohmann::json& stats);

}  // namespace ferry
