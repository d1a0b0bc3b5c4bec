// Hashes of a function's result bits over many fixed arguments, for tests that pin a function's
// bits on one platform and check them on another (x86-64 against AArch64 under qemu): the same
// hash means the same bits for every argument drawn.
#pragma once

#include <bit>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <type_traits>

#include "common/fnv1a.hpp"

namespace softevo::test {

constexpr int kHashedArguments = 1 << 18;

// FNV-1a (common/fnv1a.hpp) over the bytes of 64-bit patterns, least significant first.
struct BitHash {
  Fnv1a64 f;
  void add(std::uint64_t bits) { f.u64_le(bits); }
  std::string hex() const {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%016" PRIx64, f.value());
    return buf;
  }
};

// Arguments drawn uniformly from [lo, hi] with a fixed generator and a portable draw (the top
// 53 or 24 bits of mt19937_64 as a fraction), so every platform sees the same arguments.
template <class Real, class F>
std::string hash_uniform(Real lo, Real hi, F f) {
  static_assert(std::is_same_v<Real, double> || std::is_same_v<Real, float>);
  constexpr bool is_double = std::is_same_v<Real, double>;
  using Bits = std::conditional_t<is_double, std::uint64_t, std::uint32_t>;
  constexpr int dropped_bits = is_double ? 11 : 40;
  constexpr Real fraction_scale = is_double ? Real(0x1.0p-53) : Real(0x1.0p-24);
  std::mt19937_64 rng(20261201);
  BitHash hash;
  for (int i = 0; i < kHashedArguments; ++i) {
    const Real u = static_cast<Real>(rng() >> dropped_bits) * fraction_scale;
    hash.add(std::bit_cast<Bits>(static_cast<Real>(f(lo + (hi - lo) * u))));
  }
  return hash.hex();
}
template <class F>
std::string hash_double(double lo, double hi, F f) {
  return hash_uniform<double>(lo, hi, f);
}
template <class F>
std::string hash_float(float lo, float hi, F f) {
  return hash_uniform<float>(lo, hi, f);
}

}  // namespace softevo::test
