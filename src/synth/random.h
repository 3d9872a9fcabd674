// The synth module's one random generator: a SplitMix64 stream with Box-Muller normal deviates.
// Portable (std::normal_distribution differs between standard libraries), so a seed renders the
// same images everywhere. Internal to src/synth.
#ifndef IMPACTDIC_SRC_SYNTH_RANDOM_H_
#define IMPACTDIC_SRC_SYNTH_RANDOM_H_

#include <cmath>
#include <cstdint>
#include <numbers>

namespace impactdic::synth_detail {

// SplitMix64's finaliser of x + golden ratio: a well-mixed 64-bit hash of x.
inline std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(SplitMix64(seed)) {}
  std::uint64_t Next() {
    state_ += 0x9E3779B97F4A7C15ull;
    return SplitMix64(state_);
  }
  double Uniform() { return (Next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
  // Standard normal by Box-Muller; deviates come in pairs (cos, then the cached sin).
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = Uniform();
    while (u1 <= 0) u1 = Uniform();
    const double u2 = Uniform();
    const double r = std::sqrt(-2 * std::log(u1));
    spare_ = r * std::sin(2 * std::numbers::pi * u2);
    has_spare_ = true;
    return r * std::cos(2 * std::numbers::pi * u2);
  }

 private:
  std::uint64_t state_;
  bool has_spare_ = false;
  double spare_ = 0;
};

}  // namespace impactdic::synth_detail

#endif  // IMPACTDIC_SRC_SYNTH_RANDOM_H_
