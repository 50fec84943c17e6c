// The overlapped exchange: DistributedTraversal::runSample, whose state and
// steps are the class OverlappedSample. See distributed_traversal.h for the
// idea and docs/data-parallel.md for the measurements.
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

#include "comm/idle_backoff.h"
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

}  // namespace

// One sample of the overlapped exchange on this rank: runSample's state (the
// rays of each bounce, the counts of rays made and ended, the camera paths
// not started yet, the termination sums) and its steps. run() takes one step
// at a time, in the order described at the top of this file, until a sum
// shows the sample over on every rank; it is collective, and returns once
// every send of this rank has completed.
template <typename Path>
class DistributedTraversal<Path>::OverlappedSample {
 public:
  OverlappedSample(DistributedTraversal& traversal, uint32_t sampleIndex, const PixelSet& set,
                   SampleShading<Path>& shading, FrameStats& stats)
      : traversal_(traversal),
        comm_(traversal.comm_),
        sampleIndex_(sampleIndex),
        set_(set),
        shading_(shading),
        stats_(stats),
        rank_(comm_.rank()),
        ranks_(comm_.size()),
        replay_(Path::kReplay && traversal.mode_ == ForwardingMode::Proxies),
        outbox_(static_cast<size_t>(ranks_)) {}

  void run() {
    findOwnCameraPaths();
    takeEarlyRays();
    for (;;) {
      receiveMessages();
      if (doNextWork())
        backoff_.reset();
      else if (checkSampleOver())
        break;
    }
    waitForSends();
  }

 private:
  // Which camera paths are this rank's (proxy-guided, one collective).
  void findOwnCameraPaths() {
    auto start = Clock::now();
    const double elsewhere = stats_.times.wait + stats_.times.exchange;
    traversal_.primaryPixels(set_, shading_.cameraRays(), mine_, stats_);
    // (The owners' collectives count as wait and exchange, not as generate.)
    stats_.times.generate +=
        secondsSince(start) - (stats_.times.wait + stats_.times.exchange - elsewhere);
  }

  // What arrived for this sample while this rank was still in the previous one.
  void takeEarlyRays() {
    std::erase_if(traversal_.early_, [&](const EarlyRays& e) {
      if (e.sample != sampleIndex_) return false;
      addArrivals(e.bounce, e.rays);
      return true;
    });
  }

  // Takes every message that has arrived: rays of this sample into their
  // bounce's queues, rays of a later sample kept for that sample.
  void receiveMessages() {
    auto start = Clock::now();
    while (auto message = comm_.receive<RayMessageHeader, Path>()) {
      traversal_.received_ += message->items.size();
      const RayMessageHeader header = message->header;
      if (header.sample > sampleIndex_) {  // the sender is ahead: keep them for that sample
        traversal_.early_.push_back(
            {header.sample, header.bounce,
             PathQueue<Path>(message->items.begin(), message->items.end())});
        continue;
      }
      if (header.sample < sampleIndex_)
        throw CommunicationError("receive", rank_,
                                 fmt::format("rays of sample {} from rank {} during sample {}",
                                             header.sample, message->from, sampleIndex_));
      addArrivals(header.bounce, message->items);
    }
    stats_.times.exchange += secondsSince(start);
  }

  // Rays sent here: to trace ("arrived"), or, already traversed, to shade ("ready").
  void addArrivals(uint32_t bounce, std::span<const Path> rays) {
    BounceRays<Path>& b = at(bounce);
    for (const Path& p : rays) {
      if (p.has(kPathTraversed))
        keepToShade(p, TraceHit{}, b.ready, b.readyHits);
      else
        b.arrived.push_back(p);
    }
  }

  // Bounce `bounce`'s rays; adds bounces (here and in the stats) up to it.
  BounceRays<Path>& at(uint32_t bounce) {
    if (bounces_.size() <= bounce) bounces_.resize(bounce + 1);
    if (stats_.perBounce.size() <= bounce) stats_.perBounce.resize(bounce + 1);
    return bounces_[bounce];
  }

