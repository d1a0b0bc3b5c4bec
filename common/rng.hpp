// Deterministic random numbers: one fixed algorithm with our own distributions, so a seed gives
// the same numbers with every compiler and standard library (std:: distributions differ).
//
// Generator: xoshiro256** 1.0 (Blackman & Vigna, 2018), 256-bit state, period 2^256 - 1.
// Seeding: the 64-bit seed is expanded into the state with SplitMix64 (as the authors advise).
// uniform(): top 53 bits / 2^53, in [0, 1). normal(): Box-Muller from two uniforms, no cached
// second value (the state is just the 4 words). uniform_int(n): Lemire's nearly-divisionless
// multiply-shift with rejection, exactly uniform on [0, n).
#pragma once

#include <array>
#include <cstdint>

namespace softevo {

class Rng {
 public:
  using State = std::array<std::uint64_t, 4>;

  explicit Rng(std::uint64_t seed = 0);

  std::uint64_t next_u64();                    // raw xoshiro256** output
  double uniform();                            // [0, 1)
  double uniform(double lo, double hi);        // [lo, hi)
  double normal();                             // N(0, 1)
  double normal(double mean, double stddev);   // N(mean, stddev^2)
  std::uint64_t uniform_int(std::uint64_t n);  // [0, n), n > 0
  bool coin(double p_true);                    // uniform() < p_true

  const State& state() const { return state_; }  // for checkpoints
  void set_state(const State& state);            // throws on the all-zero state

 private:
  State state_;
};

// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
std::uint64_t splitmix64(std::uint64_t& state);

// Seed of one evaluation / one stream, independent of rank count and arrival order
// (docs/architecture.md §3): mixes the four ids through SplitMix64 in a fixed order.
// direction = -1 for "no direction".
std::uint64_t derive_seed(std::uint64_t run_seed, std::int64_t generation, std::int64_t genome_id,
                          std::int64_t direction);

}  // namespace softevo
