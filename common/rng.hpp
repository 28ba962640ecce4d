// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Deterministic random streams: every randomised stage derives its generator from a base seed
// and a stream index, so results do not depend on the order in which streams are consumed
// (or on the number of threads).

#include <cstdint>
#include <random>

namespace lidarcal {

/// SplitMix64 finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mixer.
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// Seed of stream `stream` under base seed `seed`.
inline std::uint64_t deriveSeed(std::uint64_t seed, std::uint64_t stream) {
  return splitmix64(splitmix64(seed) ^ splitmix64(stream + 0x632be59bd9b4e019ULL));
}

/// A generator for stream `stream` under base seed `seed`.
inline std::mt19937_64 makeRng(std::uint64_t seed, std::uint64_t stream) {
  return std::mt19937_64(deriveSeed(seed, stream));
}

}  // namespace lidarcal
