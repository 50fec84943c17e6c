// The distributed layer's central property, in one process: ranks as threads
// (InProcessCommunicator), each holding only its part of the scene, render
// the image the one-rank renderer renders, for every forwarding mode, both
// 36-byte path layouts, both exchanges (bulk rounds, overlapped at several
// chunk sizes) and two partitioners, at 2, 3 and 4 ranks. The frame buffer
// sums in fixed point, so the image is the one-rank image bit for bit, except
// in at most 0.2 % of the pixels (a ray meeting two surfaces at exactly the
// same distance takes whichever the traversal finds first, and that depends
// on how the content is split); no ray visits a rank twice; rays forwarded
// equal rays received; every shading re-trace finds its hit.
#include "distributed/distributed_traversal.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "comm/in_process_communicator.h"
#include "compositing/compositor.h"
#include "io/scene_loader.h"
#include "partition/partitioner.h"
#include "path/path.h"
#include "render/lights.h"
#include "render/wavefront_renderer.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"

namespace ferry {
namespace {

// The one place this test builds a rank's trace geometry (over the instances
// it owns), so a change of the trace backend's interface touches one function.
std::unique_ptr<TraceBackend> buildGeometry(Scene& scene, const std::vector<int32_t>& owned) {
  return makeEmbreeBackend(scene, owned);
}

struct SceneCase {
  std::string name, spec;
  int width, height, samplesPerPixel, maxDepth;
  bool lightPaths = false;
  float maxSampleLuminance = 0;  // pbrt's film clamp of each camera sample; 0: none
  float lensRadius = 0, focalDistance = 1;
};

RenderSettings settingsFor(const SceneCase& c) {
  RenderSettings s;
  s.width = c.width;
  s.height = c.height;
  s.samplesPerPixel = c.samplesPerPixel;
  s.maxDepth = c.maxDepth;
  s.seed = 3;
  s.lightPaths = c.lightPaths;
  if (c.maxSampleLuminance > 0)
    s.sampleClamp = {SampleClamp::Measure::Luminance, c.maxSampleLuminance};
  if (c.lensRadius > 0) {
    s.lensRadius = c.lensRadius;
    s.focalDistance = c.focalDistance;
  }
  return s;
}

// A loaded scene, its lights (taken from the scene as given, before the
// partitioner rewrites it: as the `ferry` command does), and a partition of a
// copy of it.
struct PartitionedScene {
  Scene scene;  // as the partitioner rewrote it; every rank copies it
  Partition partition;
};

PartitionedScene partitioned(const Scene& loaded, int ranks, const std::string& partitioner,
                             uint32_t seed) {
  PartitionedScene p{loaded, {}};
  PartitionerOptions options;
  options.partitioner = &partitionerNamed(partitioner);
  options.seed = seed;
  p.partition = partitionScene(p.scene, ranks, options);
  return p;
}

// What a render gives: the image (rank 0) and the counters summed over ranks.
struct RenderResult {
  std::vector<Vec3f> image;
  uint64_t cameraPaths = 0, forwarded = 0, received = 0, revisits = 0, retraceMisses = 0,
           proxyQueries = 0, forwardedToShade = 0, visitsWithoutHit = 0;
};

// One frame on this rank (set up as the `ferry` command sets up a rank:
// LocalTraversal on one rank, DistributedTraversal on more), composited.
template <typename Path>
RenderResult renderFrame(const Communicator& comm, const Scene& scene, const TraceBackend& geometry,
                         const LightSampler& lights, const Partition& partition,
                         ForwardingMode mode, const RenderSettings& settings,
                         ExchangeMode exchange = ExchangeMode::Bulk) {
  std::unique_ptr<ProxyBvh> proxies;  // outlives the traversal
  std::unique_ptr<RayTraversal<Path>> traversal;
  DistributedTraversal<Path>* distributed = nullptr;
  if (comm.size() == 1) {
    traversal = std::make_unique<LocalTraversal<Path>>(geometry);
  } else {
    proxies = std::make_unique<ProxyBvh>(partition.proxies, comm.rank(), partition.proxyShapes,
                                         partition.proxyPlacements);
    auto d = std::make_unique<DistributedTraversal<Path>>(comm, geometry, partition, *proxies, mode,
                                                          exchange, settings.chunkPixels);
    distributed = d.get();
    traversal = std::move(d);
  }
  WavefrontRenderer<Path> renderer(scene, geometry, lights, *traversal, settings);
  FrameBuffer frameBuffer(settings.width, settings.height);
  FrameStats stats = renderer.renderFrame(0, frameBuffer);
  uint64_t compositeBytes = 0;
  RenderResult result;
  result.image =
      compositeLinear(comm, frameBuffer, 1.0f / float(settings.samplesPerPixel), compositeBytes);
  const std::vector<uint64_t> mine = {stats.cameraPaths,
                                      stats.exchangeTotal().raysForwarded,
                                      distributed ? distributed->received() : 0,
                                      distributed ? distributed->revisits() : 0,
                                      stats.retraceMisses,
                                      stats.proxyQueries,
                                      stats.exchangeTotal().forwardedToShade,
                                      stats.exchangeTotal().visitsWithoutHit};
  const std::vector<uint64_t> all = comm.sum(std::span<const uint64_t>(mine));
  result.cameraPaths = all[0];
  result.forwarded = all[1];
  result.received = all[2];
  result.revisits = all[3];
  result.retraceMisses = all[4];
  result.proxyQueries = all[5];
  result.forwardedToShade = all[6];
  result.visitsWithoutHit = all[7];
  return result;
}

// The rule of tests/tools/compare_pfm.py: per channel |a - b| <= rel *
// max(|a|, |b|) + abs; returns the pixels that break it.
int pixelsBeyondTolerance(const std::vector<Vec3f>& reference, const std::vector<Vec3f>& image,
                          double relative = 1e-4, double absolute = 1e-6) {
  int bad = 0;
  for (size_t i = 0; i < reference.size(); ++i) {
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      double a = reference[i][k], b = image[i][k];
      double d = std::abs(a - b);
      if (!(d <= relative * std::max(std::abs(a), std::abs(b)) + absolute)) ok = false;
    }
    bad += !ok;
  }
  return bad;
}

struct Variant {
  ForwardingMode mode;
  bool replay;  // PathReplay, else Path8 (both 36 bytes)
  ExchangeMode exchange = ExchangeMode::Bulk;
  uint32_t chunk = 8192;  // overlapped: camera paths taken at once
  std::string name() const {
    return toString(mode) + (replay ? "/replay/" : "/mask8/") + toString(exchange) +
           (exchange == ExchangeMode::Overlapped ? fmt::format("/chunk{}", chunk) : "");
  }
};

// Overlapped at chunk sizes from a few dozen paths (many chunks and messages
// in flight, rays of many bounces at once) to the whole image.
const std::vector<Variant>& variants() {
  static const std::vector<Variant> all = {
      {ForwardingMode::Proxies, false},
      {ForwardingMode::Proxies, true},
      {ForwardingMode::Ring, false},
      {ForwardingMode::Ring, true},
      {ForwardingMode::Broadcast, false},
      {ForwardingMode::Broadcast, true},
      {ForwardingMode::Proxies, false, ExchangeMode::Overlapped, 8192},
      {ForwardingMode::Proxies, false, ExchangeMode::Overlapped, 37},
      {ForwardingMode::Proxies, true, ExchangeMode::Overlapped, 200},
      {ForwardingMode::Ring, false, ExchangeMode::Overlapped, 64},
      {ForwardingMode::Ring, true, ExchangeMode::Overlapped, 1000}};
  return all;
}

struct Case {
  SceneCase scene;
  std::string partitioner;
};

std::string caseName(const ::testing::TestParamInfo<Case>& info) {
  std::string p = info.param.partitioner;
  for (char& c : p)
    if (c == '-') c = '_';
  return info.param.scene.name + "_" + p;
}

// Every variant rendered on `ranks` thread ranks, each set up once (its copy
// of the scene, released to what it owns, and its geometry); rank 0's results.
std::vector<RenderResult> renderVariants(const Scene& loaded, const LightSampler& lights, int ranks,
                                         const std::string& partitioner,
                                         const RenderSettings& settings) {
  const PartitionedScene shared = partitioned(loaded, ranks, partitioner, settings.seed);
  std::vector<RenderResult> results(variants().size());
  runRanks(ranks, [&](const Communicator& comm) {
    Scene mine = shared.scene;  // releaseAllBut changes it: every rank its own copy
    const std::vector<int32_t> owned = shared.partition.instancesOf(comm.rank());
    mine.releaseAllBut(owned);
    auto geometry = buildGeometry(mine, owned);
    for (size_t v = 0; v < variants().size(); ++v) {
      const Variant& variant = variants()[v];
      RenderSettings s = settings;
      s.chunkPixels = variant.chunk;
      RenderResult r =
          variant.replay ? renderFrame<PathReplay>(comm, mine, *geometry, lights, shared.partition,
                                                   variant.mode, s, variant.exchange)
                         : renderFrame<Path8>(comm, mine, *geometry, lights, shared.partition,
                                              variant.mode, s, variant.exchange);
      if (comm.isRoot()) results[v] = std::move(r);
    }
  });
  return results;
}

class DistributedInProcess : public ::testing::TestWithParam<Case> {};

// One scene load and one reference per test (they take most of its time),
// then 2, 3 and 4 ranks in every variant.
TEST_P(DistributedInProcess, EqualsTheOneRankImage) {
  const Case& c = GetParam();
  // One thread per rank, as the shell tests' --threads 1.
  tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
  const RenderSettings settings = settingsFor(c.scene);
  const Scene loaded = loadScene(c.scene.spec);
  const LightSampler lights(loaded);

  // The scene as loaded, all on one rank (round-robin rewrites nothing).
  RenderResult reference;
  {
    PartitionedScene one = partitioned(loaded, 1, "round-robin", settings.seed);
    runRanks(1, [&](const Communicator& comm) {
      std::vector<int32_t> all = one.partition.instancesOf(0);
      auto geometry = buildGeometry(one.scene, all);
      reference = renderFrame<Path8>(comm, one.scene, *geometry, lights, one.partition,
                                     ForwardingMode::Proxies, settings);
    });
  }
  double meanLuminance = 0;
  for (const Vec3f& v : reference.image) meanLuminance += v.x + v.y + v.z;
  ASSERT_GT(meanLuminance, 0) << "the reference image is black";

  const int pixels = settings.width * settings.height;
  const int allowedOutliers = int(0.002 * pixels);
  for (int ranks : {2, 3, 4}) {
    const std::vector<RenderResult> results =
        renderVariants(loaded, lights, ranks, c.partitioner, settings);
    for (size_t v = 0; v < variants().size(); ++v) {
      const Variant& variant = variants()[v];
      const RenderResult& r = results[v];
      SCOPED_TRACE(fmt::format("{} ranks, {}", ranks, variant.name()));
      ASSERT_EQ(r.image.size(), reference.image.size());
      // Exact: fixed-point sums do not depend on which rank adds what.
      EXPECT_LE(pixelsBeyondTolerance(reference.image, r.image, 0, 0), allowedOutliers);
      EXPECT_EQ(r.cameraPaths, reference.cameraPaths);
      EXPECT_GT(r.forwarded, 0u) << "no ray left its rank: nothing distributed was tested";
      EXPECT_EQ(r.revisits, 0u);
      EXPECT_EQ(r.received, r.forwarded);
      EXPECT_EQ(r.retraceMisses, 0u);
      // Counted where rays arrive to be traversed, so no more than were sent so.
      EXPECT_LE(r.visitsWithoutHit, r.forwarded - r.forwardedToShade);
      // Every rank gets a copy of every ray: most find nothing there.
      if (variant.mode == ForwardingMode::Broadcast) {
        EXPECT_GT(r.visitsWithoutHit, 0u);
      }
      if (variant.mode == ForwardingMode::Proxies) {
        // Every camera path's owner is decided by one proxy query (on the
        // rank its pixel is dealt to); forwarding decisions add more.
        EXPECT_GE(r.proxyQueries, r.cameraPaths);
      }
    }
  }
}

const SceneCase kCornell{"cornell", "builtin:cornell", 40, 40, 2, 4};
const SceneCase kIsland{"island", "builtin:island?scale=0.05", 48, 27, 1, 3};
// Light paths: rays that start at the emitter (on any rank) and shadow rays
// to the camera that add to any pixel.
const SceneCase kCornellLightPaths{"cornell_light_paths", "builtin:cornell", 40, 40, 2, 4, true};
// A thin lens, and each camera sample's total clamped (its contributions are
// made on several ranks; the totals are summed before the clamp), with light
// paths (their splats clamped one by one).
const SceneCase kCornellClampedThroughALens{
    "cornell_clamped_lens", "builtin:cornell", 40, 40, 2, 4, true, 0.3f, 20.0f, 1000.0f};

// pbrt-v4's stochastic cut-outs (a hole with probability 1 - alpha, by a
// hash of the ray and the hit) on a sheet and on instanced leaves cut by a
// solid texture: every rank that traces a ray decides alike, whatever the
// partitioner cut the meshes into.
const SceneCase kStochasticCutouts{
    "cutouts_v4",
    std::string(FERRY_SOURCE_DIR) + "/tests/corpus/pbrt/cutouts_v4.pbrt",
    40,
    40,
    2,
    4};

std::vector<Case> allCases() {
  std::vector<Case> cases;
  for (const SceneCase& scene : {kCornell, kIsland})
    for (const char* partitioner : {"round-robin", "best"}) cases.push_back({scene, partitioner});
  cases.push_back({kCornellLightPaths, "best"});
  cases.push_back({kCornellClampedThroughALens, "best"});
  for (const char* partitioner : {"round-robin", "best"})
    cases.push_back({kStochasticCutouts, partitioner});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Renders, DistributedInProcess, ::testing::ValuesIn(allCases()), caseName);

// ------------------------------------------------------------------- failures

// Passes everything through to a rank's real communicator, except that one
// rank's exchange throws at its n-th call (exchangeBytes in the bulk
// exchange, a message sent in the overlapped one): a failure mid-render, in
// the exchange stage.
class FailingExchange final : public Communicator {
 public:
  FailingExchange(const Communicator& inner, int failingRank, int failAtCall)
      : inner_(inner), failingRank_(failingRank), failAtCall_(failAtCall) {}
  int calls() const { return calls_; }

