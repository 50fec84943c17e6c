#include "session/session_stats.h"

#include <algorithm>
#include <fstream>

#include <fmt/format.h>

#include "core/error.h"
#include "io/images/image_io.h"
#include "render/aov.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

double maxOf(const std::vector<double>& v) {
  return *std::max_element(v.begin(), v.end());
}

}  // namespace

size_t slowestSetup(const std::vector<SetupTimes>& setup) {
  auto ownWork = [](const SetupTimes& t) { return t.firstPixel - t.agree; };
  size_t slowest = 0;
  for (size_t rank = 1; rank < setup.size(); ++rank)
    if (ownWork(setup[rank]) > ownWork(setup[slowest])) slowest = rank;
  return slowest;
}

nlohmann::json sessionStatsJson(const RenderSession& session, const SessionReport& report,
                                const StatsContext& context) {
  const SessionSettings& s = session.settings();
  const RenderSettings& r = s.render;
  const RankMemory& memory = report.memory;
  const int ranks = int(memory.estimated.size());
  nlohmann::json j;
  j["scene"] = session.summary().toJson();
  j["settings"] = {{"width", r.width},
                   {"height", r.height},
                   {"crop", {r.crop.x0, r.crop.x1, r.crop.y0, r.crop.y1}},
                   {"image_width", r.imageWidth()},
                   {"image_height", r.imageHeight()},
                   {"spp", r.samplesPerPixel},
                   {"frames", r.frames},
                   {"max_depth", r.maxDepth},
                   {"light_strategy", lightStrategyName(r.lightStrategy)},
                   {"mis_heuristic", misHeuristicName(r.misHeuristic)},
                   {"light_choice", lightChoiceName(r.lightChoice)},
                   {"seed", r.seed},
                   {"sampler", samplerName(r.sampler)},
                   {"view", r.view},
                   {"threads", session.threads()},
                   {"ranks", ranks},
                   {"data_groups", s.dataGroups},
                   {"transport", session.communicator().transport()},
                   {"forwarding", toString(s.forwarding)},
                   {"exchange", ranks > 1 ? toString(s.exchange) : "none"},
                   {"chunk", r.chunkPixels},
                   {"retrace", toString(s.retrace)},
                   {"instancing", toString(s.instancing)},
                   {"partition", session.partitionerName()},
                   {"output", context.output},
                   {"aov", aovListText(r.aovs)},
                   {"path_layout", report.pathLayout},
                   {"path_bytes", report.pathBytes}};
  j["render"] = report.stats.toJson();
  j["render"]["rays_received"] = report.raysReceived;
  j["render"]["revisits"] = report.revisits;
  j["render"]["composite_bytes_sent"] = report.compositeBytes;
  nlohmann::json perRank = nlohmann::json::array();
  for (int rank = 0; rank < ranks; ++rank)
    perRank.push_back({{"rank", rank},
                       {"data_group", rank / (ranks / std::max(1, s.dataGroups))},
                       {"estimated_bytes", memory.estimated[rank]},
                       {"embree_bytes", memory.embree[rank]},
                       {"embree_peak_bytes", memory.embreePeak[rank]},
                       {"proxy_bytes", memory.proxies[rank]},
                       {"resident_bytes", memory.resident[rank]},
                       {"peak_resident_bytes", memory.residentPeak[rank]}});
  j["memory"] = {{"scene_estimated_bytes", session.summary().memory.total()},
                 {"max_estimated_bytes", maxOf(memory.estimated)},
                 {"max_embree_bytes", maxOf(memory.embree)},
                 {"max_proxy_bytes", maxOf(memory.proxies)},
                 {"max_peak_resident_bytes", maxOf(memory.residentPeak)},
                 {"per_rank", perRank}};
  // Set-up: rank 0's at the top (its "load" and "build" as ever), the
  // slowest rank's under "slowest", every rank's under "per_rank".
  auto setupJson = [](const SetupTimes& t, size_t rank) {
    nlohmann::json out;
    for (const auto& field : kSetupTimes) out[field.key] = t.*field.member;
    out["rank"] = rank;
    return out;
  };
  nlohmann::json setupPerRank = nlohmann::json::array();
  for (size_t rank = 0; rank < report.setup.size(); ++rank)
    setupPerRank.push_back(setupJson(report.setup[rank], rank));
  if (report.setup.empty()) setupPerRank.push_back(setupJson({}, 0));
  j["seconds"] = setupPerRank[0];
  j["seconds"].erase("rank");
  j["seconds"]["total"] = context.totalSeconds;
  j["seconds"]["slowest"] = setupPerRank[slowestSetup(report.setup)];
  j["seconds"]["per_rank"] = setupPerRank;
  return j;
}

std::string setupIntervalsText(const SetupTimes& times, std::string_view until) {
  std::string out;
  for (const auto& field : kSetupTimes) {
    if (field.key == until) break;
    const double seconds = times.*field.member;
    if (seconds == 0) continue;  // e.g. no partitioning for a part directory
    out += fmt::format("{}{} {:.2f}", out.empty() ? "" : ", ", field.key, seconds);
  }
  return out;
}

std::string sessionSummaryText(const RenderSession& session, const SessionReport& report) {
  const int ranks = session.communicator().size();
  std::string out = report.stats.summaryText(ranks);
  auto largest = [](const std::vector<double>& v) { return uint64_t(maxOf(v)); };
  const RankMemory& memory = report.memory;
  out += fmt::format(
      "  {:<22}{} of {} estimated, {} Embree, {} proxies, {} peak resident (largest rank)\n",
      "memory per rank", formatBytes(largest(memory.estimated)),
      formatBytes(session.summary().memory.total()), formatBytes(largest(memory.embree)),
      formatBytes(largest(memory.proxies)), formatBytes(largest(memory.residentPeak)));
  const size_t slowest = slowestSetup(report.setup);
  if (slowest < report.setup.size())
    out += fmt::format("  {:<22}{:.2f} s; {}: {} s\n", "time to first pixel",
                       report.setup[slowest].firstPixel,
                       ranks > 1 ? fmt::format("slowest rank {}", slowest) : std::string("set-up"),
                       setupIntervalsText(report.setup[slowest], "first_pixel"));
  out += fmt::format("  {:<22}{} ({} sent by direct send)\n", "composite",
                     fmt::format("{:.3f} s", report.compositeSeconds),
                     formatBytes(report.compositeBytes));
  if (report.revisits) out += fmt::format("  {:<22}{}\n", "REVISITS", report.revisits);
  return out;
}

void writeStatsFile(const std::string& path, const nlohmann::json& stats) {
  writeFileAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp);
    out << stats.dump(2) << "\n";
    if (!out) throw InputError(fmt::format("{}: could not write", path));
  });
}

}  // namespace ferry
