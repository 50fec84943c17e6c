#include "partition/ray_guided_partitioner.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "partition/box_tree.h"
#include "partition/part_assignment.h"

namespace ferry {
namespace {

// Byte quantiles the candidate planes cut at: 30% .. 70% in steps of 2.5%.
constexpr int kQuantiles = 17;
constexpr double kFirstQuantile = 0.30, kQuantileStep = 0.025;

struct Candidate {
  size_t family = 0;
  SplitPlane plane;
};

// How many of the sorted values lie below `x`.
size_t countBelow(const std::vector<float>& sorted, float x) {
  return size_t(std::lower_bound(sorted.begin(), sorted.end(), x) - sorted.begin());
}

}  // namespace

RayIncidence rayIncidence(const std::vector<UnitBox>& unitBoxes, const RaySample& sample) {
  std::vector<Box3f> boxes(unitBoxes.size());
  for (size_t b = 0; b < boxes.size(); ++b) boxes[b] = unitBoxes[b].box;
  const BoxTree tree(boxes);
  RayIncidence incidence;
  std::vector<uint32_t> found;
  for (const RaySegment& ray : sample.rays) {
    found.clear();
    tree.boxesAlong(ray.origin, ray.direction, ray.tmax, found);
    for (uint32_t& f : found) f = unitBoxes[f].unit;
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    if (found.size() < 2) continue;  // a ray through one unit can never be separated
    incidence.units.insert(incidence.units.end(), found.begin(), found.end());
    incidence.offsets.push_back(incidence.units.size());
  }
  return incidence;
}

RayGuidedSplitter::RayGuidedSplitter(const UnitSet& units, const RayIncidence& incidence, int ranks,
                                     double maxPart)
    : PartSplitter(units),
      incidence_(incidence),
      fallback_(units, /*groupCandidates=*/true),
      localOf_(units.units.size(), -1) {
  const int levels = std::max(1, int(std::ceil(std::log2(std::max(2, ranks)))));
  beta_ = 0.5 * std::pow(maxPart, 1.0 / levels);
  CostCounter all(units);
  for (uint32_t u = 0; u < units.units.size(); ++u) all.add(u);
  finalLimit_ = (maxPart - kRayGuidedRefineMargin) * double(all.bytes()) / double(ranks);
}

bool RayGuidedSplitter::split(const Part& part, Part& left, Part& right) {
  const size_t n = part.units.size();
  if (n < 2) return false;
  std::vector<uint8_t> placed;
  const std::vector<std::vector<Vec3f>> families =
      unitKeyFamilies(units_, part, /*groupCandidates=*/true, placed);
  const size_t keys = 3 * families.size();  // (family, axis) pairs

  // Each sampled ray with two or more of this part's units: the extent of
  // their keys, per family and axis, sorted (a plane p separates the ray
  // exactly when low < p <= high).
  for (size_t k = 0; k < n; ++k) localOf_[part.units[k]] = int32_t(k);
  std::vector<std::vector<float>> lows(keys), highs(keys);
  std::vector<float> lo(keys), hi(keys);
  Hypergraph rays;  // the same rays, by local unit, for the refinement
  for (uint64_t r = 0; r < incidence_.rays(); ++r) {
    int inPart = 0;
    const size_t start = rays.units.size();
    std::fill(lo.begin(), lo.end(), kInfinity);
    std::fill(hi.begin(), hi.end(), -kInfinity);
    for (uint64_t e = incidence_.offsets[r]; e < incidence_.offsets[r + 1]; ++e) {
      const int32_t k = localOf_[incidence_.units[e]];
      if (k < 0 || !placed[size_t(k)]) continue;
      ++inPart;
      rays.units.push_back(uint32_t(k));
      for (size_t f = 0; f < families.size(); ++f)
        for (int a = 0; a < 3; ++a) {
          const float v = families[f][size_t(k)][a];
          lo[3 * f + size_t(a)] = std::min(lo[3 * f + size_t(a)], v);
          hi[3 * f + size_t(a)] = std::max(hi[3 * f + size_t(a)], v);
        }
    }
    if (inPart < 2) {
      rays.units.resize(start);
      continue;
    }
    rays.offsets.push_back(rays.units.size());
    for (size_t i = 0; i < keys; ++i) {
      lows[i].push_back(lo[i]);
      highs[i].push_back(hi[i]);
    }
  }
  for (size_t k = 0; k < n; ++k) localOf_[part.units[k]] = -1;
  for (size_t i = 0; i < keys; ++i) {
    std::sort(lows[i].begin(), lows[i].end());
    std::sort(highs[i].begin(), highs[i].end());
  }

  // Candidate planes: byte quantiles and equidistant planes, per family and
  // axis. The quantiles weigh each unit alone (shared resources make that an
  // upper bound; the candidates' real cost is counted exactly).
  std::vector<uint64_t> weight(n);
  uint64_t total = 0;
  for (size_t k = 0; k < n; ++k)
    total += weight[k] = placed[k] ? aloneBytes(units_, part.units[k]) : 0;
  std::vector<Candidate> candidates;
  std::vector<size_t> order;
  for (size_t f = 0; f < families.size(); ++f) {
    const std::vector<Vec3f>& key = families[f];
    Box3f keyBounds;
    for (size_t k = 0; k < n; ++k)
      if (placed[k]) keyBounds.extend(key[k]);
    for (const SplitPlane& plane : candidatePlanes(keyBounds)) candidates.push_back({f, plane});
    for (int a = 0; a < 3; ++a) {
      order.clear();
      for (size_t k = 0; k < n; ++k)
        if (placed[k]) order.push_back(k);
      std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
        return key[x][a] < key[y][a] || (key[x][a] == key[y][a] && x < y);
      });
      uint64_t below = 0;
      int q = 0;
      for (size_t i = 0; i < order.size() && q < kQuantiles; ++i) {
        // Units before i (keys below key[order[i]]) would go left.
        while (q < kQuantiles &&
               double(below) >= (kFirstQuantile + kQuantileStep * q) * double(total)) {
          if (i > 0 && key[order[i]][a] > key[order[0]][a])
            candidates.push_back({f, {a, key[order[i]][a]}});
          ++q;
        }
        below += weight[order[i]];
      }
    }
  }

  // The fewest separated rays among balanced candidates; else the most balanced.
  // A side within the final limit is small enough at any level: beta
  // assumes a side keeps beta of its parent's bytes at every level, but with
  // shared content (an object instanced all over) both sides keep the
  // shared part, so halving by beta would force splits apart (moving an
  // object's instances to one side) that the final limit does not need.
  const double limit = std::max(beta_ * double(part.bytes), finalLimit_);
  struct Best {
    bool balanced = false;
    uint64_t separated = 0;
    double larger = 0, cost = 0;
    int index = -1;
  } best;
  CostCounter leftCost(units_), rightCost(units_);
  for (size_t c = 0; c < candidates.size(); ++c) {
    const Candidate& cand = candidates[c];
    const std::vector<Vec3f>& key = families[cand.family];
    Box3f leftBox, rightBox;
    const size_t leftCount =
        planeSides(units_, part, placed, key, cand.plane, leftCost, rightCost, leftBox, rightBox);
    if (leftCount == 0 || leftCount == n) continue;
    const size_t i = 3 * cand.family + size_t(cand.plane.axis);
    const uint64_t separated =
        countBelow(lows[i], cand.plane.position) - countBelow(highs[i], cand.plane.position);
    const double larger = double(std::max(leftCost.bytes(), rightCost.bytes()));
    const double cost =
        splitCost(part.domain, part.bytes, leftBox, leftCost.bytes(), rightBox, rightCost.bytes());
    const bool balanced = larger <= limit;
    bool better = false;
    if (best.index < 0 || balanced != best.balanced)
      better = best.index < 0 || balanced;
    else if (balanced)
      better = separated < best.separated || (separated == best.separated && cost < best.cost);
    else
      better = larger < best.larger || (larger == best.larger && separated < best.separated);
    if (better) best = {balanced, separated, larger, cost, int(c)};
  }
  if (best.index < 0) return fallback_.split(part, left, right);
  const Candidate& chosen = candidates[size_t(best.index)];
  const std::vector<Vec3f>& key = families[chosen.family];
  std::vector<uint16_t> side(n);
  for (size_t k = 0; k < n; ++k)
    side[k] = placed[k] && !(key[k][chosen.plane.axis] < chosen.plane.position);
  PartAssignment sides(units_, part.units, rays, 2, std::move(side));
  // The refinement keeps the balance the plane reached (the slack below the
  // limit is left for the splits below this one).
  sides.rebalance(limit);
  sides.refine(std::min(limit, double(sides.largest())));
  left = Part{};
  right = Part{};
  for (size_t k = 0; k < n; ++k) (sides.partOf(k) ? right : left).units.push_back(part.units[k]);
  if (left.units.empty() || right.units.empty()) return fallback_.split(part, left, right);
  left.bytes = bytesOf(left.units);
  right.bytes = bytesOf(right.units);
  left.domain = boundsOf(left.units);
  right.domain = boundsOf(right.units);
  return true;
}

