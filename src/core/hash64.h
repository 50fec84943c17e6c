// XXH64 (Yann Collet's xxHash, 64-bit variant, from Debian's libxxhash), the
// digest part files and checkpoints are checked with. Streaming: feed bytes
// in any chunking and get the same digest as hashing them at once.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace ferry {

class Hash64 {
 public:
  // Room for xxHash's streaming state (checked where it is used).
  struct State {
    alignas(8) unsigned char bytes[96];
  };

  explicit Hash64(uint64_t seed = 0);
  void update(const void* data, size_t bytes);
  uint64_t digest() const;

 private:
  State state_;
};

uint64_t hash64(const void* data, size_t bytes, uint64_t seed = 0);
// 16 lower-case hex digits, as stored in manifests.
std::string hashToHex(uint64_t hash);

}  // namespace ferry
