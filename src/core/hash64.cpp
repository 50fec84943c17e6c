#include "core/hash64.h"

#include <fmt/format.h>

#define XXH_STATIC_LINKING_ONLY  // XXH64_state_t's layout, to hold it in place
#include <xxhash.h>

#include <new>

namespace ferry {
namespace {

static_assert(sizeof(XXH64_state_t) <= sizeof(Hash64::State) &&
                  alignof(XXH64_state_t) <= alignof(Hash64::State),
              "Hash64 holds xxHash's streaming state in place");

XXH64_state_t* state(Hash64::State& s) {
  return std::launder(reinterpret_cast<XXH64_state_t*>(&s));
}
const XXH64_state_t* state(const Hash64::State& s) {
  return std::launder(reinterpret_cast<const XXH64_state_t*>(&s));
}

}  // namespace

Hash64::Hash64(uint64_t seed) {
  XXH64_reset(new (&state_) XXH64_state_t, seed);
}

void Hash64::update(const void* data, size_t bytes) {
  if (bytes > 0) XXH64_update(state(state_), data, bytes);
}

uint64_t Hash64::digest() const {
  return XXH64_digest(state(state_));
}

uint64_t hash64(const void* data, size_t bytes, uint64_t seed) {
  return XXH64(bytes > 0 ? data : "", bytes, seed);
}

std::string hashToHex(uint64_t hash) {
  return fmt::format("{:016x}", hash);
}

}  // namespace ferry