void refinePartsByRays(const UnitSet& units, const RayIncidence& incidence,
                       std::vector<Part>& parts, double limit) {
  if (parts.size() < 2 || parts.size() > kMaxRefinedParts) return;
  // Every unit is in exactly one part (object splits share none).
  std::vector<uint16_t> partOf(units.units.size(), 0);
  std::vector<uint8_t> seen(units.units.size(), 0);
  for (size_t p = 0; p < parts.size(); ++p)
    for (uint32_t u : parts[p].units) {
      FERRY_CHECK(!seen[u]);
      seen[u] = 1;
      partOf[u] = uint16_t(p);
    }
  std::vector<uint32_t> members(units.units.size());
  for (uint32_t u = 0; u < members.size(); ++u) members[u] = u;
  PartAssignment assignment(units, std::move(members), incidence, int(parts.size()),
                            std::move(partOf));
  assignment.rebalance(limit);
  assignment.refine(std::max(limit, double(assignment.largest())));
  for (Part& part : parts) part.units.clear();
  for (uint32_t u = 0; u < units.units.size(); ++u)
    parts[size_t(assignment.partOf(u))].units.push_back(u);
  for (Part& part : parts) {
    part.bytes = costOf(units, part.units);
    part.domain = Box3f{};
    for (uint32_t u : part.units) part.domain.extend(units.units[u].bounds);
  }
  // A part the moves emptied (its units went where they cost less) leaves
  // its rank to a copy of the costliest part (assignRanks), as the split
  // loop does when units run out: no rank holds nothing.
  std::erase_if(parts, [](const Part& part) { return part.units.empty(); });
}

uint64_t estimatedForwards(const RayIncidence& incidence, const std::vector<Part>& parts,
                           size_t unitCount) {
  std::vector<int32_t> partOf(unitCount, -1);
  for (size_t p = 0; p < parts.size(); ++p)
    for (uint32_t u : parts[p].units) partOf[u] = int32_t(p);
  uint64_t forwards = 0;
  std::vector<int32_t> touched;
  for (uint64_t r = 0; r < incidence.rays(); ++r) {
    touched.clear();
    for (uint64_t e = incidence.offsets[r]; e < incidence.offsets[r + 1]; ++e)
      if (partOf[incidence.units[e]] >= 0) touched.push_back(partOf[incidence.units[e]]);
    std::sort(touched.begin(), touched.end());
    const size_t distinct = size_t(std::unique(touched.begin(), touched.end()) - touched.begin());
    forwards += distinct > 0 ? distinct - 1 : 0;
  }
  return forwards;
}

}  // namespace ferry
