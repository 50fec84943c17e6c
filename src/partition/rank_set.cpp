#include "partition/rank_set.h"

#include <algorithm>
#include <bit>
#include <ostream>

#include "core/error.h"

namespace ferry {

RankSet RankSet::single(int rank) {
  RankSet s;
  s.insert(rank);
  return s;
}

RankSet RankSet::firstN(int n) {
  RankSet s;
  for (int r = 0; r < n; ++r) s.insert(r);
  return s;
}

RankSet RankSet::fromWords(const uint64_t* words, size_t count) {
  RankSet s;
  if (count == 0) return s;
  s.low_ = words[0];
  s.high_.assign(words + 1, words + count);
  s.trim();
  return s;
}

void RankSet::trim() {
  while (!high_.empty() && high_.back() == 0) high_.pop_back();
}

bool RankSet::contains(int rank) const {
  if (rank < 0) return false;
  return (word(size_t(rank) / 64) >> (rank % 64)) & 1;
}

void RankSet::insert(int rank) {
  FERRY_CHECK_GE(rank, 0);
  if (rank < 64) {
    low_ |= uint64_t(1) << rank;
    return;
  }
  size_t k = size_t(rank) / 64 - 1;
  if (high_.size() <= k) high_.resize(k + 1, 0);
  high_[k] |= uint64_t(1) << (rank % 64);
}

int RankSet::count() const {
  int n = std::popcount(low_);
  for (uint64_t w : high_) n += std::popcount(w);
  return n;
}

int RankSet::nth(int k) const {
  FERRY_CHECK_GE(k, 0);
  for (size_t i = 0; i < wordCount(); ++i) {
    uint64_t w = word(i);
    int c = std::popcount(w);
    if (k >= c) {
      k -= c;
      continue;
    }
    for (; k > 0; --k) w &= w - 1;
    return int(i * 64) + std::countr_zero(w);
  }
  FERRY_CHECK(false && "RankSet::nth past the end");
  return -1;
}

int RankSet::highest() const {
  for (size_t i = wordCount(); i-- > 0;)
    if (uint64_t w = word(i)) return int(i * 64) + 63 - std::countl_zero(w);
  return -1;
}

bool RankSet::intersects(const RankSet& o) const {
  if (low_ & o.low_) return true;
  const size_t n = std::min(high_.size(), o.high_.size());
  for (size_t i = 0; i < n; ++i)
    if (high_[i] & o.high_[i]) return true;
  return false;
}

bool RankSet::isSubsetOf(const RankSet& o) const {
  if (low_ & ~o.low_) return false;
  for (size_t i = 0; i < high_.size(); ++i)
    if (high_[i] & ~(i < o.high_.size() ? o.high_[i] : 0)) return false;
  return true;
}

RankSet& RankSet::operator|=(const RankSet& o) {
  low_ |= o.low_;
  if (high_.size() < o.high_.size()) high_.resize(o.high_.size(), 0);
  for (size_t i = 0; i < o.high_.size(); ++i) high_[i] |= o.high_[i];
  return *this;
}

std::vector<int> RankSet::ranks() const {
  std::vector<int> out;
  for (size_t i = 0; i < wordCount(); ++i)
    for (uint64_t w = word(i); w; w &= w - 1) out.push_back(int(i * 64) + std::countr_zero(w));
  return out;
}

std::string RankSet::toString() const {
  std::string s = "{";
  for (int r : ranks()) s += (s.size() > 1 ? ", " : "") + std::to_string(r);
  return s + "}";
}

std::ostream& operator<<(std::ostream& out, const RankSet& s) {
  return out << s.toString();
}

}  // namespace ferry
