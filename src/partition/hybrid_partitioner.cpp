#include "partition/hybrid_partitioner.h"

#include <algorithm>
#include <bit>
#include <numeric>

namespace ferry {
namespace {

// What a part holds, as a sorted resource list, to price a unit's copy.
struct PartContent {
  std::vector<uint32_t> resources;
  uint64_t marginal(const UnitSet& set, uint32_t unit) const {
    const Unit& u = set.units[unit];
    uint64_t bytes = u.ownBytes;
    for (uint32_t k = 0; k < u.resourceCount; ++k) {
      uint32_t r = set.resources[u.firstResource + k];
      if (!std::binary_search(resources.begin(), resources.end(), r)) bytes += set.resourceBytes[r];
    }
    return bytes;
  }
  void add(const UnitSet& set, uint32_t unit) {
    const Unit& u = set.units[unit];
    std::vector<uint32_t> merged;
    merged.reserve(resources.size() + u.resourceCount);
    std::set_union(resources.begin(), resources.end(), set.resources.begin() + u.firstResource,
                   set.resources.begin() + u.firstResource + u.resourceCount,
                   std::back_inserter(merged));
    resources = std::move(merged);
  }
};

}  // namespace

ReplicationResult replicateLargeUnits(const UnitSet& units, std::vector<Part>& parts,
                                      const std::vector<RankSet>& partRanks,
                                      std::vector<RankSet>& owners, uint64_t budget,
                                      uint64_t maxPartBytes) {
  ReplicationResult result;
  if (parts.size() < 2) return result;
  Box3f world;
  for (const Unit& u : units.units) world.extend(u.bounds);
  const double minimumArea = world.surfaceArea() * kLargeAreaFraction;

  std::vector<uint32_t> candidates;
  std::vector<double> areaPerByte(units.units.size(), 0);
  for (uint32_t u = 0; u < units.units.size(); ++u) {
    const Box3f& b = units.units[u].bounds;
    if (b.empty() || b.surfaceArea() < minimumArea) continue;
    areaPerByte[u] = b.surfaceArea() / double(std::max<uint64_t>(1, aloneBytes(units, u)));
    candidates.push_back(u);
  }
  if (candidates.empty()) return result;
  std::stable_sort(candidates.begin(), candidates.end(),
                   [&](uint32_t a, uint32_t b) { return areaPerByte[a] > areaPerByte[b]; });

  std::vector<PartContent> content(parts.size());
  for (size_t k = 0; k < parts.size(); ++k) {
    std::vector<uint32_t>& r = content[k].resources;
    for (uint32_t u : parts[k].units) {
      const Unit& unit = units.units[u];
      r.insert(r.end(), units.resources.begin() + unit.firstResource,
               units.resources.begin() + unit.firstResource + unit.resourceCount);
    }
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }

  uint64_t left = budget;
  for (uint32_t u : candidates) {
    uint64_t cost = 0;
    bool fits = true;
    std::vector<size_t> missing;
    for (size_t k = 0; k < parts.size(); ++k) {
      if (std::binary_search(parts[k].units.begin(), parts[k].units.end(), u)) continue;
      missing.push_back(k);
      const uint64_t added = content[k].marginal(units, u);
      cost += added * uint64_t(partRanks[k].count());
      fits &= maxPartBytes == 0 || parts[k].bytes + added <= maxPartBytes;
    }
    if (missing.empty() || cost > left || !fits) continue;
    left -= cost;
    result.addedBytes += cost;
    ++result.replicatedUnits;
    for (size_t k : missing) {
      parts[k].bytes += content[k].marginal(units, u);
      content[k].add(units, u);
      parts[k].units.insert(std::upper_bound(parts[k].units.begin(), parts[k].units.end(), u), u);
      owners[u] |= partRanks[k];
    }
  }
  return result;
}

}  // namespace ferry
