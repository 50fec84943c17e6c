// Counter-based random numbers: every value is a pure function of
// (pixel, sample, bounce, dimension, seed). No generator state is carried by a
// path, so the image cannot depend on thread count, rank count, partitioner or
// the order in which paths are processed. A path vertex's numbers come from
// RandomStream, independent or Sobol' (SamplerKind); the other uses
// (random01) are independent.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "core/sobol.h"

namespace ferry {

// 32-bit finalizer from the "lowbias32" family (Chris Wellons): full avalanche.
[[gnu::always_inline]] inline uint32_t hashMix(uint32_t x) {
  x ^= x >> 16;
  x *= 0x21f0aaadu;
  x ^= x >> 15;
  x *= 0x735a2d97u;
  x ^= x >> 15;
  return x;
}

[[gnu::always_inline]] inline uint32_t hashCombine(uint32_t seed, uint32_t value) {
  return hashMix(seed ^ (value + 0x9e3779b9u + (seed << 6) + (seed >> 2)));
}

// Which random decision a number is for; one dimension per use keeps
// decisions independent of each other.
enum class RandomDim : uint32_t {
  PixelJitterX = 0,
  PixelJitterY,
  LightSelect,
  LightSampleU,
  LightSampleV,
  BsdfLobe,
  BsdfU,
  BsdfV,
  Roulette,
  OwnerPick,
  MaterialSelect,  // which material of a mix shades the vertex
  LensU,           // the thin lens point of a camera ray or a connection to the camera
  LensV,
  Time,  // when a camera ray is, within the shutter (scene/motion.h)
  Count
};

struct RandomKey {
  uint32_t pixel = 0;
  uint32_t sample = 0;
  uint32_t bounce = 0;
  uint32_t seed = 0;
};

// The part of the hash shared by every dimension of one key. A path vertex
// draws up to eight numbers from one key: hashing the key once (RandomStream)
// and each dimension with one more mix keeps the numbers cheap.
[[gnu::always_inline]] inline uint32_t randomKeyHash(const RandomKey& key) {
  // Two 64-bit mixes (the splitmix64 finalizer, a bijection): (pixel, sample),
  // then (bounce, seed) added; half the work of combining four 32-bit hashes.
  auto mix64 = [](uint64_t x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    return x ^ (x >> 31);
  };
  const uint64_t h = mix64((uint64_t(key.pixel) << 32) | key.sample);
  return uint32_t(mix64(h + ((uint64_t(key.bounce) << 32) | key.seed) * 0x9e3779b97f4a7c15ull) >>
                  32);
}

// One full-avalanche mix of the key's hash and a per-dimension constant: a
// bijection for each dimension, so the numbers of one key are distinct, and
// unrelated between dimensions (tested in random_test.cpp).
[[gnu::always_inline]] inline uint32_t randomBitsFromKeyHash(uint32_t keyHash, uint32_t dimension) {
  return hashMix(keyHash ^ (dimension * 0x9e3779b9u + 0x632be5abu));
}

inline uint32_t randomBits(const RandomKey& key, uint32_t dimension) {
  return randomBitsFromKeyHash(randomKeyHash(key), dimension);
}

// Uniform in [0, 1): the top 24 bits give exactly representable floats.
[[gnu::always_inline]] inline float random01FromBits(uint32_t bits) {
  return static_cast<float>(bits >> 8) * 0x1p-24f;
}

inline float random01(const RandomKey& key, RandomDim dim) {
  return random01FromBits(randomBits(key, static_cast<uint32_t>(dim)));
}

// How a path vertex's numbers are drawn (--sampler): Sobol' points, a fresh
// 2D sequence for each pair of numbers (core/sobol.h; pbrt-v4's paddedsobol),
// whose stratification lowers the error at equal samples; or independent
// hashes of the key (pbrt's independent sampler).
enum class SamplerKind : uint8_t { Sobol, Independent };

inline const char* samplerName(SamplerKind kind) {
  return kind == SamplerKind::Sobol ? "sobol" : "independent";
}
inline std::optional<SamplerKind> samplerNamed(std::string_view name) {
  if (name == "sobol") return SamplerKind::Sobol;
  if (name == "independent") return SamplerKind::Independent;
  return std::nullopt;
}

// The numbers of one key. Independent: the key hashed once, each dimension
// with one more mix (stream(dim) == random01(key, dim)). Sobol': sample
// `key.sample` of the sequences (pixel, bounce, seed) and the dimension's
// pair key; the pairs are (PixelJitterX, Y), (LightSampleU, V), (BsdfU, V),
// (LensU, V), and each other dimension is the first number of its own pair.
class RandomStream {
 public:
  [[gnu::always_inline]] explicit RandomStream(const RandomKey& key,
                                               SamplerKind kind = SamplerKind::Independent)
      : sobol_(kind == SamplerKind::Sobol) {
    if (sobol_) {
      keyHash_ = randomKeyHash(RandomKey{key.pixel, 0, key.bounce, key.seed});
      reversedSample_ = reverseBits(key.sample);
    } else {
      keyHash_ = randomKeyHash(key);
    }
  }
  [[gnu::always_inline]] float operator()(RandomDim dim) const {
    const uint32_t d = static_cast<uint32_t>(dim);
    if (!sobol_) return random01FromBits(randomBitsFromKeyHash(keyHash_, d));
    const uint32_t second = kSecondOfPair[d];
    const uint32_t seed = randomBitsFromKeyHash(keyHash_, d - second);
    if (!second) return random01FromBits(sobolFirst(reversedSample_, seed));
    return random01FromBits(sobolSecond(reversedSample_, seed, hashMix(seed ^ 0x68e31da4u)));
  }

 private:
  // 1 for the second number of a pair (its pair key is the dimension before).
  static constexpr uint8_t kSecondOfPair[uint32_t(RandomDim::Count)] = {0, 1, 0, 0, 1, 0, 0,
                                                                        1, 0, 0, 0, 0, 1, 0};
  static_assert(uint32_t(RandomDim::Count) == 14, "pair each new dimension in kSecondOfPair");
  uint32_t keyHash_ = 0;
  uint32_t reversedSample_ = 0;
  bool sobol_;
};

}  // namespace ferry
