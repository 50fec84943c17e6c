// XXH64 (Yann Collet's xxHash, 64-bit variant), written out here so that part
// files can be checked for corruption without a new dependency. Streaming:
// feed bytes in any chunking and get the same digest as hashing them at once.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace ferry {

class Hash64 {
 public:
  explicit Hash64(uint64_t seed = 0);
  void update(const void* data, size_t bytes);
  uint64_t digest() const;

 private:
  uint64_t seed_;
  uint64_t lanes_[4];
  uint8_t buffer_[32];
  size_t buffered_ = 0;
  uint64_t total_ = 0;
};

uint64_t hash64(const void* data, size_t bytes, uint64_t seed = 0);
// 16 lower-case hex digits, as stored in manifests.
std::string hashToHex(uint64_t hash);

}  // namespace ferry
