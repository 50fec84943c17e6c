// Proxies merged down to a budget. Every rank holds every proxy, so their
// number is memory and set-up time on every rank. The union box of proxies
// with the same owners still satisfies the partition invariant; what merging
// costs is rays sent to the owners through the gaps of the union. So
// proxies are grouped by owner set, each group starts as one union box, and
// the box of largest surface area is split in two (a binned sweep over its
// members' centres, least summed area) until the budget is reached or every
// box holds one proxy. Deterministic: every rank merging the same proxies
// gets the same boxes. docs/partitioning.md, "Proxies under a budget".
#pragma once

#include <cstdint>
#include <vector>

#include "partition/partition.h"
#include "partition/proxies.h"

namespace ferry {

// The default of `--max-proxies`: about 24 MB on every rank (the proxy tree
// holds each world box and its owners in its node's slot, ~90 B each with
// the nodes). Above the built-ins at scale 1 with every partitioner, so
// their partitions are as without a budget.
constexpr uint64_t kDefaultMaxProxies = uint64_t(1) << 18;

// `proxies` unchanged if there are at most `maxProxies` (or maxProxies is 0),
// else at most max(maxProxies, number of distinct owner sets) union boxes,
// ordered by owner set and then as the top-down splits leave them.
std::vector<Proxy> mergeProxies(std::vector<Proxy> proxies, uint64_t maxProxies);

// The same for proxies given as unit boxes (unitProxyBoxes) owned by their
// unit's owners: the same result as making the Proxy list first, without it
// (braided instances are several times the budget before merging: 28 bytes
// each here, 56 as a Proxy).
std::vector<Proxy> mergeProxies(const std::vector<UnitBox>& boxes,
                                const std::vector<RankSet>& unitOwners, uint64_t maxProxies);

}  // namespace ferry
