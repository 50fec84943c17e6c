// The proxy query that decides which rank generates a camera path
// (proxy-guided primaries, paper Section 3.3) and where a ray is forwarded:
// the closest proxy along a ray whose owners the ray has not visited. At 8
// ranks this query was 81 % of all stage time (issue 13), so it is measured
// here on its own, side by side with the ProxyBvh of da05014 (a median split
// over centres, children visited in a fixed order: `BaselineProxyBvh` below,
// kept only as this benchmark's baseline), in one run.
//
// Proxies: the island's 8-rank `best` partition (the default scale: about
// 78 K proxies), and the same proxies tiled 5 x 5 over the plane with the
// island's extent as pitch (about 2 M proxies, the size of the scale=30
// partition; a stand-in, since partitioning scale=30 itself needs 4.5 GB).
// Rays: the camera rays of the island's first view at 640x360, one per pixel
// centre, nothing excluded (the primary-ownership query); and the same rays
// with rank 0 excluded (a forwarding decision after a local trace).
// Each benchmark checks that both trees answer every query identically.
//
//   build/bench/proxy_query_bench                      (ratios printed at the end)
//   build/bench/proxy_query_bench --benchmark_repetitions=5
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/floating_point_mode.h"
#include "io/scene_loader.h"
#include "partition/partitioner.h"
#include "render/camera.h"
#include "scene/scene.h"
#include "trace/proxy_bvh.h"

namespace ferry {
namespace {

// The ProxyBvh of da05014: median split on the longest axis of the centres,
// leaves of 4, children pushed left-then-right, ties to the lower index.
class BaselineProxyBvh {
 public:
  explicit BaselineProxyBvh(const std::vector<Proxy>& proxies) : proxies_(proxies) {
    for (const Proxy& p : proxies_) masks_.push_back(p.owners.mask());
    order_.resize(proxies_.size());
    for (size_t i = 0; i < order_.size(); ++i) order_[i] = int32_t(i);
    if (!proxies_.empty()) build(0, int32_t(proxies_.size()), 0);
  }
  ProxyBvh::Hit closest(Vec3f origin, Vec3f direction, float tmax, RankMask excluded) const {
    ProxyBvh::Hit best;
    Vec3f inv{1 / direction.x, 1 / direction.y, 1 / direction.z};
    int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if ((node.owners & ~excluded) == 0) continue;
      float tNode;
      if (!intersectBox(node.bounds, origin, inv,
                        std::min(tmax, std::nextafter(best.tEnter, kInfinity)), tNode))
        continue;
      if (node.left < 0) {
        for (int32_t i = node.first; i < node.first + node.count; ++i) {
          int32_t id = order_[i];
          if (masks_[size_t(id)] & excluded) continue;
          float t;
          if (!intersectBox(proxies_[id].bounds, origin, inv, tmax, t)) continue;
          if (t < best.tEnter || (t == best.tEnter && id < best.proxy)) best = {id, t};
        }
      } else {
        stack[top++] = node.right;
        stack[top++] = node.left;
      }
    }
    return best;
  }

