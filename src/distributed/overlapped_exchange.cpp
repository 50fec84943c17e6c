// The overlapped exchange (issue 13): DistributedTraversal::runSample. See
// distributed_traversal.h for the idea and docs/data-parallel.md for the
// measurements.
//
// A rank keeps, per bounce, the rays it made and must trace first (local
// first), the rays that arrived to be traced here, and the rays whose
// traversal ended here, ready to shade. Its loop takes, in this order:
// arrived messages; ready rays of the deepest bounce (shading finishes
// paths, and new rays are traced here first); rays to trace of the deepest
// bounce (up to a chunk at once; whatever leaves goes out at once, one
// message per destination); the next chunk of its own camera paths; and
// when nothing is left, the termination check. Deepest first keeps the rays
// in flight few: a chunk goes from camera to last bounce while the rays it
// sent away are traced elsewhere.
//
// Termination without a collective per round: every rank counts the rays it
// made (camera paths, continuations, shadow rays) and the rays that ended
// here (shaded, or dropped as occluded). An idle rank contributes (made,
// ended, changed) to a non-blocking sum; when a sum completes, the sample is
// over if made == ended and no rank's counts changed since its previous
// contribution. Why that is safe: a rank contributes to sum k+1 only after
// sum k completed, i.e. after every rank contributed to sum k; if no rank's
// counts changed between its two contributions, then at the moment of the
// last contribution to sum k every rank's counts were what it contributed
// to sum k+1, one consistent cut of the whole computation. A ray in flight
// or in a queue at that cut was made and not ended, so made == ended there
// means no ray was left anywhere, and none can appear.
#include <algorithm>
#include <chrono>
#include <optional>

#include <fmt/format.h>

#include "core/clock.h"
#include "core/error.h"
#include "core/fault_injection.h"
#include "distributed/distributed_traversal.h"
#include "distributed/ray_routing.h"

namespace ferry {
namespace {

// What travels in front of a message's rays.
struct RayMessageHeader {
  uint32_t sample;  // the sample index (a check: one sample at a time)
  uint32_t bounce;  // every ray of a message is of this bounce
};

// One bounce's rays on this rank.
template <typename Path>
struct BounceRays {
  PathQueue<Path> made;             // made here: traced here first
  PathQueue<Path> arrived;          // sent here to be traced
  RayQueues<Path> ready;            // traversal ended here: to shade
  std::vector<TraceHit> readyHits;  // per ready.paths entry
  bool hasTraceWork() const { return !made.empty() || !arrived.empty(); }
};

// How long an idle rank waits for a message before it looks again: short at
// first (a reply is often on its way), longer while nothing comes, so that
// ranks outnumbering cores leave them to the ranks that have work.
class IdleBackoff {
 public:
  std::chrono::microseconds next() {
    const auto wait = current_;
    current_ = std::min(current_ * 2, kLongest);
    return wait;
  }
  void reset() { current_ = kShortest; }

