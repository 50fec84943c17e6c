#include "partition/proxy_merge.h"

#include <algorithm>
#include <numeric>
#include <queue>

namespace ferry {
namespace {

// Owner sets in a total order (word by word), for grouping.
bool ownersBefore(const RankSet& a, const RankSet& b) {
  const size_t words = std::max(a.wordCount(), b.wordCount());
  for (size_t k = words; k-- > 0;)
    if (a.word(k) != b.word(k)) return a.word(k) < b.word(k);
  return false;
}

struct Cluster {
  uint32_t first = 0, last = 0;  // a range of `order`
  Box3f box;
};

constexpr int kBins = 16;

// Splits order[first, last) in two non-empty halves; returns the first index
// of the second. Binned over the centres on each axis, the planes leaving
// the least summed surface area; the middle of the range if every centre is
// the same point.
template <class Input>
uint32_t splitCluster(const Input& proxies, std::vector<uint32_t>& order, uint32_t first,
                      uint32_t last) {
  Box3f centres;
  for (uint32_t i = first; i < last; ++i) centres.extend(proxies.bounds(order[i]).center());
  const Vec3f extent = centres.size();
  int bestAxis = -1, bestBin = 0;
  float bestCost = kInfinity;
  auto binOf = [&](int axis, uint32_t id) {
    const float f = (proxies.bounds(id).center()[axis] - centres.lower[axis]) / extent[axis];
    return std::clamp(int(f * kBins), 0, kBins - 1);
  };
  for (int axis = 0; axis < 3; ++axis) {
    if (!(extent[axis] > 0)) continue;
    Box3f bins[kBins];
    uint32_t counts[kBins] = {};
    for (uint32_t i = first; i < last; ++i) {
      const int b = binOf(axis, order[i]);
      bins[b].extend(proxies.bounds(order[i]));
      ++counts[b];
    }
    float rightArea[kBins];
    uint32_t rightCount[kBins];
    Box3f right;
    uint32_t n = 0;
    for (int b = kBins - 1; b >= 0; --b) {
      right.extend(bins[b]);
      n += counts[b];
      rightArea[b] = right.empty() ? 0 : right.surfaceArea();
      rightCount[b] = n;
    }
    Box3f left;
    uint32_t leftCount = 0;
    for (int b = 1; b < kBins; ++b) {  // bins below b go left
      left.extend(bins[b - 1]);
      leftCount += counts[b - 1];
      if (leftCount == 0 || rightCount[b] == 0) continue;
      const float cost = left.surfaceArea() + rightArea[b];
      if (cost < bestCost) {
        bestCost = cost;
        bestAxis = axis;
        bestBin = b;
      }
    }
  }
  if (bestAxis < 0) return first + (last - first) / 2;
  auto mid = std::stable_partition(order.begin() + first, order.begin() + last,
                                   [&](uint32_t id) { return binOf(bestAxis, id) < bestBin; });
  return uint32_t(mid - order.begin());
}

template <class Input>
Box3f unionOf(const Input& proxies, const std::vector<uint32_t>& order, uint32_t first,
              uint32_t last) {
  Box3f b;
  for (uint32_t i = first; i < last; ++i) b.extend(proxies.bounds(order[i]));
  return b;
}

// The merge, over proxies given as `proxies.size()`, `.bounds(i)` and
// `.owners(i)`.
template <class Input>
std::vector<Proxy> merge(const Input& proxies, uint64_t maxProxies) {
  std::vector<uint32_t> order(proxies.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return ownersBefore(proxies.owners(a), proxies.owners(b));
  });

  // One cluster per owner set to start with.
  std::vector<Cluster> clusters;
  clusters.reserve(size_t(std::min<uint64_t>(maxProxies, proxies.size())) + 1);
  for (uint32_t first = 0; first < order.size();) {
    uint32_t last = first + 1;
    while (last < order.size() && proxies.owners(order[last]) == proxies.owners(order[first]))
      ++last;
    clusters.push_back({first, last, unionOf(proxies, order, first, last)});
    first = last;
  }
  // The splittable clusters, largest area first (ties: the earlier range).
  auto larger = [&](uint32_t a, uint32_t b) {
    const float aa = clusters[a].box.surfaceArea(), ab = clusters[b].box.surfaceArea();
    if (aa != ab) return aa < ab;
    return clusters[a].first > clusters[b].first;
  };
  std::priority_queue<uint32_t, std::vector<uint32_t>, decltype(larger)> queue(larger);
  auto offer = [&](uint32_t c) {
    if (clusters[c].last - clusters[c].first > 1) queue.push(c);
  };
  for (uint32_t c = 0; c < clusters.size(); ++c) offer(c);
  while (clusters.size() < maxProxies && !queue.empty()) {
    const uint32_t c = queue.top();
    queue.pop();
    const uint32_t first = clusters[c].first, last = clusters[c].last;
    const uint32_t mid = splitCluster(proxies, order, first, last);
    clusters[c] = {first, mid, unionOf(proxies, order, first, mid)};
    clusters.push_back({mid, last, unionOf(proxies, order, mid, last)});
    offer(c);
    offer(uint32_t(clusters.size() - 1));
  }

  std::sort(clusters.begin(), clusters.end(),
            [](const Cluster& a, const Cluster& b) { return a.first < b.first; });
  std::vector<Proxy> merged;
  merged.reserve(clusters.size());
  for (const Cluster& c : clusters) merged.push_back({c.box, proxies.owners(order[c.first])});
  return merged;
}

struct ProxyInput {
  const std::vector<Proxy>& proxies;
  size_t size() const { return proxies.size(); }
  const Box3f& bounds(uint32_t i) const { return proxies[i].bounds; }
  const RankSet& owners(uint32_t i) const { return proxies[i].owners; }
};

struct UnitBoxInput {
  const std::vector<UnitBox>& boxes;
  const std::vector<RankSet>& unitOwners;
  size_t size() const { return boxes.size(); }
  const Box3f& bounds(uint32_t i) const { return boxes[i].box; }
  const RankSet& owners(uint32_t i) const { return unitOwners[boxes[i].unit]; }
};

}  // namespace

std::vector<Proxy> mergeProxies(std::vector<Proxy> proxies, uint64_t maxProxies) {
  if (maxProxies == 0 || proxies.size() <= maxProxies) return proxies;
  return merge(ProxyInput{proxies}, maxProxies);
}

std::vector<Proxy> mergeProxies(const std::vector<UnitBox>& boxes,
                                const std::vector<RankSet>& unitOwners, uint64_t maxProxies) {
  if (maxProxies == 0 || boxes.size() <= maxProxies) {
    std::vector<Proxy> proxies;
    proxies.reserve(boxes.size());
    for (const UnitBox& b : boxes) proxies.push_back({b.box, unitOwners[b.unit]});
    return proxies;
  }
  return merge(UnitBoxInput{boxes, unitOwners}, maxProxies);
}

}  // namespace ferry