  int rank() const override { return inner_.rank(); }
  int size() const override { return inner_.size(); }
  const char* transport() const override { return inner_.transport(); }
  void barrier() const override { inner_.barrier(); }
  uint64_t sum(uint64_t value) const override { return inner_.sum(value); }
  double max(double value) const override { return inner_.max(value); }
  std::vector<uint64_t> sum(std::span<const uint64_t> values) const override {
    return inner_.sum(values);
  }
  std::vector<double> sum(std::span<const double> values) const override {
    return inner_.sum(values);
  }
  std::vector<double> max(std::span<const double> values) const override {
    return inner_.max(values);
  }
  std::vector<int> exchangeCounts(const std::vector<int>& sendCounts) const override {
    return inner_.exchangeCounts(sendCounts);
  }
  void exchangeBytes(const void* send, const std::vector<int>& sendCounts,
                     const std::vector<int>& sendOffsets, void* receive,
                     const std::vector<int>& receiveCounts,
                     const std::vector<int>& receiveOffsets) const override {
    if (rank() == failingRank_ && ++calls_ == failAtCall_)
      throw std::runtime_error("injected failure at exchange");
    inner_.exchangeBytes(send, sendCounts, sendOffsets, receive, receiveCounts, receiveOffsets);
  }
  void gatherBytes(const void* send, int sendBytes, void* receive, const std::vector<int>& counts,
                   const std::vector<int>& offsets) const override {
    inner_.gatherBytes(send, sendBytes, receive, counts, offsets);
  }
  std::vector<int> gatherInt(int value) const override { return inner_.gatherInt(value); }
  void broadcastBytes(std::span<std::byte> bytes) const override { inner_.broadcastBytes(bytes); }
  std::unique_ptr<Communicator> split(int color) const override { return inner_.split(color); }
  SendHandle sendBytes(int to, std::vector<std::byte> bytes) const override {
    if (rank() == failingRank_ && ++calls_ == failAtCall_)
      throw std::runtime_error("injected failure at exchange");
    return inner_.sendBytes(to, std::move(bytes));
  }
  std::optional<ReceivedBytes> receiveBytes() const override { return inner_.receiveBytes(); }
  bool sendDone(SendHandle handle) const override { return inner_.sendDone(handle); }
  bool allSendsDone() const override { return inner_.allSendsDone(); }
  void waitForMessage(std::chrono::microseconds timeout) const override {
    inner_.waitForMessage(timeout);
  }
  SumHandle startSum(std::vector<uint64_t> values) const override {
    return inner_.startSum(std::move(values));
  }
  bool sumDone(SumHandle handle, std::vector<uint64_t>& result) const override {
    return inner_.sumDone(handle, result);
  }