 private:
  struct Node {
    Box3f bounds;
    RankMask owners = 0;
    int32_t left = -1, right = -1, first = 0, count = 0;
  };
  int32_t build(int32_t first, int32_t count, int depth) {
    int32_t index = int32_t(nodes_.size());
    nodes_.push_back({});
    Box3f bounds, centers;
    RankMask owners = 0;
    for (int32_t i = first; i < first + count; ++i) {
      bounds.extend(proxies_[order_[i]].bounds);
      centers.extend(proxies_[order_[i]].bounds.center());
      owners |= masks_[size_t(order_[i])];
    }
    nodes_[index].bounds = bounds;
    nodes_[index].owners = owners;
    if (count <= 4 || depth > 60) {
      nodes_[index].first = first;
      nodes_[index].count = count;
      return index;
    }
    int axis = centers.longestAxis();
    int32_t mid = first + count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                     [&](int32_t a, int32_t b) {
                       float ca = proxies_[a].bounds.center()[axis],
                             cb = proxies_[b].bounds.center()[axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    int32_t left = build(first, mid - first, depth + 1);
    int32_t right = build(mid, first + count - mid, depth + 1);
    nodes_[index].left = left;
    nodes_[index].right = right;
    return index;
  }
  const std::vector<Proxy>& proxies_;
  std::vector<RankMask> masks_;
  std::vector<int32_t> order_;
  std::vector<Node> nodes_;
};

// The image whose camera rays are queried (one per pixel centre).
constexpr int kWidth = 640, kHeight = 360;

struct Ray {
  Vec3f origin, direction;
};

struct Case {
  std::vector<Proxy> proxies;
  std::vector<Ray> rays;
  std::unique_ptr<ProxyBvh> tree;
  std::unique_ptr<BaselineProxyBvh> baseline;
};

// The island's 8-rank best partition and its first view's camera rays.
const Case& islandCase(int tiles) {
  static std::map<int, std::unique_ptr<Case>> cases;
  auto& slot = cases[tiles];
  if (slot) return *slot;
  slot = std::make_unique<Case>();
  Case& c = *slot;
  Scene scene = loadScene("builtin:island");
  const CameraView view = scene.view("");
  PartitionerOptions options;
  options.name = "best";
  Partition partition = partitionScene(scene, 8, options);
  Box3f extent;
  for (const Proxy& p : partition.proxies) extent.extend(p.bounds);
  const Vec3f pitch = extent.upper - extent.lower;
  for (int i = 0; i < tiles; ++i)
    for (int j = 0; j < tiles; ++j) {
      const Vec3f shift{float(i - tiles / 2) * pitch.x, 0, float(j - tiles / 2) * pitch.z};
      for (Proxy p : partition.proxies) {
        p.bounds.lower = p.bounds.lower + shift;
        p.bounds.upper = p.bounds.upper + shift;
        c.proxies.push_back(p);
      }
    }
  Camera camera(view, kWidth, kHeight);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      c.rays.push_back({camera.origin(), camera.direction(float(x) + 0.5f, float(y) + 0.5f)});
  c.tree = std::make_unique<ProxyBvh>(c.proxies);
  c.baseline = std::make_unique<BaselineProxyBvh>(c.proxies);
  for (RankMask excluded : {RankMask(0), RankMask(1)})
    for (const Ray& r : c.rays) {
      ProxyBvh::Hit a = c.tree->closest(r.origin, r.direction, kInfinity, excluded);
      ProxyBvh::Hit b = c.baseline->closest(r.origin, r.direction, kInfinity, excluded);
      if (a.proxy != b.proxy || a.tEnter != b.tEnter) {
        std::fprintf(stderr, "proxy_query_bench: the trees disagree (%d vs %d)\n", a.proxy,
                     b.proxy);
        std::abort();
      }
    }
  std::fprintf(stderr, "proxy_query_bench: %zu proxies, %zu rays, %zu tree nodes\n",
               c.proxies.size(), c.rays.size(), c.tree->nodeCount());
  return c;
}

template <bool kBaseline>
void BM_Query(benchmark::State& state) {
  const Case& c = islandCase(int(state.range(0)));
  const RankMask excluded = RankMask(state.range(1));
  int64_t found = 0;
  for (auto _ : state) {
    for (const Ray& r : c.rays) {
      ProxyBvh::Hit h = kBaseline ? c.baseline->closest(r.origin, r.direction, kInfinity, excluded)
                                  : c.tree->closest(r.origin, r.direction, kInfinity, excluded);
      found += h.found();
    }
  }
  benchmark::DoNotOptimize(found);
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(c.rays.size()));
  state.counters["us_per_query"] =
      benchmark::Counter(double(state.iterations()) * double(c.rays.size()) * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// Args: tiles (1: 78 K proxies, 5: ~2 M), excluded mask (0: camera rays, 1: rank 0 visited).
BENCHMARK_TEMPLATE(BM_Query, true)
    ->Name("Baseline")
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({5, 0})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Query, false)
    ->Name("ProxyBvh")
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({5, 0})
    ->Unit(benchmark::kMillisecond);

// Prints Baseline / ProxyBvh time per query for each case.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.run_type != Run::RT_Iteration) continue;
      std::string name = run.benchmark_name();
      std::string args = name.substr(name.find('/'));
      // CPU time per query, in microseconds (this machine is shared: CPU
      // time is steadier than wall time).
      const double queries = double(kWidth) * double(kHeight);
      (name.rfind("Baseline", 0) == 0 ? baseline_ : tree_)[args] =
          run.GetAdjustedCPUTime() * 1e3 / queries;  // ms -> us
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf("\nCPU time per query (args: tiles/excluded), baseline and ProxyBvh:\n");
    for (const auto& [args, base] : baseline_)
      if (tree_.count(args))
        std::printf("  %-8s %.3f us  %.3f us  %.2fx faster\n", args.c_str(), base, tree_.at(args),
                    base / tree_.at(args));
  }

 private:
  std::map<std::string, double> baseline_, tree_;
};

}  // namespace
}  // namespace ferry

int main(int argc, char** argv) {
  ferry::useFixedFloatingPointMode();  // as ferry runs
  benchmark::Initialize(&argc, argv);
  ferry::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
}
