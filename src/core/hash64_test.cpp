#include "core/hash64.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace ferry {
namespace {

// Reference digests from the xxHash library itself (libxxhash 0.8.1, XXH64).
TEST(Hash64, MatchesReferenceXxh64) {
  EXPECT_EQ(hash64("", 0), 0xef46db3751d8e999ull);
  EXPECT_EQ(hash64("a", 1), 0xd24ec4f1a98c6e5bull);
  EXPECT_EQ(hash64("abc", 3), 0x44bc2cf5ad770999ull);
  EXPECT_EQ(hash64("abc", 3, 7), 0x9e755206156676d7ull);
  std::vector<uint8_t> bytes;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 256; ++i) bytes.push_back(uint8_t(i));
  for (char c : std::string("xyz")) bytes.push_back(uint8_t(c));
  EXPECT_EQ(hash64(bytes.data(), bytes.size()), 0xe921a1b45bd779f8ull);
  EXPECT_EQ(hash64(bytes.data(), 100, 123456789), 0xf96f532e91c7bcf4ull);
}

TEST(Hash64, StreamingEqualsOneShotForAnyChunking) {
  std::vector<uint8_t> bytes(1000);
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = uint8_t(i * 37 + 11);
  uint64_t whole = hash64(bytes.data(), bytes.size(), 5);
  for (size_t chunk : {1, 3, 7, 31, 32, 33, 64, 999}) {
    Hash64 h(5);
    for (size_t at = 0; at < bytes.size(); at += chunk)
      h.update(bytes.data() + at, std::min(chunk, bytes.size() - at));
    EXPECT_EQ(h.digest(), whole) << "chunk " << chunk;
  }
  EXPECT_EQ(hashToHex(0xef46db3751d8e999ull), "ef46db3751d8e999");
}

}  // namespace
}  // namespace ferry
