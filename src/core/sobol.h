// Sobol' points for the renderer's samples: the first two Sobol' dimensions,
// a fresh 2D sequence for each pair of a path vertex's numbers ("padded"
// Sobol', as pbrt-v4's paddedsobol sampler). Each pair's sequence is the
// Sobol' sequence with its sample order shuffled by a nested uniform (Owen)
// scramble of the index (Burley, "Practical Hash-based Owen Scrambling",
// JCGT 2020) and its second component moved by a random digital shift (XOR),
// both keyed by the pair's seed. So any 2^k samples from a multiple of 2^k
// form a (0, k, 2)-net (every 2^-i by 2^-(k-i) box holds one point), each
// point is uniform in the square, and different seeds give unrelated sequences.
#pragma once

#include <array>
#include <cstdint>

namespace ferry {

[[gnu::always_inline]] inline uint32_t reverseBits(uint32_t x) {
  x = __builtin_bswap32(x);
  x = ((x & 0x0f0f0f0fu) << 4) | ((x >> 4) & 0x0f0f0f0fu);
  x = ((x & 0x33333333u) << 2) | ((x >> 2) & 0x33333333u);
  return ((x & 0x55555555u) << 1) | ((x >> 1) & 0x55555555u);
}

// A bijection of 32 bits whose output bit j depends only on input bits
// 0..j and the seed (pbrt-v4's FastOwenScrambler without its bit
// reversals): on reversed bits it is a nested uniform scramble.
[[gnu::always_inline]] inline uint32_t owenScrambleReversed(uint32_t v, uint32_t seed) {
  v ^= v * 0x3d20adeau;
  v += seed;
  v *= (seed >> 16) | 1u;
  v ^= v * 0x05526c56u;
  v ^= v * 0x53a22864u;
  return v;
}

namespace sobol_detail {
// The second Sobol' dimension of index reverseBits(z), as four tables of
// z's bytes (direction numbers v(0) = 2^31, v(k) = v(k-1) ^ v(k-1) >> 1).
constexpr std::array<uint32_t, 1024> secondDimensionTable() {
  std::array<uint32_t, 32> column{};  // the value of z = 1 << j (index bit 31 - j)
  uint32_t v = 0x80000000u;
  for (int k = 0; k < 32; ++k) {
    column[31 - k] = v;
    v ^= v >> 1;
  }
  std::array<uint32_t, 1024> table{};
  for (int byte = 0; byte < 4; ++byte)
    for (int value = 0; value < 256; ++value) {
      uint32_t r = 0;
      for (int b = 0; b < 8; ++b)
        if (value & (1 << b)) r ^= column[8 * byte + b];
      table[256 * byte + value] = r;
    }
  return table;
}
inline constexpr std::array<uint32_t, 1024> kSecondDimension = secondDimensionTable();
}  // namespace sobol_detail

// Sample `index`'s point of the 2D sequence `seed` shuffles, as 32-bit
// fractions, from reversedIndex = reverseBits(index). The first component is
// uniform over seeds as it is; the second needs a uniform digital shift
// `shift`, unrelated to the seed, to make the point uniform in the square.
[[gnu::always_inline]] inline uint32_t sobolFirst(uint32_t reversedIndex, uint32_t seed) {
  // The shuffled index is reverseBits(z), whose first Sobol' dimension is z.
  return owenScrambleReversed(reversedIndex, seed);
}
[[gnu::always_inline]] inline uint32_t sobolSecond(uint32_t reversedIndex, uint32_t seed,
                                                   uint32_t shift) {
  const uint32_t z = sobolFirst(reversedIndex, seed);  // the shuffled index, reversed
  const auto& t = sobol_detail::kSecondDimension;
  return t[z & 255] ^ t[256 + ((z >> 8) & 255)] ^ t[512 + ((z >> 16) & 255)] ^ t[768 + (z >> 24)] ^
         shift;
}

}  // namespace ferry
