#include "partition/object_partitioner.h"

#include <algorithm>
#include <limits>

namespace ferry {

std::vector<std::vector<Vec3f>> unitKeyFamilies(const UnitSet& set, const Part& part,
                                                bool groupCandidates,
                                                std::vector<uint8_t>& placed) {
  const auto& units = set.units;
  const size_t n = part.units.size();
  placed.assign(n, 0);
  std::vector<Vec3f> own(n);
  for (size_t k = 0; k < n; ++k) {
    placed[k] = !units[part.units[k]].bounds.empty();
    if (placed[k]) own[k] = units[part.units[k]].bounds.center();
  }
  std::vector<std::vector<Vec3f>> families = {own};
  if (!groupCandidates) return families;
  std::vector<Box3f> groupBox(set.objectCount);
  bool anyShared = false;
  std::vector<uint32_t> seen(set.objectCount, 0);
  for (size_t k = 0; k < n; ++k) {
    const int32_t g = units[part.units[k]].object;
    if (g < 0 || !placed[k]) continue;
    anyShared |= seen[g]++ > 0;
    groupBox[g].extend(units[part.units[k]].bounds);
  }
  if (anyShared) {
    std::vector<Vec3f> grouped = own;
    for (size_t k = 0; k < n; ++k) {
      const int32_t g = units[part.units[k]].object;
      if (g >= 0 && placed[k]) grouped[k] = groupBox[g].center();
    }
    families.push_back(std::move(grouped));
  }
  return families;
}

size_t planeSides(const UnitSet& units, const Part& part, const std::vector<uint8_t>& placed,
                  const std::vector<Vec3f>& key, const SplitPlane& plane, CostCounter& leftCost,
                  CostCounter& rightCost, Box3f& leftBox, Box3f& rightBox) {
  leftCost.clear();
  rightCost.clear();
  size_t leftCount = 0;
  for (size_t k = 0; k < part.units.size(); ++k) {
    const uint32_t u = part.units[k];
    if (!placed[k] || key[k][plane.axis] < plane.position) {
      leftCost.add(u);
      leftBox.extend(units.units[u].bounds);
      ++leftCount;
    } else {
      rightCost.add(u);
      rightBox.extend(units.units[u].bounds);
    }
  }
  return leftCount;
}

bool CentroidSplitter::split(const Part& part, Part& left, Part& right) {
  if (part.units.size() < 2) return false;
  const size_t n = part.units.size();
  // Units without geometry always go left: they need an owner, not a place.
  std::vector<uint8_t> placed;
  const std::vector<std::vector<Vec3f>> families =
      unitKeyFamilies(units_, part, groupCandidates_, placed);
  const std::vector<Vec3f>& own = families[0];

  double best = std::numeric_limits<double>::infinity();
  int bestFamily = -1;
  SplitPlane chosen;
  CostCounter leftCost(units_), rightCost(units_);
  for (size_t f = 0; f < families.size(); ++f) {
    const std::vector<Vec3f>& key = families[f];
    Box3f keyBounds;
    for (size_t k = 0; k < n; ++k)
      if (placed[k]) keyBounds.extend(key[k]);
    for (const SplitPlane& plane : candidatePlanes(keyBounds)) {
      Box3f leftBox, rightBox;
      const size_t leftCount =
          planeSides(units_, part, placed, key, plane, leftCost, rightCost, leftBox, rightBox);
      if (leftCount == 0 || leftCount == n) continue;
      double cost = splitCost(part.domain, part.bytes, leftBox, leftCost.bytes(), rightBox,
                              rightCost.bytes());
      if (cost < best) {
        best = cost;
        chosen = plane;
        bestFamily = int(f);
      }
    }
  }

  left = Part{};
  right = Part{};
  if (bestFamily >= 0) {
    const std::vector<Vec3f>& key = families[size_t(bestFamily)];
    for (size_t k = 0; k < n; ++k)
      (!placed[k] || key[k][chosen.axis] < chosen.position ? left : right)
          .units.push_back(part.units[k]);
  } else {
    // Every centre in one place: halve by count, in the order of the centres
    // along the longest axis, then by id.
    Box3f centres;
    for (size_t k = 0; k < n; ++k)
      if (placed[k]) centres.extend(own[k]);
    const int axis = centres.empty() ? 0 : centres.longestAxis();
    std::vector<size_t> order(n);
    for (size_t k = 0; k < n; ++k) order[k] = k;
    auto keyOf = [&](size_t k) { return placed[k] ? own[k][axis] : -kInfinity; };
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return keyOf(a) < keyOf(b); });
    for (size_t i = 0; i < n; ++i) (i < n / 2 ? left : right).units.push_back(part.units[order[i]]);
    std::sort(left.units.begin(), left.units.end());
    std::sort(right.units.begin(), right.units.end());
  }
  left.bytes = bytesOf(left.units);
  right.bytes = bytesOf(right.units);
  left.domain = boundsOf(left.units);
  right.domain = boundsOf(right.units);
  return true;
}

std::vector<Proxy> unitBoxProxies(const UnitSet& units, const std::vector<RankSet>& owners) {
  std::vector<Proxy> proxies;
  for (size_t u = 0; u < units.units.size(); ++u)
    if (!units.units[u].bounds.empty()) proxies.push_back({units.units[u].bounds, owners[u]});
  return proxies;
}

}  // namespace ferry
