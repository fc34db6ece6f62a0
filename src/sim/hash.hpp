#pragma once
// Integer hashes and a counter-based random source for the generator. Everything random in a
// synthetic sequence comes from these, never from std:: distributions (whose output is
// implementation-defined), so a seed gives the same bytes with any standard library.

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

namespace rgbl::sim_detail {

// No hit yet: where the ray casts of the scene and the renderer start their nearest-hit search.
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// splitmix64's finaliser: a bijective 64-bit mix.
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31U);
}

inline std::uint64_t mix64(std::uint64_t a, std::uint64_t b) { return mix64(a ^ mix64(b)); }
inline std::uint64_t mix64(std::uint64_t a, std::uint64_t b, std::uint64_t c) { return mix64(mix64(a, b), c); }

// A fast 32-bit avalanche (lowbias32), for texture lattices.
inline std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16U;
  x *= 0x7FEB352DU;
  x ^= x >> 15U;
  x *= 0x846CA68BU;
  x ^= x >> 16U;
  return x;
}

inline std::uint32_t hash2(std::int32_t ix, std::int32_t iy, std::uint32_t salt) {
  return hash32(static_cast<std::uint32_t>(ix) * 0x9E3779B1U ^ hash32(static_cast<std::uint32_t>(iy) + salt * 0x85EBCA77U));
}

// Uniform in [0, 1) from a hash.
inline float unit(std::uint32_t h) { return static_cast<float>(h >> 8U) * (1.0F / 16777216.0F); }
inline double unit64(std::uint64_t h) { return static_cast<double>(h >> 11U) * (1.0 / 9007199254740992.0); }

// Standard normal from a 64-bit key (Box-Muller on two derived uniforms).
inline double gaussian(std::uint64_t key) {
  const double u1 = unit64(mix64(key, 0x51ED2701ULL)) + 1e-300;  // never 0
  const double u2 = unit64(mix64(key, 0xA3B195ULL));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

// A sequential random source for laying out the scene.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(mix64(seed)) {}
  std::uint64_t next() { return mix64(state_++); }
  double uniform() { return unit64(next()); }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  std::uint32_t next32() { return static_cast<std::uint32_t>(next() >> 32U); }

 private:
  std::uint64_t state_;
};

}  // namespace rgbl::sim_detail