  // The first work there is here, deepest bounce first: shade ready rays,
  // else trace rays, else start camera paths. False when there is none.
  // A step's whole time is in the stage times: what its parts do not time
  // themselves (moving rays between queues, growing them) counts to the
  // step's stage (shade; exchange; generate).
  bool doNextWork() {
    const auto start = Clock::now();
    const double timed = stats_.times.total();
    double StageTimes::*stage = nullptr;
    if (auto b = deepest([](const BounceRays<Path>& r) { return r.ready.size() > 0; })) {
      shadeReady(*b);
      stage = &StageTimes::shade;
    } else if (auto t = deepest([](const BounceRays<Path>& r) { return r.hasTraceWork(); })) {
      traceBatch(*t);
      stage = &StageTimes::exchange;
    } else if (nextPixel_ < mine_.size()) {
      startCameraPaths();
      stage = &StageTimes::generate;
    } else {
      return false;
    }
    stats_.times.*stage += std::max(0.0, secondsSince(start) - (stats_.times.total() - timed));
    return true;
  }

  // The deepest bounce with work of the kind asked for, if any.
  template <typename HasWork>
  std::optional<uint32_t> deepest(HasWork&& hasWork) const {
    for (size_t b = bounces_.size(); b-- > 0;)
      if (hasWork(bounces_[b])) return uint32_t(b);
    return std::nullopt;
  }

  // Shades bounce `bounce`'s ready rays; their new rays are made here.
  void shadeReady(uint32_t bounce) {
    BounceRays<Path>& b = bounces_[bounce];
    ended_ += b.ready.size();
    shading_.shade(bounce, b.ready, b.readyHits, spawned_, stats_);
    b.ready.clear();
    b.readyHits.clear();
    made_ += spawned_.size();
    if (spawned_.size() == 0) return;
    BounceRays<Path>& next = at(bounce + 1);  // (may move `b`)
    next.made.insert(next.made.end(), spawned_.paths.begin(), spawned_.paths.end());
    next.made.insert(next.made.end(), spawned_.shadowRays.begin(), spawned_.shadowRays.end());
  }

  // Traces up to a chunk of bounce `bounce`'s rays (made here first), keeps
  // what ends here, sends the rest.
  void traceBatch(uint32_t bounce) {
    BounceRays<Path>& b = bounces_[bounce];
    const bool madeHere = takeBatch(b);
    if (replay_) {
      if (madeHere)
        visited_.assign(batch_.size(), RankSet::single(rank_));
      else  // with the tmax each ray arrived with
        visited_ = traversal_.replayArrivals(batch_, stats_);
    }
    if (madeHere)
      traversal_.trace(batch_, stats_, &batchHits_);
    else
      traversal_.traceArrivals(batch_, batchHits_, stats_.perBounce[bounce], stats_);
    auto start = Clock::now();
    routeBatch(b, bounce == 0 && madeHere ? traversal_.sampleView_ : nullptr);
    sendOutbox(bounce);
    stats_.times.exchange += secondsSince(start);
  }

  // Moves up to a chunk of `b`'s rays to trace, from the back of its made
  // rays if any, else of its arrived ones, into batch_; true if made here.
  bool takeBatch(BounceRays<Path>& b) {
    const bool madeHere = !b.made.empty();
    PathQueue<Path>& source = madeHere ? b.made : b.arrived;
    const size_t n = std::min<size_t>(source.size(), traversal_.chunkPixels_);
    batch_.assign(source.end() - ptrdiff_t(n), source.end());
    source.resize(source.size() - n);
    return madeHere;
  }

  // Each traced ray's next step: kept to shade in `b`, dropped (an occluded
  // shadow ray: it ends here), or into the outbox of the rank it goes to.
  // `cameraClearance`: a batch of this sample's camera paths, made here.
  void routeBatch(BounceRays<Path>& b,
                  const typename DistributedTraversal<Path>::ViewOwnership* cameraClearance) {
    traversal_.decide(batch_, visited_, destination_, stats_, cameraClearance);
    for (size_t i = 0; i < batch_.size(); ++i) {
      const int d = destination_[i];
      if (d == kShadeHere)
        keepToShade(batch_[i], batchHits_[i], b.ready, b.readyHits);
      else if (d == kDrop)
        ++ended_;
      else
        outbox_[size_t(d)].push_back(batch_[i]);
    }
  }

  // Sends each non-empty outbox as one message, in rank order, and empties it.
  void sendOutbox(uint32_t bounce) {
    if (traversal_.firstExchange_) {
      maybeInjectFailure("exchange", rank_);
      traversal_.firstExchange_ = false;
    }
    ExchangeCounters& counters = stats_.perBounce[bounce];
    for (int to = 0; to < ranks_; ++to) {
      PathQueue<Path>& rays = outbox_[size_t(to)];
      if (rays.empty()) continue;
      comm_.send(to, RayMessageHeader{sampleIndex_, bounce}, std::span<const Path>(rays));
      counters.countSent(rays.data(), rays.size(), sizeof(Path));
      ++counters.messages;
      rays.clear();
    }
  }

