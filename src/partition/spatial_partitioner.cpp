#include "partition/spatial_partitioner.h"

#include <limits>

namespace ferry {
namespace {

Box3f intersect(const Box3f& a, const Box3f& b) {
  Box3f r;
  r.lower = max(a.lower, b.lower);
  r.upper = min(a.upper, b.upper);
  return r;
}

}  // namespace

bool SpatialSplitter::divide(const Part& part, int axis, float position, Part& left, Part& right) {
  Box3f leftHalf = part.domain, rightHalf = part.domain;
  leftHalf.upper[axis] = position;
  rightHalf.lower[axis] = position;
  left = Part{};
  right = Part{};
  Box3f leftContent, rightContent;
  for (uint32_t u : part.units) {
    const Box3f& b = units_.units[u].bounds;
    if (b.empty()) {  // no geometry: needs an owner, not a place
      left.units.push_back(u);
      continue;
    }
    // Closed on the left, so every point of the box lands in a half that lists the unit.
    if (b.lower[axis] <= position) {
      left.units.push_back(u);
      leftContent.extend(b);
    }
    if (b.upper[axis] > position) {
      right.units.push_back(u);
      rightContent.extend(b);
    }
  }
  if (left.units.empty() || right.units.empty()) return false;
  // Both halves holding everything is no progress (the domain would only shrink).
  if (left.units.size() == part.units.size() && right.units.size() == part.units.size())
    return false;
  left.domain = intersect(leftHalf, leftContent);
  right.domain = intersect(rightHalf, rightContent);
  return true;
}

bool SpatialSplitter::split(const Part& part, Part& left, Part& right) {
  if (part.domain.empty()) return false;
  if (rule_ == SpatialSplitRule::Median) {
    // The longest axis whose median lies strictly inside the domain.
    int axes[3] = {0, 1, 2};
    const Vec3f size = part.domain.size();
    std::stable_sort(axes, axes + 3, [&](int a, int b) { return size[a] > size[b]; });
    for (int axis : axes) {
      const float lo = part.domain.lower[axis], hi = part.domain.upper[axis];
      const float mid = lo + (hi - lo) * 0.5f;
      if (!(mid > lo && mid < hi)) continue;
      if (!divide(part, axis, mid, left, right)) continue;
      left.bytes = bytesOf(left.units);
      right.bytes = bytesOf(right.units);
      return true;
    }
    return false;
  }
  double best = std::numeric_limits<double>::infinity();
  bool found = false;
  Part l, r;
  for (const SplitPlane& plane : candidatePlanes(part.domain)) {
    if (!divide(part, plane.axis, plane.position, l, r)) continue;
    l.bytes = bytesOf(l.units);
    r.bytes = bytesOf(r.units);
    double cost = splitCost(part.domain, part.bytes, l.domain, l.bytes, r.domain, r.bytes);
    if (cost < best) {
      best = cost;
      found = true;
      left = std::move(l);
      right = std::move(r);
    }
  }
  return found;
}

std::vector<Proxy> domainProxies(const std::vector<Part>& parts,
                                 const std::vector<RankSet>& partRanks) {
  std::vector<Proxy> proxies;
  for (size_t k = 0; k < parts.size(); ++k)
    if (!parts[k].domain.empty()) proxies.push_back({parts[k].domain, partRanks[k]});
  return proxies;
}

}  // namespace ferry
