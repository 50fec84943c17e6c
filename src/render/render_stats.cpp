#include "render/render_stats.h"

#include <algorithm>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "scene/scene_summary.h"

namespace ferry {

ExchangeCounters& ExchangeCounters::operator+=(const ExchangeCounters& o) {
  raysForwarded += o.raysForwarded;
  bytesSent += o.bytesSent;
  rounds += o.rounds;
  return *this;
}

StageTimes& StageTimes::operator+=(const StageTimes& o) {
  generate += o.generate;
  trace += o.trace;
  exchange += o.exchange;
  shade += o.shade;
  composite += o.composite;
  return *this;
}

ExchangeCounters FrameStats::exchangeTotal() const {
  ExchangeCounters t;
  for (const ExchangeCounters& c : perBounce) t += c;
  return t;
}

void FrameStats::merge(const FrameStats& o) {
  seconds = std::max(seconds, o.seconds);
  cameraPaths += o.cameraPaths;
  continuationRays += o.continuationRays;
  shadowRays += o.shadowRays;
  closestTraces += o.closestTraces;
  occlusionTraces += o.occlusionTraces;
  retraces += o.retraces;
  retraceMisses += o.retraceMisses;
  proxyQueries += o.proxyQueries;
  replayQueries += o.replayQueries;
  if (perBounce.size() < o.perBounce.size()) perBounce.resize(o.perBounce.size());
  for (size_t i = 0; i < o.perBounce.size(); ++i) perBounce[i] += o.perBounce[i];
  times += o.times;
}

nlohmann::json FrameStats::toJson() const {
  nlohmann::json j;
  j["frame"] = frame;
  j["seconds"] = seconds;
  j["camera_paths"] = cameraPaths;
  j["continuation_rays"] = continuationRays;
  j["shadow_rays"] = shadowRays;
  j["traces"] = {{"closest", closestTraces},      {"occlusion", occlusionTraces},
                 {"retrace", retraces},           {"retrace_misses", retraceMisses},
                 {"proxy_queries", proxyQueries}, {"replay_queries", replayQueries},
                 {"total", raysTraced()}};
  j["rays_per_second"] = seconds > 0 ? double(raysTraced()) / seconds : 0.0;
  ExchangeCounters ex = exchangeTotal();
  j["exchange"] = {
      {"rays_forwarded", ex.raysForwarded}, {"bytes_sent", ex.bytesSent}, {"rounds", ex.rounds}};
  nlohmann::json bounces = nlohmann::json::array();
  for (const ExchangeCounters& c : perBounce)
    bounces.push_back(
        {{"rays_forwarded", c.raysForwarded}, {"bytes_sent", c.bytesSent}, {"rounds", c.rounds}});
  j["exchange_per_bounce"] = bounces;
  j["stage_seconds"] = {{"generate", times.generate},
                        {"trace", times.trace},
                        {"exchange", times.exchange},
                        {"shade", times.shade},
                        {"composite", times.composite}};
  return j;
}

FrameStats RenderStats::total() const {
  FrameStats t;
  t.frame = -1;
  for (const FrameStats& f : frames) {
    double s = t.seconds + f.seconds;
    t.merge(f);
    t.seconds = s;
  }
  return t;
}

nlohmann::json RenderStats::toJson() const {
  nlohmann::json j;
  j["total"] = total().toJson();
  nlohmann::json perFrame = nlohmann::json::array();
  for (const FrameStats& f : frames) perFrame.push_back(f.toJson());
  j["frames"] = perFrame;
  return j;
}

std::string RenderStats::summaryText(int ranks) const {
  FrameStats t = total();
  ExchangeCounters ex = t.exchangeTotal();
  std::string out;
  auto row = [&](const std::string& label, const std::string& value) {
    out += fmt::format("  {:<22}{}\n", label, value);
  };
  out += "render stats\n";
  row("frames", fmt::format("{} in {:.3f} s ({:.3f} s/frame)", frames.size(), t.seconds,
                            frames.empty() ? 0.0 : t.seconds / frames.size()));
  row("ranks", fmt::format("{}", ranks));
  row("camera paths", formatCount(t.cameraPaths));
  row("rays traced", fmt::format("{} ({} closest, {} shadow, {} re-trace)",
                                 formatCount(t.raysTraced()), formatCount(t.closestTraces),
                                 formatCount(t.occlusionTraces), formatCount(t.retraces)));
  row("rays per second", formatCount(uint64_t(t.seconds > 0 ? t.raysTraced() / t.seconds : 0)));
  row("rays forwarded",
      fmt::format("{} ({} per frame)", formatCount(ex.raysForwarded),
                  formatCount(frames.empty() ? 0 : ex.raysForwarded / frames.size())));
  row("bytes sent", formatBytes(ex.bytesSent));
  row("exchange rounds", fmt::format("{}", ex.rounds));
  row("stage seconds",
      fmt::format("generate {:.2f}, trace {:.2f}, exchange {:.2f}, shade {:.2f}, "
                  "composite {:.2f} (summed over ranks, and on one rank over threads)",
                  t.times.generate, t.times.trace, t.times.exchange, t.times.shade,
                  t.times.composite));
  if (t.retraceMisses) row("re-trace misses", fmt::format("{}", t.retraceMisses));
  return out;
}

}  // namespace ferry
