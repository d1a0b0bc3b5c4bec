// The C library's functions that the evaluation outside physics/ calls (worker/: sin and cos of
// the controller's oscillator phase and of the target direction, tanhf of the Elman network,
// acos of the heading and direction terms) must give the same bits on every platform softevo
// supports: a hash of their results over many arguments of the ranges they see is pinned here
// from x86-64 (glibc 2.36, Debian 12; the same with glibc's FMA variants turned off) and checked
// on AArch64 by `tools/bootstrap.sh aarch64` (under qemu). The physics itself uses its own
// reproducible functions (physics/reproducible_math.hpp) and does not depend on these.
//
// Known difference: AArch64's tanhf (glibc 2.36) differs from x86-64's by 1-2 ulp for some
// arguments (16 of the 2^18 here, all with |x| < 1.25), so TanhOfFloats fails there until the
// controller uses a reproducible tanh; sin, cos and acos agree.
#include <gtest/gtest.h>

#include <bit>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>

namespace {

constexpr int kArguments = 1 << 18;

// FNV-1a over the 64-bit patterns of the results.
struct BitHash {
  std::uint64_t h = 0xcbf29ce484222325ull;
  void add(std::uint64_t bits) {
    for (int b = 0; b < 8; ++b) {
      h ^= (bits >> (8 * b)) & 0xff;
      h *= 0x100000001b3ull;
    }
  }
  std::string hex() const {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%016" PRIx64, h);
    return buf;
  }
};

// Arguments drawn uniformly from [lo, hi] with a fixed generator and a portable draw (the 53 top
// bits of mt19937_64 as a fraction), so every platform sees the same arguments.
template <class F>
std::string hash_double(double lo, double hi, F f) {
  std::mt19937_64 rng(20261201);
  BitHash hash;
  for (int i = 0; i < kArguments; ++i) {
    const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    hash.add(std::bit_cast<std::uint64_t>(f(lo + (hi - lo) * u)));
  }
  return hash.hex();
}
template <class F>
std::string hash_float(float lo, float hi, F f) {
  std::mt19937_64 rng(20261201);
  BitHash hash;
  for (int i = 0; i < kArguments; ++i) {
    const float u = static_cast<float>(rng() >> 40) * 0x1.0p-24f;
    hash.add(std::bit_cast<std::uint32_t>(f(lo + (hi - lo) * u)));
  }
  return hash.hex();
}

// The oscillator phase (simulation.cpp) and the direction angle (fitness.cpp): sin and cos over
// a few turns.
TEST(LibmBits, SinAndCosOfDoubles) {
  const std::string s = hash_double(-30.0, 30.0, [](double x) { return std::sin(x); });
  const std::string c = hash_double(-30.0, 30.0, [](double x) { return std::cos(x); });
  std::printf("sin %s, cos %s\n", s.c_str(), c.c_str());
  EXPECT_EQ(s, "e78a987c6f5446a9");
  EXPECT_EQ(c, "d585e67bcc24a159");
}

// The Elman network's activations (controller.cpp: std::tanh of a float is tanhf); its inputs
// are weighted sums of values in [-1, 1].
TEST(LibmBits, TanhOfFloats) {
  const std::string t = hash_float(-20.0f, 20.0f, [](float x) { return std::tanh(x); });
  const std::string n = hash_float(-1.0f, 1.0f, [](float x) { return std::tanh(x); });
  std::printf("tanhf %s, tanhf near 0 %s\n", t.c_str(), n.c_str());
  EXPECT_EQ(t, "981b7e580171452e");
  EXPECT_EQ(n, "1b9b031000d46afe");
}

// Heading and direction terms (fitness.cpp: acos of a clamped cosine).
TEST(LibmBits, AcosOfDoubles) {
  const std::string a = hash_double(-1.0, 1.0, [](double x) { return std::acos(x); });
  const std::string e = hash_double(0.999, 1.0, [](double x) { return std::acos(x); });
  std::printf("acos %s, acos near 1 %s\n", a.c_str(), e.c_str());
  EXPECT_EQ(a, "b6e74c7be3ccdd8e");
  EXPECT_EQ(e, "75d65ee4606dba31");
}

}  // namespace
