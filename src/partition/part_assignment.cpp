#include "partition/part_assignment.h"

#include <algorithm>

#include "core/error.h"

namespace ferry {

PartAssignment::PartAssignment(const UnitSet& set, std::vector<uint32_t> members,
                               const Hypergraph& rays, int parts, std::vector<uint16_t> part)
    : set_(set), members_(std::move(members)), rays_(rays), parts_(parts), part_(std::move(part)) {
  FERRY_CHECK_EQ(members_.size(), part_.size());
  FERRY_CHECK(parts_ >= 1 && parts_ <= 65535);
  const size_t n = members_.size(), k = size_t(parts_);
  raysOf_.assign(n + 1, 0);
  for (uint32_t i : rays_.units) ++raysOf_[i + 1];
  for (size_t i = 0; i < n; ++i) raysOf_[i + 1] += raysOf_[i];
  rayList_.resize(rays_.units.size());
  std::vector<uint64_t> fill(raysOf_.begin(), raysOf_.end() - 1);
  for (size_t r = 0; r < rays_.rays(); ++r)
    for (uint64_t e = rays_.offsets[r]; e < rays_.offsets[r + 1]; ++e)
      rayList_[fill[rays_.units[e]]++] = uint32_t(r);
  count_.assign(k * rays_.rays(), 0);
  for (size_t r = 0; r < rays_.rays(); ++r) {
    uint32_t touched = 0;
    for (uint64_t e = rays_.offsets[r]; e < rays_.offsets[r + 1]; ++e)
      touched += count_[k * r + part_[rays_.units[e]]]++ == 0;
    score_ += touched > 0 ? touched - 1 : 0;
  }
  refs_.assign(k * set_.resourceBytes.size(), 0);
  bytes_.assign(k, 0);
  for (size_t i = 0; i < n; ++i) add(i, part_[i]);
}

uint64_t PartAssignment::largest() const {
  return *std::max_element(bytes_.begin(), bytes_.end());
}

int64_t PartAssignment::scoreChange(size_t i, int to) const {
  const size_t k = size_t(parts_);
  const int from = part_[i];
  int64_t change = 0;
  for (uint64_t e = raysOf_[i]; e < raysOf_[i + 1]; ++e) {
    const uint32_t r = rayList_[e];
    change -= count_[k * r + size_t(from)] == 1;  // the ray leaves `from`
    change += count_[k * r + size_t(to)] == 0;    // and reaches `to`
  }
  return change;
}

uint64_t PartAssignment::bytesWhereUsers(size_t i, int part, uint32_t users) const {
  const Unit& u = set_.units[members_[i]];
  const size_t base = size_t(part) * set_.resourceBytes.size();
  uint64_t b = u.ownBytes;
  for (uint32_t j = 0; j < u.resourceCount; ++j) {
    const uint32_t r = set_.resources[u.firstResource + j];
    if (refs_[base + r] == users) b += set_.resourceBytes[r];
  }
  return b;
}

void PartAssignment::add(size_t i, int part) {
  bytes_[size_t(part)] += added(i, part);
  const Unit& u = set_.units[members_[i]];
  const size_t base = size_t(part) * set_.resourceBytes.size();
  for (uint32_t j = 0; j < u.resourceCount; ++j)
    ++refs_[base + set_.resources[u.firstResource + j]];
}

void PartAssignment::remove(size_t i, int part) {
  bytes_[size_t(part)] -= released(i, part);
  const Unit& u = set_.units[members_[i]];
  const size_t base = size_t(part) * set_.resourceBytes.size();
  for (uint32_t j = 0; j < u.resourceCount; ++j)
    --refs_[base + set_.resources[u.firstResource + j]];
}

void PartAssignment::move(size_t i, int to) {
  const size_t k = size_t(parts_);
  const int from = part_[i];
  if (from == to) return;
  int64_t change = 0;
  for (uint64_t e = raysOf_[i]; e < raysOf_[i + 1]; ++e) {
    const uint32_t r = rayList_[e];
    change -= --count_[k * r + size_t(from)] == 0;
    change += count_[k * r + size_t(to)]++ == 0;
  }
  score_ = uint64_t(int64_t(score_) + change);
  remove(i, from);
  add(i, to);
  part_[i] = uint16_t(to);
}

double PartAssignment::excess(double limit) const {
  double e = 0;
  for (uint64_t b : bytes_) e += std::max(0.0, double(b) - limit);
  return e;
}

void PartAssignment::refine(double limit) {
  constexpr int kPasses = 8;
  const size_t k = size_t(parts_);
  std::vector<uint8_t> touched(k);
  for (int pass = 0; pass < kPasses; ++pass) {
    uint64_t moved = 0;
    for (size_t i = 0; i < part_.size(); ++i) {
      if (raysOf_[i] == raysOf_[i + 1]) continue;
      const int from = part_[i];
      // The parts its rays touch: the only ones a move to can lower the score.
      std::fill(touched.begin(), touched.end(), 0);
      for (uint64_t e = raysOf_[i]; e < raysOf_[i + 1]; ++e)
        for (size_t p = 0; p < k; ++p) touched[p] |= count_[k * rayList_[e] + p] > 0;
      int best = -1;
      int64_t bestChange = 0;
      for (size_t p = 0; p < k; ++p) {
        if (!touched[p] || int(p) == from) continue;
        const int64_t change = scoreChange(i, int(p));
        if (change >= bestChange) continue;  // ties keep the lower part
        if (double(bytes_[p] + added(i, int(p))) > limit) continue;
        best = int(p);
        bestChange = change;
      }
      if (best < 0) continue;
      move(i, best);
      ++moved;
    }
    moves_ += moved;
    if (moved == 0) break;
  }
}

void PartAssignment::rebalance(double limit) {
  // The rounds lower the total excess; gathering a shared mesh's users frees
  // copies (less over all parts) but may pile them on one part. Where the
  // largest part ends larger than it was, the moves are undone: balancing
  // is for the largest part.
  const std::vector<uint16_t> before = part_;
  const uint64_t largestBefore = largest();
  rebalanceRounds(limit);
  if (largest() <= largestBefore) return;
  for (size_t i = 0; i < part_.size(); ++i) move(i, before[i]);
}

void PartAssignment::rebalanceRounds(double limit) {
  constexpr int kRounds = 8;
  const size_t k = size_t(parts_), resources = set_.resourceBytes.size();
  struct Candidate {
    double score;
    std::vector<uint32_t> members;
    int to;
  };
  for (int round = 0; round < kRounds; ++round) {
    if (excess(limit) <= 0) return;
    // The parts over the limit give; the lightest part (and, for a group,
    // a part already holding its resources) receives.
    std::vector<int> byBytes(k);
    for (size_t p = 0; p < k; ++p) byBytes[p] = int(p);
    std::stable_sort(byBytes.begin(), byBytes.end(),
                     [&](int a, int b) { return bytes_[size_t(a)] < bytes_[size_t(b)]; });
    std::vector<Candidate> candidates;
    auto tryGroup = [&](const std::vector<uint32_t>& group, int to, double& removed,
                        double& damage) {
      const double before = excess(limit);
      const uint64_t scoreBefore = score_;
      std::vector<uint16_t> from(group.size());
      for (size_t g = 0; g < group.size(); ++g) {
        from[g] = part_[group[g]];
        move(group[g], to);
      }
      removed = before - excess(limit);
      damage = double(score_) - double(scoreBefore);
      return from;
    };
    auto undo = [&](const std::vector<uint32_t>& group, const std::vector<uint16_t>& from) {
      for (size_t g = 0; g < group.size(); ++g) move(group[g], from[g]);
    };
    auto consider = [&](const std::vector<uint32_t>& group, int to) {
      if (to == part_[group[0]]) return;
      double removed = 0, damage = 0;
      undo(group, tryGroup(group, to, removed, damage));
      if (removed > 0) candidates.push_back({(damage + 1) / removed, group, to});
    };
    std::vector<std::vector<uint32_t>> byObject(k * set_.objectCount);
    std::vector<std::vector<uint32_t>> byResource(k * resources);
    for (size_t i = 0; i < part_.size(); ++i) {
      const int p = part_[i];
      if (double(bytes_[size_t(p)]) <= limit) continue;
      consider({uint32_t(i)}, byBytes[0] == p ? byBytes[1 % k] : byBytes[0]);
      const Unit& u = set_.units[members_[i]];
      if (u.object >= 0)
        byObject[size_t(p) * set_.objectCount + size_t(u.object)].push_back(uint32_t(i));
      for (uint32_t j = 0; j < u.resourceCount; ++j)
        byResource[size_t(p) * resources + set_.resources[u.firstResource + j]].push_back(
            uint32_t(i));
    }
    // Groups go to the lightest part, and to each part already holding the
    // group's first resource (where they add least).
    auto considerGroup = [&](const std::vector<uint32_t>& group) {
      if (group.size() < 2) return;
      const int from = part_[group[0]];
      const int lightest = byBytes[0] == from ? byBytes[1 % k] : byBytes[0];
      consider(group, lightest);
      const Unit& u = set_.units[members_[group[0]]];
      if (u.resourceCount == 0) return;
      const uint32_t r = set_.resources[u.firstResource];
      for (size_t p = 0; p < k; ++p)
        if (int(p) != from && int(p) != lightest && refs_[p * resources + r] > 0)
          consider(group, int(p));
    };
    for (const auto& g : byObject) considerGroup(g);
    for (size_t p = 0; p < k; ++p)
      for (size_t r = 0; r < resources; ++r) {
        const auto& g = byResource[p * resources + r];
        bool elsewhere = false;
        for (size_t q = 0; q < k && !elsewhere; ++q)
          elsewhere = q != p && refs_[q * resources + r] > 0;
        if (elsewhere) considerGroup(g);
      }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
    uint64_t moved = 0;
    for (const Candidate& c : candidates) {
      if (excess(limit) <= 0) break;
      bool whole = true;  // still all in one part (an earlier move may have taken some)
      for (uint32_t i : c.members) whole &= part_[i] == part_[c.members[0]];
      if (!whole || part_[c.members[0]] == c.to) continue;
      double removed = 0, damage = 0;
      const std::vector<uint16_t> from = tryGroup(c.members, c.to, removed, damage);
      if (removed <= 0) {
        undo(c.members, from);  // no longer helps
        continue;
      }
      moved += c.members.size();
    }
    moves_ += moved;
    if (moved == 0) return;
  }
}

}  // namespace ferry
