#pragma once
// Platform-independent random numbers. std::mt19937_64 is fully specified by the C++ standard
// (same seed -> same 64-bit stream everywhere), but std::uniform_real_distribution,
// std::uniform_int_distribution and std::shuffle are not (their algorithms are
// implementation-defined), so the mappings from raw 64-bit words used by this library are
// written out here.
#include <cstddef>
#include <cstdint>
#include <random>
#include <span>
#include <utility>

namespace systole::uq {

using Rng = std::mt19937_64;

// A uniform double strictly inside (0, 1): the top 52 bits k of one 64-bit word,
// u = (k + 1/2) 2^-52. Every u is exact (53 significant bits) and 0 < u < 1, so quantile
// functions of unbounded distributions never see 0 or 1.
inline double uniform01(Rng& rng) {
  const std::uint64_t k = rng() >> 12;
  return (static_cast<double>(k) + 0.5) * 0x1p-52;
}

// A uniform integer in [0, n), n >= 1, by rejection (no modulo bias).
inline std::uint64_t uniform_below(Rng& rng, std::uint64_t n) {
  if (n <= 1) return 0;
  // Largest multiple of n that fits: accept x < limit, where limit = 2^64 - (2^64 mod n).
  const std::uint64_t rem = (0 - n) % n;  // (2^64 - n) mod n == 2^64 mod n
  for (;;) {
    const std::uint64_t x = rng();
    if (x >= rem) return x % n;  // the accepted range [rem, 2^64) has a multiple of n values
  }
}

// Fisher–Yates shuffle (Knuth, TAOCP vol. 2, Algorithm 3.4.2P) driven by uniform_below.
template <class T>
void shuffle(std::span<T> values, Rng& rng) {
  for (std::size_t i = values.size(); i > 1; --i) {
    const std::size_t j = static_cast<std::size_t>(uniform_below(rng, i));
    std::swap(values[i - 1], values[j]);
  }
}

// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer, used to derive
// independent sub-seeds and as the counter-based hash behind Owen scrambling.
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A sub-seed for stream `stream` of a computation seeded with `seed` (e.g. one per design
// dimension, or the bootstrap of one QoI), so that streams do not overlap or correlate.
inline std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream) {
  return mix64(mix64(seed) ^ mix64(stream + 0x632be59bd9b4e019ULL));
}

}  // namespace systole::uq
