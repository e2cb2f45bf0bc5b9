#pragma once
// Counter-based random numbers: a value is a pure function of its key (seed, stream, index), so
// results do not depend on thread scheduling or on which sweeps were generated before.

#include <cmath>
#include <cstdint>

namespace mmlio::sim {

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

inline std::uint64_t hashKey(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d = 0) {
  return splitmix64(splitmix64(splitmix64(splitmix64(a) ^ b) ^ c) ^ d);
}

/// Uniform in (0, 1) from a 64-bit hash.
inline double unitFromHash(std::uint64_t h) {
  return (static_cast<double>(h >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

/// Standard normal sample for a key (Box-Muller on two derived hashes).
inline double normalFromKey(std::uint64_t key) {
  const double u1 = unitFromHash(splitmix64(key ^ 0x1234567ULL)), u2 = unitFromHash(splitmix64(key ^ 0x89ABCDEFULL));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace mmlio::sim
