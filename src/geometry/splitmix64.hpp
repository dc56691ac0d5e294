#pragma once
// SplitMix64 (Steele, Lea and Flood, 2014): a tiny pseudo-random generator whose output is
// fixed by its definition. std's distributions are not (they differ between standard
// libraries), so everything that must give the same places for a seed on every platform
// (placed goals, the simulator's starts, goals and movers) draws from this.

#include <cstddef>
#include <cstdint>

namespace staa {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, n), n > 0 (the modulo bias is below 2^-50 for any count of places).
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
  // Uniform in [0, 1) from the top 53 bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // Uniform in [a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  // A standard normal sample from one draw: four 16-bit uniforms summed (Irwin-Hall),
  // centred and scaled to unit variance. Its tails end at +-3.5 sigma, which a sensor's noise
  // model does not miss.
  double normal() {
    std::uint64_t bits = next();
    double sum = 0.0;
    for (int i = 0; i < 4; ++i) {
      sum += static_cast<double>(bits & 0xFFFF) * (1.0 / 65536.0);
      bits >>= 16;
    }
    return (sum - 2.0) * 1.7320508075688772;  // var of the sum is 4/12
  }

 private:
  std::uint64_t state_;
};

}  // namespace staa