  // Makes the next chunk of this rank's camera paths (and with light paths
  // those too), to be traced here.
  void startCameraPaths() {
    const size_t n = std::min<size_t>(mine_.size() - nextPixel_, traversal_.chunkPixels_);
    BounceRays<Path>& cameraBounce = at(0);
    const size_t before = cameraBounce.made.size();
    shading_.cameraPaths(std::span<const uint32_t>(mine_.data() + nextPixel_, n), cameraBounce.made,
                         stats_);
    nextPixel_ += n;
    made_ += cameraBounce.made.size() - before;
  }

  // Nothing here to do: contributes to a sum if none is running, else reads
  // the running one if it completed, else waits for a message. True when the
  // completed sum shows the sample over on every rank.
  bool checkSampleOver() {
    auto start = Clock::now();
    bool over = false;
    if (!wave_) {
      contributeCounts();
    } else if (comm_.sumDone(*wave_, total_)) {
      wave_.reset();
      over = total_[0] == total_[1] && total_[2] == 0;
    } else {
      comm_.waitForMessage(backoff_.next());
    }
    stats_.times.wait += secondsSince(start);
    return over;
  }

  // Starts a sum of (made, ended, whether they changed since this rank's
  // previous contribution).
  void contributeCounts() {
    const bool changed = !contributed_ || made_ != contributedMade_ || ended_ != contributedEnded_;
    wave_ = comm_.startSum({made_, ended_, changed ? 1u : 0u});
    contributedMade_ = made_;
    contributedEnded_ = ended_;
    contributed_ = true;
    if (comm_.isRoot()) ++stats_.terminationWaves;
  }

  // Every ray was received (made == ended everywhere), so every send completes.
  void waitForSends() {
    auto start = Clock::now();
    while (!comm_.allSendsDone()) comm_.waitForMessage(std::chrono::microseconds(20));
    stats_.times.wait += secondsSince(start);
  }

  DistributedTraversal& traversal_;
  const Communicator& comm_;
  const uint32_t sampleIndex_;
  const PixelSet set_;  // the sample's pixels
  SampleShading<Path>& shading_;
  FrameStats& stats_;
  const int rank_, ranks_;
  const bool replay_;  // replay layout, proxies mode

  std::vector<uint32_t> mine_;  // this rank's camera paths
  size_t nextPixel_ = 0;        // into mine_: the next one to start
  std::vector<BounceRays<Path>> bounces_;
  uint64_t made_ = 0, ended_ = 0;  // this sample's rays on this rank

  // Scratch, reused from batch to batch.
  PathQueue<Path> batch_;
  std::vector<TraceHit> batchHits_;
  std::vector<RankSet> visited_;
  std::vector<int> destination_;
  std::vector<PathQueue<Path>> outbox_;  // per rank
  RayQueues<Path> spawned_;

  // Termination: the running sum, if any, and this rank's last contribution.
  std::optional<SumHandle> wave_;
  uint64_t contributedMade_ = 0, contributedEnded_ = 0;
  bool contributed_ = false;
  std::vector<uint64_t> total_;
  IdleBackoff backoff_;
};

template <typename Path>
void DistributedTraversal<Path>::runSample(uint32_t sampleIndex, const PixelSet& set,
                                           SampleShading<Path>& shading, FrameStats& stats) {
  OverlappedSample(*this, sampleIndex, set, shading, stats).run();
}

// The class is instantiated in distributed_traversal.cpp; this is its one member here.
template void DistributedTraversal<Path8>::runSample(uint32_t, const PixelSet&,
                                                     SampleShading<Path8>&, FrameStats&);
template void DistributedTraversal<Path64>::runSample(uint32_t, const PixelSet&,
                                                      SampleShading<Path64>&, FrameStats&);
template void DistributedTraversal<PathReplay>::runSample(uint32_t, const PixelSet&,
                                                          SampleShading<PathReplay>&, FrameStats&);
template void DistributedTraversal<PathProbe>::runSample(uint32_t, const PixelSet&,
                                                         SampleShading<PathProbe>&, FrameStats&);

}  // namespace ferry
