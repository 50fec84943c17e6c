#include "report/partition_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>

#include "core/clock.h"
#include "core/error.h"
#include "io/images/image_io.h"
#include "report/canvas.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {

MaxPartReport maxPartReport(Scene scene, const std::string& sceneName, int minRanks, int maxRanks,
                            const PartitionerOptions& base) {
  FERRY_CHECK_GE(minRanks, 1);
  FERRY_CHECK_LE(minRanks, maxRanks);
  MaxPartReport report;
  report.scene = sceneName;
  report.inputBytes = summarize(scene).memory.total();
  report.minRanks = minRanks;
  report.maxRanks = maxRanks;
  auto run = [&](Scene& s, const Partitioner& partitioner, bool whole) {
    PartitionerOptions o = base;
    o.partitioner = &partitioner;
    o.keepObjectsWhole = whole;
    auto start = Clock::now();
    std::vector<uint64_t> curve = maxPartBytesCurve(s, o, maxRanks);
    MaxPartSeries series;
    series.partitioner = partitioner.name();
    series.whole = whole;
    series.bytes.assign(curve.begin() + (minRanks - 1), curve.end());
    series.seconds = secondsSince(start);
    report.series.push_back(std::move(series));
  };
  // Kept whole, the partitioners that do not cut meshes leave the scene as
  // it is; those that cut, and breaking objects, rewrite it, so those run on
  // copies or last.
  std::vector<const Partitioner*> keep, cut;
  for (const Partitioner* p : partitioners())
    if (p->fromThePaper()) (p->cutsMeshes() ? cut : keep).push_back(p);
  for (const Partitioner* p : keep) run(scene, *p, true);
  for (const Partitioner* p : cut)
    for (bool whole : {true, false}) {
      Scene copy = scene;
      run(copy, *p, whole);
    }
  for (const Partitioner* p : keep) run(scene, *p, false);
  // In the paper's order, broken before whole.
  std::vector<MaxPartSeries> ordered;
  for (const std::string& name : paperPartitionerNames())
    for (bool whole : {false, true})
      for (MaxPartSeries& s : report.series)
        if (s.partitioner == name && s.whole == whole) ordered.push_back(s);
  report.series = std::move(ordered);
  return report;
}

void writeMaxPartCsv(const std::string& path, const MaxPartReport& report) {
  writeFileAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp);
    out << "ranks";
    for (const MaxPartSeries& s : report.series) out << "," << s.label();
    out << "\n";
    for (int n = report.minRanks; n <= report.maxRanks; ++n) {
      out << n;
      for (const MaxPartSeries& s : report.series) out << "," << s.bytes[n - report.minRanks];
      out << "\n";
    }
    out.close();
    if (!out) throw InputError(fmt::format("{}: could not write", path));
  });
}

std::vector<uint8_t> plotMaxPart(const MaxPartReport& report, int width, int height) {
  Canvas c(width, height);
  const Rgba ink{30, 30, 30, 255}, grid{215, 215, 215, 255};
  const int left = 70, right = 250, top = 62, bottom = 56;
  const int plotW = width - left - right, plotH = height - top - bottom;
  const bool logX = report.maxRanks >= 16 * report.minRanks;
  auto xOf = [&](double n) {
    double a = report.minRanks, b = std::max(report.maxRanks, report.minRanks + 1);
    double t = logX ? std::log2(n / a) / std::log2(b / a) : (n - a) / (b - a);
    return float(left + t * plotW);
  };
  auto yOf = [&](double percent) { return float(top + plotH * (1 - percent / 100.0)); };

  c.text(left, 10,
         fmt::format("{}: largest part vs. rank count ({} in all)", report.scene,
                     formatBytes(report.inputBytes)),
         ink, 2);
  // Grid and axes.
  for (int p = 0; p <= 100; p += 10) {
    float y = yOf(p);
    c.line(float(left), y, float(left + plotW), y, grid);
    std::string label = fmt::format("{}%", p);
    c.text(left - 8 - Canvas::textWidth(label, 1), int(y) - 5, label, ink, 1);
  }
  std::vector<int> ticks;
  if (logX) {
    for (int n = 1; n <= report.maxRanks; n *= 2)
      if (n >= report.minRanks) ticks.push_back(n);
  } else {
    int step = std::max(1, (report.maxRanks - report.minRanks) / 10);
    for (int n = report.minRanks; n <= report.maxRanks; n += step) ticks.push_back(n);
  }
  for (int n : ticks) {
    float x = xOf(n);
    c.line(x, float(top), x, float(top + plotH), grid);
    std::string label = std::to_string(n);
    c.text(int(x) - Canvas::textWidth(label) / 2, top + plotH + 8, label, ink, 1);
  }
  c.line(float(left), float(top), float(left), float(top + plotH), ink);
  c.line(float(left), float(top + plotH), float(left + plotW), float(top + plotH), ink);
  c.text(left + plotW / 2 - 60, top + plotH + 28, logX ? "ranks (log scale)" : "ranks", ink, 1);
  c.text(8, top - 20, "largest part, % of the scene's memory estimate", ink, 1);

  // Curves: colour by partitioner, dashed when kept whole. Partitioners that
  // often coincide (object-naive and object-proxies always do: the same
  // parts) are drawn wider first, so each stays visible under the next.
  const auto& names = paperPartitionerNames();
  const float widths[6] = {2.0f, 2.0f, 8.0f, 5.0f, 3.0f, 2.0f};
  for (const MaxPartSeries& s : report.series) {
    int k = int(std::find(names.begin(), names.end(), s.partitioner) - names.begin());
    Rgba color = rankColor(k == 5 ? 9 : k);
    float px = 0, py = 0;
    for (int n = report.minRanks; n <= report.maxRanks; ++n) {
      double percent = 100.0 * double(s.bytes[n - report.minRanks]) /
                       double(std::max<uint64_t>(1, report.inputBytes));
      float x = xOf(n), y = yOf(std::min(percent, 105.0));
      if (n > report.minRanks) c.line(px, py, x, y, color, widths[k], 1.0f, s.whole ? 6.0f : 0.0f);
      px = x;
      py = y;
    }
  }
  // Legend.
  int ly = top + 4;
  for (const MaxPartSeries& s : report.series) {
    int k = int(std::find(names.begin(), names.end(), s.partitioner) - names.begin());
    Rgba color = rankColor(k == 5 ? 9 : k);
    int lx = left + plotW + 16;
    c.line(float(lx), float(ly + 6), float(lx + 34), float(ly + 6), color, widths[k], 1.0f,
           s.whole ? 6.0f : 0.0f);
    c.text(lx + 42, ly, s.label(), ink, 1);
    ly += 18;
  }
  c.text(left + plotW + 16, ly + 8, "solid: non-instanced objects", ink, 1);
  c.text(left + plotW + 16, ly + 22, "  broken into meshes", ink, 1);
  c.text(left + plotW + 16, ly + 36, "dashed: kept whole", ink, 1);
  return c.rgba();
}

void writeMaxPartPlot(const std::string& path, const MaxPartReport& report, int width, int height) {
  writePng(path, width, height, plotMaxPart(report, width, height));
}

}  // namespace ferry
