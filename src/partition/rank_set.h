// A set of ranks of any size: the owners of an instance or a proxy, and (for
// the replay path layout) the ranks a ray has visited.
//
// Ranks 0..63 live in one inline 64-bit word, so up to 64 ranks a set is a
// plain mask with no allocation and every operation is a few bit operations
// (the <=64-rank renderer converts to RankMask once, at set-up, and never
// touches this class on its hot path). Ranks 64 and above live in further
// words on the heap, kept without trailing zero words so that equal sets
// compare equal.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace ferry {

using RankMask = uint64_t;  // bit r: rank r (up to 64 ranks): the compact paths' masks

class RankSet {
 public:
  RankSet() = default;
  static RankSet single(int rank);
  static RankSet fromMask(RankMask mask) {
    RankSet s;
    s.low_ = mask;
    return s;
  }
  // Ranks 0 .. n-1.
  static RankSet firstN(int n);
  // `count` little-endian words, word k holding ranks 64k .. 64k+63.
  static RankSet fromWords(const uint64_t* words, size_t count);

  bool empty() const { return low_ == 0 && high_.empty(); }
  bool contains(int rank) const;
  void insert(int rank);
  int count() const;
  // The k-th lowest rank (0 <= k < count()).
  int nth(int k) const;
  int lowest() const { return nth(0); }
  int highest() const;  // -1 when empty

  bool intersects(const RankSet& o) const;
  bool isSubsetOf(const RankSet& o) const;
  RankSet& operator|=(const RankSet& o);
  friend RankSet operator|(RankSet a, const RankSet& b) { return a |= b; }
  bool operator==(const RankSet& o) const = default;

  // True when every rank is below 64: then mask() is the whole set.
  bool fitsInMask() const { return high_.empty(); }
  RankMask mask() const { return low_; }  // ranks 0..63 only
  // Word k (ranks 64k .. 64k+63); 0 past the last stored word.
  uint64_t word(size_t k) const {
    return k == 0 ? low_ : (k - 1 < high_.size() ? high_[k - 1] : 0);
  }
  size_t wordCount() const { return 1 + high_.size(); }

  std::vector<int> ranks() const;
  std::string toString() const;  // e.g. "{0, 3, 70}"

 private:
  void trim();
  uint64_t low_ = 0;
  std::vector<uint64_t> high_;
};

std::ostream& operator<<(std::ostream& out, const RankSet& s);

// Words needed to store any set of `ranks` ranks (part files).
inline size_t rankSetWords(int ranks) {
  return ranks <= 64 ? 1 : size_t(ranks + 63) / 64;
}

}  // namespace ferry