 private:
  void abortEveryRank(const std::string& message, int code) const override {
    inner_.abortAll(message, code);
  }

  const Communicator& inner_;
  int failingRank_, failAtCall_;
  mutable int calls_ = 0;
};

// A pinhole view's camera-path owners are decided once: the first sample
// pixel by pixel, the second five rays a pixel, then only pixels whose five
// owners differ, sample by sample. A renderer for another view on the same traversal decides anew,
// and both views' images are the one-rank images; a frame rendered in
// slices keeps each slice's owners.
TEST(DistributedInProcessOwnership, DecidedOncePerViewAndAnewForANewView) {
  tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
  const Scene loaded = loadScene("builtin:cornell");
  const LightSampler lights(loaded);
  RenderSettings first = settingsFor(kCornell);
  RenderSettings moved = first;
  moved.camera = loaded.view("");
  moved.camera->from = moved.camera->from + Vec3f(0.3f, -0.2f, 0.1f);
  const uint32_t pixels = uint32_t(first.width * first.height);
  const uint32_t spp = uint32_t(first.samplesPerPixel);

  // The one-rank images of both views.
  std::vector<std::vector<Vec3f>> reference;
  for (const RenderSettings& s : {first, moved}) {
    PartitionedScene one = partitioned(loaded, 1, "round-robin", s.seed);
    runRanks(1, [&](const Communicator& comm) {
      auto geometry = buildGeometry(one.scene, one.partition.instancesOf(0));
      reference.push_back(renderFrame<Path8>(comm, one.scene, *geometry, lights, one.partition,
                                             ForwardingMode::Proxies, s)
                              .image);
    });
  }

  const PartitionedScene shared = partitioned(loaded, 2, "best", first.seed);
  std::vector<std::vector<Vec3f>> bulkImages;  // per view: the bulk exchange's (no clearance)
  for (ExchangeMode exchange : {ExchangeMode::Bulk, ExchangeMode::Overlapped}) {
    SCOPED_TRACE(toString(exchange));
    runRanks(2, [&](const Communicator& comm) {
      Scene mine = shared.scene;
      const std::vector<int32_t> owned = shared.partition.instancesOf(comm.rank());
      mine.releaseAllBut(owned);
      auto geometry = buildGeometry(mine, owned);
      ProxyBvh proxies(shared.partition.proxies, comm.rank(), shared.partition.proxyShapes,
                       shared.partition.proxyPlacements);
      DistributedTraversal<Path8> traversal(comm, *geometry, shared.partition, proxies,
                                            ForwardingMode::Proxies, exchange);
      for (size_t v = 0; v < 2; ++v) {
        const RenderSettings& s = v == 0 ? first : moved;
        WavefrontRenderer<Path8> renderer(mine, *geometry, lights, traversal, s);
        std::vector<uint64_t> queries, skipped;  // per frame, summed over ranks
        FrameBuffer firstFrame(s.width, s.height), later(s.width, s.height);
        for (int frame = 0; frame < 3; ++frame) {
          const FrameStats stats = renderer.renderFrame(frame, frame == 0 ? firstFrame : later);
          queries.push_back(comm.sum(stats.primaryQueries));
          skipped.push_back(comm.sum(stats.skippedQueries));
        }
        uint64_t bytes = 0;
        const std::vector<Vec3f> image =
            compositeLinear(comm, firstFrame, 1.0f / float(spp), bytes);
        if (!comm.isRoot()) continue;
        SCOPED_TRACE(v == 0 ? "first view" : "moved view");
        // Sample 0 is decided pixel by pixel, sample 1 decides the view (five
        // rays a pixel) and its varying pixels, every later sample those only.
        ASSERT_EQ(queries[1] % spp, 0u);
        const uint64_t varying = queries[1] / spp;
        EXPECT_EQ(queries[0], pixels + 5 * pixels + (spp - 1) * varying);
        EXPECT_EQ(queries[2], queries[1]);
        EXPECT_GT(varying, 0u) << "no pixel has two owners: the test shows nothing";
        EXPECT_LT(varying, pixels / 4);
        EXPECT_LE(pixelsBeyondTolerance(reference[v], image, 0, 0), int(0.002 * pixels));
        // The overlapped exchange decides camera rays that hit nearer than
        // their pixel's clearance without a query, from the view's second
        // sample on; the same decisions, so the same image as the bulk one's.
        if (exchange == ExchangeMode::Bulk) {
          EXPECT_EQ(skipped[2], 0u);
          bulkImages.push_back(image);
        } else {
          EXPECT_GT(skipped[2], pixels / 4) << "the clearance decided too few camera rays";
          ASSERT_EQ(bulkImages.size(), 2u);
          EXPECT_EQ(pixelsBeyondTolerance(bulkImages[v], image, 0, 0), 0);
        }
      }
      // The viewer renders frames in slices: each slice's owners are kept.
      WavefrontRenderer<Path8> renderer(mine, *geometry, lights, traversal, moved);
      FrameBuffer frameBuffer(moved.width, moved.height);
      std::vector<uint64_t> queries;
      for (int frame = 0; frame < 2; ++frame) {
        uint64_t q = 0;
        for (uint32_t slice = 0; slice < 3; ++slice)
          q += renderer
                   .renderPixels(frame, pixels * slice / 3, pixels * (slice + 1) / 3, frameBuffer)
                   .primaryQueries;
        queries.push_back(comm.sum(q));
      }
      if (comm.isRoot()) {
        EXPECT_EQ(queries[0], pixels + 5 * pixels + (spp - 1) * queries[1] / spp) << "in slices";
      }
    });
  }
}

// Rank 1 fails in the exchange stage in the middle of a render and calls
// abortAll, as the `ferry` command does with a render-time error; every rank
// ends, soon, with rank 1's message.
TEST(DistributedInProcessFailure, ExchangeFailureOnOneRankEndsEveryRank) {
  tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
  const SceneCase scene = kCornell;
  const RenderSettings settings = settingsFor(scene);
  const Scene loaded = loadScene(scene.spec);
  const LightSampler lights(loaded);
  const int ranks = 3;
  const PartitionedScene shared = partitioned(loaded, ranks, "round-robin", settings.seed);
  struct FailureCase {
    ForwardingMode mode;
    ExchangeMode exchange;
  };
  for (FailureCase fc : {FailureCase{ForwardingMode::Proxies, ExchangeMode::Bulk},
                         FailureCase{ForwardingMode::Broadcast, ExchangeMode::Bulk},
                         FailureCase{ForwardingMode::Proxies, ExchangeMode::Overlapped}}) {
    const ForwardingMode mode = fc.mode;
    SCOPED_TRACE(toString(mode) + "/" + toString(fc.exchange));
    using Clock = std::chrono::steady_clock;
    std::mutex mutex;
    std::vector<std::string> messages(ranks);
    std::vector<Clock::time_point> ended(ranks);
    Clock::time_point failed;
    std::atomic<int> failingCalls{0};
    try {
      runRanks(ranks, [&](const Communicator& comm) {
        FailingExchange failing(comm, 1, 3);
        try {
          Scene mine = shared.scene;
          const std::vector<int32_t> owned = shared.partition.instancesOf(comm.rank());
          mine.releaseAllBut(owned);
          auto geometry = buildGeometry(mine, owned);
          RenderSettings s = settings;
          s.chunkPixels = 64;  // overlapped: many messages, the failure mid-sample
          renderFrame<Path8>(failing, mine, *geometry, lights, shared.partition, mode, s,
                             fc.exchange);
        } catch (const std::exception& e) {
          if (comm.rank() == 1) {
            failingCalls = failing.calls();
            failed = Clock::now();
          }
          try {
            failing.abortAll(e.what());
          } catch (const std::exception& aborted) {
            std::lock_guard lock(mutex);
            messages[comm.rank()] = aborted.what();
            ended[comm.rank()] = Clock::now();
            throw;
          }
        }
      });
      FAIL() << "the render finished despite the failure";
    } catch (const GroupAborted& e) {
      EXPECT_EQ(e.abortingRank(), 1);
      EXPECT_EQ(e.reason(), "injected failure at exchange");
    }
    EXPECT_EQ(failingCalls.load(), 3) << "the failure came before the third exchange";
    for (int r = 0; r < ranks; ++r) {
      EXPECT_NE(messages[r].find("rank 1 aborted: injected failure at exchange"), std::string::npos)
          << "rank " << r << ": " << messages[r];
      EXPECT_LT(std::chrono::duration<double>(ended[r] - failed).count(), 1.0) << "rank " << r;
    }
  }
}

}  // namespace
}  // namespace ferry
