// Units assigned to K parts, refined by moving units between parts, with a
// sample of rays as the hypergraph that scores it (the ray-guided
// partitioner's optimizer; ray_guided_partitioner.h).
//
// The score is the forwarding estimate: a ray whose units lie in m parts
// costs m - 1 (the "connectivity - 1" metric). Bytes are counted as a part
// pays them: its units' records, and each mesh or texture once per part that
// uses it. refine() moves single units, greedily, where that lowers the score
// within the byte limit; rebalance() removes the excess above the limit by
// the moves that cost the fewest rays per byte: single units, an object's
// instances, or the users of a shared mesh or texture. A pure function of
// the input (ties to the lower index). docs/partitioning.md, "The
// ray-guided partitioner".
#pragma once

#include <cstdint>
#include <vector>

#include "partition/units.h"

namespace ferry {

// Rays as rows of unit indices: ray r passes units[offsets[r], offsets[r + 1]).
struct Hypergraph {
  std::vector<uint64_t> offsets{0};
  std::vector<uint32_t> units;
  size_t rays() const { return offsets.size() - 1; }
};

class PartAssignment {
 public:
  // `members[k]`: the unit (of `set`) that index k stands for; `rays` over
  // indices k; `part[k]`: its part, below `parts`.
  PartAssignment(const UnitSet& set, std::vector<uint32_t> members, const Hypergraph& rays,
                 int parts, std::vector<uint16_t> part);

  int partOf(size_t k) const { return part_[k]; }
  uint64_t bytes(int part) const { return bytes_[size_t(part)]; }
  uint64_t largest() const;
  // Sum over rays of (parts the ray touches - 1).
  uint64_t score() const { return score_; }
  uint64_t moves() const { return moves_; }

  void refine(double limit);
  void rebalance(double limit);

 private:
  // Score change of moving index k to part `to` (negative: better).
  int64_t scoreChange(size_t k, int to) const;
  // Bytes `part` frees when index k leaves it, and takes when k joins it:
  // k's records and the resources of k that `users` units there use (1: only k).
  uint64_t bytesWhereUsers(size_t k, int part, uint32_t users) const;
  uint64_t released(size_t k, int part) const { return bytesWhereUsers(k, part, 1); }
  uint64_t added(size_t k, int part) const { return bytesWhereUsers(k, part, 0); }
  void rebalanceRounds(double limit);
  void add(size_t k, int part);
  void remove(size_t k, int part);
  void move(size_t k, int to);
  double excess(double limit) const;

  const UnitSet& set_;
  std::vector<uint32_t> members_;
  const Hypergraph& rays_;
  int parts_;
  std::vector<uint16_t> part_;
  std::vector<uint64_t> raysOf_;  // index k's rays: rayList_[raysOf_[k], raysOf_[k + 1])
  std::vector<uint32_t> rayList_;
  std::vector<uint32_t> count_;  // per ray and part: its units there
  std::vector<uint32_t> refs_;   // per part and resource: units there using it
  std::vector<uint64_t> bytes_;  // per part
  uint64_t score_ = 0;
  uint64_t moves_ = 0;
};

}  // namespace ferry
