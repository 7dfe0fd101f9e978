// Counter-based random numbers: the value for (seed, stream, index) does not
// depend on thread count or evaluation order, so seeded results are reproducible
// bit for bit (std::normal_distribution is implementation-defined; this is not).
#pragma once

#include <cmath>
#include <cstdint>

namespace lf3pm {

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Uniform double in (0, 1) from a 64-bit hash.
inline double unit_open(std::uint64_t h) { return (static_cast<double>(h >> 11) + 0.5) * (1.0 / 9007199254740992.0); }

/// Standard normal sample number `index` of stream `stream` under `seed` (Box-Muller).
inline double normal_sample(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  const std::uint64_t key = splitmix64(seed ^ splitmix64(stream ^ splitmix64(index)));
  const double u1 = unit_open(splitmix64(key));
  const double u2 = unit_open(splitmix64(key ^ 0xD1B54A32D192ED03ull));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

}  // namespace lf3pm
