#include "render/render_stats.h"

#include <algorithm>
#include <iterator>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "scene/scene_summary.h"

namespace ferry {

namespace {

// j[group][key] for a field with a group, else j[key].
template <typename Owner, typename Value>
nlohmann::json& slot(nlohmann::json& j, const StatsField<Owner, Value>& field) {
  return field.group ? j[field.group][field.key] : j[field.key];
}

nlohmann::json exchangeJson(const ExchangeCounters& c) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& field : kExchangeCounters) slot(j, field) = c.*field.member;
  return j;
}

}  // namespace

ExchangeCounters& ExchangeCounters::operator+=(const ExchangeCounters& o) {
  for (const auto& field : kExchangeCounters) this->*field.member += o.*field.member;
  return *this;
}

StageTimes& StageTimes::operator+=(const StageTimes& o) {
  for (const auto& field : kStageTimes) this->*field.member += o.*field.member;
  return *this;
}

ExchangeCounters FrameStats::exchangeTotal() const {
  ExchangeCounters t;
  for (const ExchangeCounters& c : perBounce) t += c;
  return t;
}

void FrameStats::merge(const FrameStats& o) {
  seconds = std::max(seconds, o.seconds);
  cpuSeconds += o.cpuSeconds;
  busiestRankCpuSeconds += o.busiestRankCpuSeconds;
  for (const auto& field : kFrameCounters) this->*field.member += o.*field.member;
  if (perBounce.size() < o.perBounce.size()) perBounce.resize(o.perBounce.size());
  for (size_t i = 0; i < o.perBounce.size(); ++i) perBounce[i] += o.perBounce[i];
  times += o.times;
}

nlohmann::json FrameStats::toJson() const {
  nlohmann::json j;
  j["frame"] = frame;
  j["seconds"] = seconds;
  j["cpu_seconds"] = cpuSeconds;
  j["busiest_rank_cpu_seconds"] = busiestRankCpuSeconds;
  for (const auto& field : kFrameCounters) slot(j, field) = this->*field.member;
  j["traces"]["total"] = raysTraced();
  j["rays_per_second"] = seconds > 0 ? double(raysTraced()) / seconds : 0.0;
  j["exchange"] = exchangeJson(exchangeTotal());
  nlohmann::json bounces = nlohmann::json::array();
  for (const ExchangeCounters& c : perBounce) bounces.push_back(exchangeJson(c));
  j["exchange_per_bounce"] = bounces;
  for (const auto& field : kStageTimes) slot(j, field) = times.*field.member;
  return j;
}

std::vector<uint64_t> FrameStats::counterValues() const {
  std::vector<uint64_t> values;
  values.reserve(std::size(kFrameCounters) + perBounce.size() * std::size(kExchangeCounters));
  for (const auto& field : kFrameCounters) values.push_back(this->*field.member);
  for (const ExchangeCounters& c : perBounce)
    for (const auto& field : kExchangeCounters) values.push_back(c.*field.member);
  return values;
}

void FrameStats::setCounterValues(std::span<const uint64_t> values) {
  constexpr size_t frameCounters = std::size(kFrameCounters);
  constexpr size_t perBounceCounters = std::size(kExchangeCounters);
  FERRY_CHECK_GE(values.size(), frameCounters);
  FERRY_CHECK_EQ((values.size() - frameCounters) % perBounceCounters, 0u);
  const uint64_t* v = values.data();
  for (const auto& field : kFrameCounters) this->*field.member = *v++;
  perBounce.assign((values.size() - frameCounters) / perBounceCounters, {});
  for (ExchangeCounters& c : perBounce)
    for (const auto& field : kExchangeCounters) c.*field.member = *v++;
}

std::vector<double> FrameStats::stageTimeValues() const {
  std::vector<double> values;
  for (const auto& field : kStageTimes) values.push_back(times.*field.member);
  return values;
}

void FrameStats::setStageTimeValues(std::span<const double> values) {
  FERRY_CHECK_EQ(values.size(), std::size(kStageTimes));
  const double* v = values.data();
  for (const auto& field : kStageTimes) times.*field.member = *v++;
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
  row("CPU time", fmt::format("{:.3f} s ({:.3f} s/frame, summed over ranks and threads)",
                              t.cpuSeconds, frames.empty() ? 0.0 : t.cpuSeconds / frames.size()));
  if (ranks > 1 && t.cpuSeconds > 0)
    row("busiest rank's CPU",
        fmt::format("{:.2f}x the mean rank's", t.busiestRankCpuSeconds * ranks / t.cpuSeconds));
  row("camera paths", formatCount(t.cameraPaths));
  if (t.lightPaths) row("light paths", formatCount(t.lightPaths));
  row("rays traced", fmt::format("{} ({} closest, {} shadow, {} re-trace)",
                                 formatCount(t.raysTraced()), formatCount(t.closestTraces),
                                 formatCount(t.occlusionTraces), formatCount(t.retraces)));
  row("rays per second", formatCount(uint64_t(t.seconds > 0 ? t.raysTraced() / t.seconds : 0)));
  row("rays forwarded",
      fmt::format("{} ({} per frame; {} shadow rays, {} only to be shaded; {} found nothing "
                  "where they were sent)",
                  formatCount(ex.raysForwarded),
                  formatCount(frames.empty() ? 0 : ex.raysForwarded / frames.size()),
                  formatCount(ex.shadowRaysForwarded), formatCount(ex.forwardedToShade),
                  formatCount(ex.visitsWithoutHit)));
  row("bytes sent", formatBytes(ex.bytesSent));
  if (ex.messages || t.terminationWaves)
    row("exchange", fmt::format("overlapped: {} messages, {} termination sums", ex.messages,
                                t.terminationWaves));
  else
    row("exchange rounds", fmt::format("{}", ex.rounds));
  row("stage seconds",
      fmt::format("generate {:.2f}, trace {:.2f}, exchange {:.2f}, shade {:.2f}, wait {:.2f}, "
                  "composite {:.2f} (summed over ranks, and on one rank over threads)",
                  t.times.generate, t.times.trace, t.times.exchange, t.times.shade, t.times.wait,
                  t.times.composite));
  if (t.mediumRealCollisions || t.mediumNullCollisions || t.mediumMajorantCells)
    row("media",
        fmt::format("{} real collisions, {} null collisions, {} majorant cells",
                    formatCount(t.mediumRealCollisions), formatCount(t.mediumNullCollisions),
                    formatCount(t.mediumMajorantCells)));
  if (t.retraceMisses) row("re-trace misses", fmt::format("{}", t.retraceMisses));
  return out;
}

}  // namespace ferry
