// How close Ferry's path tracer comes to the ceiling set by its trace backend
// alone, and whether the Embree backend's wavefront calls (Embree's stream
// API, rtcIntersect1M / rtcOccluded1M) beat single-ray calls
// (rtcIntersect1 / rtcOccluded1) in a tbb::parallel_for on the same rays.
//
// One frame is rendered once through the WavefrontRenderer with a traversal
// that records every ray Embree is asked about: the closest-hit and shadow
// rays of each wavefront (as the traversal receives them) and the shading
// re-traces (rebuilt exactly as WavefrontRenderer::shade makes them). Then:
//   Render       the whole frame (camera rays, traversal, shading, re-traces)
//   TraceStream  only the recorded queries, wavefront by wavefront, through
//                the backend's wavefront calls (TraceBackend::trace of a copy
//                of the recorded queue, TraceBackend::retrace in batches of
//                256 as shading makes them)
//   TraceSingle  the same queries, same batches, same parallel_for grain,
//                one rtcIntersect1 / rtcOccluded1 per ray (the re-traces
//                searching to the recorded distance, without the backend's
//                small margin: the same traversal work)
//   TraceStreamNoRetrace  TraceStream without the re-traces: what keeping
//                the hit instead of re-tracing would save
//   RenderRemote the whole frame as Ferry renders it by default (--retrace
//                remote: on one rank nothing is re-traced); its ceiling is
//                TraceStreamNoRetrace
// Render and the recording use --retrace all (the paper: every shaded path
// re-traced), so the ray counts of Render and TraceStream agree.
// Every benchmark reports rays/s over the same ray count (closest + shadow +
// re-trace), so their ratios are the figures in docs/performance.md. The
// ratios are printed at the end, from the median of the repetitions, which run
// randomly interleaved so a noisy machine hurts all variants alike.
//
//   build/bench/trace_ceiling_bench                    (5 repetitions)
//   build/bench/trace_ceiling_bench --benchmark_repetitions=9
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "builtin/builtin.h"
#include "core/floating_point_mode.h"
#include "path/path.h"
#include "render/frame_buffer.h"
#include "render/lights.h"
#include "render/ray_traversal.h"
#include "render/wavefront_renderer.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"

namespace ferry {
namespace {

// The queries of one wavefront, in the order the renderer makes them: the
// queue as the traversal received it, and shading's re-traces.
struct Wave {
  PathQueue<Path8> paths, shadowRays;
  std::vector<TraceRay> closest, shadow;  // the queue's rays, for single-ray calls
  std::vector<RetraceRay> retrace;
  std::vector<TraceRay> retraceRays;  // the same, for single-ray calls
};

// LocalTraversal that also writes down what it traces.
class RecordingTraversal final : public RayTraversal<Path8> {
 public:
  explicit RecordingTraversal(const TraceBackend& geometry) : inner_(geometry) {}
  bool anyRaysLeft(size_t localRays) override { return localRays > 0; }
  void traverse(RayQueues<Path8>& rays, std::vector<TraceHit>& pathHits, ExchangeCounters& exchange,
                FrameStats& stats) override {
    Wave& w = waves.emplace_back();
    w.paths = rays.paths;
    w.shadowRays = rays.shadowRays;
    for (const Path8& p : rays.paths)
      w.closest.push_back(TraceRay{p.origin, p.dir(), 0.0f, p.tmax});
    for (const Path8& p : rays.shadowRays)
      w.shadow.push_back(TraceRay{p.origin, p.dir(), 0.0f, p.tmax});
    inner_.traverse(rays, pathHits, exchange, stats);
    // With --retrace all, WavefrontRenderer::shade re-traces every path that hit.
    for (const Path8& p : rays.paths)
      if (p.hasHit()) {
        w.retrace.push_back({p.origin, p.dir(), p.tmax});
        w.retraceRays.push_back({p.origin, p.dir(), 0, p.tmax});
      }
  }
  std::vector<Wave> waves;

