// Fully specified pseudo-random numbers for plugins and the host (the
// point-cloud sampling): the same seed gives
// the same numbers with every compiler and standard library (the output
// of std::*_distribution is left open by the standard, so generated
// objects and resets must not use them). Header-only, no dependencies.
#pragma once

#include <cstdint>
#include <string>

namespace manibench::sdk {

// splitmix64 (Steele, Lea, Flood 2014): tiny, fast, passes BigCrush.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  // Uniform in [lo, hi), from the top 53 bits.
  double uniform(double lo, double hi) { return lo + (hi - lo) * double(next() >> 11) * 0x1.0p-53; }
  int integer(int lo, int hi) { return lo + int(next() % uint64_t(hi - lo + 1)); }  // inclusive
  // In [0, bound): multiply-shift; the bias (bound / 2^64) is negligible.
  uint64_t below(uint64_t bound) {
    return static_cast<uint64_t>((static_cast<unsigned __int128>(next()) * bound) >> 64);
  }
  bool chance(double p) { return uniform(0, 1) < p; }

 private:
  uint64_t state_;
};

// FNV-1a of a string: turns an object id into a seed.
inline uint64_t hashString(const std::string& s) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

}  // namespace manibench::sdk
