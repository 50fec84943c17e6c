#include "partition/split_loop.h"

#include <algorithm>
#include <numeric>

#include "core/error.h"

namespace ferry {

Part PartSplitter::root() {
  Part p;
  p.units.resize(units_.units.size());
  std::iota(p.units.begin(), p.units.end(), 0u);
  p.bytes = bytesOf(p.units);
  p.domain = boundsOf(p.units);
  p.splittable = p.units.size() > 1;
  return p;
}

uint64_t PartSplitter::bytesOf(const std::vector<uint32_t>& members) {
  counter_.clear();
  for (uint32_t u : members) counter_.add(u);
  return counter_.bytes();
}

Box3f PartSplitter::boundsOf(const std::vector<uint32_t>& members) const {
  Box3f b;
  for (uint32_t u : members) b.extend(units_.units[u].bounds);
  return b;
}

std::vector<Part> runSplitLoop(PartSplitter& splitter, int parts,
                               const std::function<void(const std::vector<Part>&)>& observe) {
  FERRY_CHECK_GE(parts, 1);
  std::vector<Part> current;
  current.push_back(splitter.root());
  if (observe) observe(current);
  while (int(current.size()) < parts) {
    // The costliest part that can still be split (ties: the first).
    int chosen = -1;
    for (size_t k = 0; k < current.size(); ++k)
      if (current[k].splittable && (chosen < 0 || current[k].bytes > current[chosen].bytes))
        chosen = int(k);
    if (chosen < 0) break;
    Part left, right;
    if (!splitter.split(current[chosen], left, right)) {
      current[chosen].splittable = false;
      continue;
    }
    FERRY_CHECK(!left.units.empty() && !right.units.empty());
    left.splittable = left.units.size() > 1;
    right.splittable = right.units.size() > 1;
    current[chosen] = std::move(left);
    current.insert(current.begin() + chosen + 1, std::move(right));
    if (observe) observe(current);
  }
  return current;
}

std::vector<RankSet> assignRanks(const std::vector<Part>& parts, int ranks) {
  FERRY_CHECK(!parts.empty());
  FERRY_CHECK_LE(parts.size(), ranks);
  std::vector<RankSet> mask(parts.size());
  for (size_t k = 0; k < parts.size(); ++k) mask[k] = RankSet::single(int(k));
  std::vector<size_t> byCost(parts.size());
  std::iota(byCost.begin(), byCost.end(), size_t(0));
  std::stable_sort(byCost.begin(), byCost.end(),
                   [&](size_t a, size_t b) { return parts[a].bytes > parts[b].bytes; });
  for (int r = int(parts.size()); r < ranks; ++r)
    mask[byCost[(r - parts.size()) % parts.size()]].insert(r);
  return mask;
}

std::vector<RankSet> unitOwners(const UnitSet& units, const std::vector<Part>& parts,
                                const std::vector<RankSet>& partRanks) {
  std::vector<RankSet> owners(units.units.size());
  for (size_t k = 0; k < parts.size(); ++k)
    for (uint32_t u : parts[k].units) owners[u] |= partRanks[k];
  return owners;
}

std::vector<RankSet> instanceOwnersOf(const UnitSet& units, const std::vector<RankSet>& owners) {
  std::vector<RankSet> out(units.unitOfInstance.size());
  for (size_t i = 0; i < out.size(); ++i)
    if (units.unitOfInstance[i] >= 0) out[i] = owners[units.unitOfInstance[i]];
  return out;
}

double splitCost(const Box3f& parent, uint64_t parentBytes, const Box3f& left, uint64_t leftBytes,
                 const Box3f& right, uint64_t rightBytes) {
  const double pb = std::max<double>(1.0, double(parentBytes));
  const double lb = double(leftBytes), rb = double(rightBytes);
  const double memory = (lb + rb + std::abs(lb - rb)) / pb;
  const double pa = parent.surfaceArea();
  const double sah =
      pa > 0 ? (left.surfaceArea() * lb + right.surfaceArea() * rb) / (pa * pb) : (lb + rb) / pb;
  return 0.5 * sah + 0.5 * memory;
}

std::vector<SplitPlane> candidatePlanes(const Box3f& bounds, int perAxis) {
  std::vector<SplitPlane> planes;
  if (bounds.empty()) return planes;
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = bounds.lower[axis], hi = bounds.upper[axis];
    if (!(hi > lo)) continue;
    for (int k = 1; k <= perAxis; ++k) {
      float at = lo + (hi - lo) * (float(k) / float(perAxis + 1));
      if (at > lo && at < hi) planes.push_back({axis, at});
    }
  }
  return planes;
}

}  // namespace ferry