 private:
  LocalTraversal<Path8> inner_;
};

struct Setup {
  std::string spec;
  Scene scene;
  std::unique_ptr<TraceBackend> geometry;
  std::unique_ptr<LightSampler> lights;
  RenderSettings settings;
  std::vector<Wave> waves;
  uint64_t rays = 0;  // closest + shadow + re-trace, as FrameStats::raysTraced counts them
};

// The scenes and sizes measured; each is built and recorded once.
Setup& setup(int which) {
  static std::map<int, std::unique_ptr<Setup>> cache;
  auto& slot = cache[which];
  if (slot) return *slot;
  slot = std::make_unique<Setup>();
  Setup& s = *slot;
  s.spec = which == 0 ? "builtin:island?scale=0.1" : "builtin:cornell";
  s.scene = generateBuiltin(parseBuiltinSpec(s.spec));
  s.geometry = makeEmbreeBackend(s.scene);
  s.lights = std::make_unique<LightSampler>(s.scene);
  s.settings.width = 640;
  s.settings.height = 360;
  s.settings.samplesPerPixel = 1;
  s.settings.maxDepth = 5;
  s.settings.retraceAll = true;
  RecordingTraversal recorder(*s.geometry);
  WavefrontRenderer<Path8> renderer(s.scene, *s.geometry, *s.lights, recorder, s.settings);
  FrameBuffer fb(s.settings.width, s.settings.height);
  FrameStats stats = renderer.renderFrame(0, fb);
  s.waves = std::move(recorder.waves);
  s.rays = stats.raysTraced();
  uint64_t recorded = 0;
  for (const Wave& w : s.waves) recorded += w.closest.size() + w.shadow.size() + w.retrace.size();
  if (recorded != s.rays)
    std::fprintf(stderr, "warning: recorded %llu rays, the renderer counted %llu\n",
                 (unsigned long long)recorded, (unsigned long long)s.rays);
  return s;
}

void setLabels(benchmark::State& state, const Setup& s) {
  state.SetLabel(s.spec);
  state.counters["rays"] = double(s.rays);
  state.counters["rays/s"] =
      benchmark::Counter(double(s.rays), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Render(benchmark::State& state) {
  Setup& s = setup(int(state.range(0)));
  LocalTraversal<Path8> traversal(*s.geometry);
  WavefrontRenderer<Path8> renderer(s.scene, *s.geometry, *s.lights, traversal, s.settings);
  for (auto _ : state) {
    FrameBuffer fb(s.settings.width, s.settings.height);
    FrameStats stats = renderer.renderFrame(0, fb);
    benchmark::DoNotOptimize(fb.sum().data());
    if (stats.raysTraced() != s.rays)
      state.SkipWithError("the frame traced a different number of rays");
  }
  setLabels(state, s);
}

// The default renderer (--retrace remote): same frame, no re-traces on one rank.
void BM_RenderRemote(benchmark::State& state) {
  Setup& s = setup(int(state.range(0)));
  RenderSettings settings = s.settings;
  settings.retraceAll = false;
  LocalTraversal<Path8> traversal(*s.geometry);
  WavefrontRenderer<Path8> renderer(s.scene, *s.geometry, *s.lights, traversal, settings);
  uint64_t retraced = 0;
  for (auto _ : state) {
    FrameBuffer fb(settings.width, settings.height);
    FrameStats stats = renderer.renderFrame(0, fb);
    benchmark::DoNotOptimize(fb.sum().data());
    retraced = stats.retraces;
  }
  if (retraced != 0) state.SkipWithError("one rank re-traced with --retrace remote");
  setLabels(state, s);
}

// The backend's batch (256 rays): the grain of every parallel loop here.
constexpr size_t kGrain = 256;

void traceStream(benchmark::State& state, bool retrace) {
  Setup& s = setup(int(state.range(0)));
  PathQueue<Path8> queue;
  std::vector<TraceHit> hits;
  for (auto _ : state) {
    for (const Wave& w : s.waves) {
      queue = w.paths;  // the trace writes its answers into the paths
      hits.resize(queue.size());
      s.geometry->trace(queue, 0, {}, hits);
      queue = w.shadowRays;
      s.geometry->trace(queue, 0, {}, {});
      if (retrace) {
        hits.resize(w.retrace.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, w.retrace.size(), kGrain),
                          [&](const auto& r) {
                            for (size_t i = r.begin(); i < r.end(); i += kGrain) {
                              const size_t n = std::min(kGrain, r.end() - i);
                              s.geometry->retrace(std::span(w.retrace).subspan(i, n),
                                                  std::span(hits).subspan(i, n));
                            }
                          });
      }
      benchmark::DoNotOptimize(hits.data());
      benchmark::DoNotOptimize(queue.data());
    }
  }
  setLabels(state, s);
}

void BM_TraceStream(benchmark::State& state) {
  traceStream(state, true);
}
// What the re-traces cost: the same without them (rays/s still over all rays, so read its time
// only).
void BM_TraceStreamNoRetrace(benchmark::State& state) {
  traceStream(state, false);
}

// Single-ray calls, same grain as the backend's batches.
void intersectSingle(const TraceBackend& g, const std::vector<TraceRay>& rays,
                     std::vector<TraceHit>& hits) {
  hits.resize(rays.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kGrain), [&](const auto& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) hits[i] = g.intersect(rays[i]);
  });
}

void BM_TraceSingle(benchmark::State& state) {
  Setup& s = setup(int(state.range(0)));
  std::vector<TraceHit> hits;
  std::vector<uint8_t> occluded;
  for (auto _ : state) {
    for (const Wave& w : s.waves) {
      intersectSingle(*s.geometry, w.closest, hits);
      occluded.resize(w.shadow.size());
      tbb::parallel_for(tbb::blocked_range<size_t>(0, w.shadow.size(), kGrain), [&](const auto& r) {
        for (size_t i = r.begin(); i != r.end(); ++i)
          occluded[i] = s.geometry->occluded(w.shadow[i]);
      });
      intersectSingle(*s.geometry, w.retraceRays, hits);
      benchmark::DoNotOptimize(hits.data());
      benchmark::DoNotOptimize(occluded.data());
    }
  }
  setLabels(state, s);
}

// Arg 0: island at scale 0.1, arg 1: Cornell box; 640x360, 1 spp, max depth 5.
BENCHMARK(BM_Render)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRemote)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TraceStream)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TraceSingle)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TraceStreamNoRetrace)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// Console output as usual, plus the ratios of the median times per scene.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  RatioReporter() : ConsoleReporter(isatty(fileno(stdout)) ? OO_ColorTabular : OO_Tabular) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs)
      if (run.run_type == Run::RT_Iteration && !run.error_occurred) {
        times_[run.run_name.function_name][run.run_name.args].push_back(run.GetAdjustedRealTime());
        auto rays = run.counters.find("rays");
        if (rays != run.counters.end()) rays_[run.run_name.args] = rays->second.value;
      }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      size_t n = v.size();
      return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    };
    std::printf("\nratios of median frame/trace times (same rays; > 1: the first is slower)\n");
    for (const char* arg : {"0", "1"}) {
      auto get = [&](const char* f) -> double {
        auto it = times_.find(f);
        if (it == times_.end() || !it->second.count(arg)) return 0;
        return median(it->second.at(arg));
      };
      double render = get("BM_Render"), stream = get("BM_TraceStream"),
             single = get("BM_TraceSingle"), noRetrace = get("BM_TraceStreamNoRetrace");
      const char* name = arg[0] == '0' ? "island?scale=0.1" : "cornell";
      auto mrays = [&](double ms) { return ms > 0 ? rays_[arg] / ms / 1e3 : 0.0; };
      std::printf(
          "  %-18s render/trace-stream %6.2f   trace-single/trace-stream %6.3f   (medians %.1f / "
          "%.1f / %.1f ms,"
          " %.2f / %.2f / %.2f Mrays/s, %.0f rays, n=%zu)\n",
          name, stream > 0 ? render / stream : 0.0, stream > 0 ? single / stream : 0.0, render,
          stream, single, mrays(render), mrays(stream), mrays(single), rays_[arg],
          times_["BM_Render"][arg].size());
      std::printf("  %-18s re-traces: %.1f ms of the %.1f ms traced (%.0f %% of the render)\n", "",
                  stream - noRetrace, stream,
                  render > 0 ? 100 * (stream - noRetrace) / render : 0.0);
      double remote = get("BM_RenderRemote");
      std::printf(
          "  %-18s --retrace remote: render %.1f ms, render/trace-stream-no-retrace %6.2f,"
          " render(all)/render(remote) %6.2f\n",
          "", remote, noRetrace > 0 ? remote / noRetrace : 0.0, remote > 0 ? render / remote : 0.0);
    }
  }

 private:
  std::map<std::string, std::map<std::string, std::vector<double>>> times_;
  std::map<std::string, double> rays_;
};

}  // namespace
}  // namespace ferry

int main(int argc, char** argv) {
  ferry::useFixedFloatingPointMode();  // as ferry runs
  // Defaults that make one run a fair comparison on a shared machine; any flag given overrides
  // them.
  std::vector<char*> args(argv, argv + argc);
  std::string reps = "--benchmark_repetitions=5",
              interleave = "--benchmark_enable_random_interleaving=true";
  auto given = [&](const char* prefix) {
    for (int i = 1; i < argc; ++i)
      if (std::string(argv[i]).rfind(prefix, 0) == 0) return true;
    return false;
  };
  if (!given("--benchmark_repetitions")) args.push_back(reps.data());
  if (!given("--benchmark_enable_random_interleaving")) args.push_back(interleave.data());
  int n = int(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  ferry::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