 private:
  static constexpr std::chrono::microseconds kShortest{10}, kLongest{500};
  std::chrono::microseconds current_ = kShortest;
};

}  // namespace

template <typename Path>
void DistributedTraversal<Path>::runSample(uint32_t sampleIndex, uint32_t first, uint32_t last,
                                           SampleShading<Path>& shading, FrameStats& stats) {
  const int rank = comm_.rank();
  const int ranks = comm_.size();
  const bool replay = Path::kReplay && mode_ == ForwardingMode::Proxies;

  // Which camera paths are this rank's (proxy-guided, one collective).
  std::vector<uint32_t> mine;
  {
    auto start = Clock::now();
    primaryPixels(
        first, last, [&](uint32_t pixel) { return shading.cameraRay(pixel); }, mine, stats);
    stats.times.generate += secondsSince(start);
  }

  std::vector<BounceRays<Path>> bounces;
  auto at = [&](uint32_t bounce) -> BounceRays<Path>& {
    if (bounces.size() <= bounce) bounces.resize(bounce + 1);
    if (stats.perBounce.size() <= bounce) stats.perBounce.resize(bounce + 1);
    return bounces[bounce];
  };
  uint64_t made = 0, ended = 0;  // this sample's rays on this rank
  size_t nextPixel = 0;          // into `mine`

  // Scratch, reused from batch to batch.
  PathQueue<Path> batch;
  std::vector<TraceHit> batchHits;
  std::vector<RankSet> visited;
  std::vector<int> destination;
  std::vector<PathQueue<Path>> outbox(static_cast<size_t>(ranks));
  RayQueues<Path> spawned;

  auto addArrivals = [&](uint32_t bounce, const auto& rays) {
    BounceRays<Path>& b = at(bounce);
    for (const Path& p : rays) {
      if (p.has(kPathTraversed))
        keepToShade(p, TraceHit{}, b.ready, b.readyHits);
      else
        b.arrived.push_back(p);
    }
  };
  auto receiveArrivals = [&] {
    auto start = Clock::now();
    while (auto message = comm_.receive<RayMessageHeader, Path>()) {
      received_ += message->items.size();
      const RayMessageHeader header = message->header;
      if (header.sample > sampleIndex) {  // the sender is ahead: keep them for that sample
        early_.push_back({header.sample, header.bounce,
                          PathQueue<Path>(message->items.begin(), message->items.end())});
        continue;
      }
      if (header.sample < sampleIndex)
        throw CommunicationError("receive", rank,
                                 fmt::format("rays of sample {} from rank {} during sample {}",
                                             header.sample, message->from, sampleIndex));
      addArrivals(header.bounce, message->items);
    }
    stats.times.exchange += secondsSince(start);
  };
  // What arrived for this sample while this rank was still in the previous one.
  std::erase_if(early_, [&](const EarlyRays& e) {
    if (e.sample != sampleIndex) return false;
    addArrivals(e.bounce, e.rays);
    return true;
  });

  // Shades bounce `bounce`'s ready rays; their new rays are made here.
  auto shadeBounce = [&](uint32_t bounce) {
    BounceRays<Path>& b = bounces[bounce];
    ended += b.ready.size();
    shading.shade(bounce, b.ready, b.readyHits, spawned, stats);
    b.ready.clear();
    b.readyHits.clear();
    made += spawned.size();
    if (spawned.size() == 0) return;
    BounceRays<Path>& next = at(bounce + 1);
    next.made.insert(next.made.end(), spawned.paths.begin(), spawned.paths.end());
    next.made.insert(next.made.end(), spawned.shadowRays.begin(), spawned.shadowRays.end());
  };

  // Traces up to a chunk of bounce `bounce`'s rays (made here first), keeps
  // what ends here, sends the rest.
  auto traceBounce = [&](uint32_t bounce) {
    BounceRays<Path>& b = bounces[bounce];
    const bool madeHere = !b.made.empty();
    PathQueue<Path>& source = madeHere ? b.made : b.arrived;
    const size_t n = std::min<size_t>(source.size(), chunkPixels_);
    batch.assign(source.end() - ptrdiff_t(n), source.end());
    source.resize(source.size() - n);
    if (replay) {
      if (madeHere)
        visited.assign(batch.size(), RankSet::single(rank));
      else
        visited = replayArrivals(batch, stats);  // with the tmax each ray arrived with
    }
    if (madeHere)
      trace(batch, stats, &batchHits);
    else
      traceArrivals(batch, batchHits, stats.perBounce[bounce], stats);
    auto start = Clock::now();
    decide(batch, visited, destination, stats);
    for (size_t i = 0; i < batch.size(); ++i) {
      const int d = destination[i];
      if (d == kShadeHere)
        keepToShade(batch[i], batchHits[i], b.ready, b.readyHits);
      else if (d == kDrop)
        ++ended;
      else
        outbox[size_t(d)].push_back(batch[i]);
    }
    if (firstExchange_) {
      maybeInjectFailure("exchange", rank);
      firstExchange_ = false;
    }
    ExchangeCounters& counters = stats.perBounce[bounce];
    for (int to = 0; to < ranks; ++to) {
      PathQueue<Path>& rays = outbox[size_t(to)];
      if (rays.empty()) continue;
      comm_.send(to, RayMessageHeader{sampleIndex, bounce}, std::span<const Path>(rays));
      counters.countSent(rays.data(), rays.size(), sizeof(Path));
      ++counters.messages;
      rays.clear();
    }
    stats.times.exchange += secondsSince(start);
  };

  // The deepest bounce with work of the kind asked for, if any.
  auto deepest = [&](auto&& hasWork) -> std::optional<uint32_t> {
    for (size_t b = bounces.size(); b-- > 0;)
      if (hasWork(bounces[b])) return uint32_t(b);
    return std::nullopt;
  };

  std::optional<SumHandle> wave;
  uint64_t contributedMade = 0, contributedEnded = 0;
  bool contributed = false;
  std::vector<uint64_t> total;
  IdleBackoff backoff;
  for (;;) {
    receiveArrivals();
    if (auto b = deepest([](const BounceRays<Path>& r) { return r.ready.size() > 0; })) {
      shadeBounce(*b);
    } else if (auto t = deepest([](const BounceRays<Path>& r) { return r.hasTraceWork(); })) {
      traceBounce(*t);
    } else if (nextPixel < mine.size()) {
      const size_t n = std::min<size_t>(mine.size() - nextPixel, chunkPixels_);
      BounceRays<Path>& first = at(0);
      const size_t before = first.made.size();
      // (Camera paths, and with light paths those too.)
      shading.cameraPaths(std::span<const uint32_t>(mine.data() + nextPixel, n), first.made, stats);
      nextPixel += n;
      made += first.made.size() - before;
    } else {
      // Nothing here to do: is the sample over everywhere?
      auto start = Clock::now();
      if (!wave) {
        const bool changed = !contributed || made != contributedMade || ended != contributedEnded;
        wave = comm_.startSum({made, ended, changed ? 1u : 0u});
        contributedMade = made;
        contributedEnded = ended;
        contributed = true;
        if (comm_.isRoot()) ++stats.terminationWaves;
      } else if (comm_.sumDone(*wave, total)) {
        wave.reset();
        if (total[0] == total[1] && total[2] == 0) {
          stats.times.wait += secondsSince(start);
          break;
        }
      } else {
        comm_.waitForMessage(backoff.next());
      }
      stats.times.wait += secondsSince(start);
      continue;
    }
    backoff.reset();
  }
  // Every ray was received (made == ended everywhere), so every send completes.
  auto start = Clock::now();
  while (!comm_.allSendsDone()) comm_.waitForMessage(std::chrono::microseconds(20));
  stats.times.wait += secondsSince(start);
}

// The class is instantiated in distributed_traversal.cpp; this is its one member here.
template void DistributedTraversal<Path8>::runSample(uint32_t, uint32_t, uint32_t,
                                                     SampleShading<Path8>&, FrameStats&);
template void DistributedTraversal<Path64>::runSample(uint32_t, uint32_t, uint32_t,
                                                      SampleShading<Path64>&, FrameStats&);
template void DistributedTraversal<PathReplay>::runSample(uint32_t, uint32_t, uint32_t,
                                                          SampleShading<PathReplay>&, FrameStats&);

}  // namespace ferry
