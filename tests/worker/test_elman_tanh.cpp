// softevo's binary32 tanh and expm1 (worker/elman_tanh.cpp, docs/model.md §4.7): the same bits
// as the function every earlier result used (glibc 2.36's tanhf on x86-64), on every platform,
// and accurate against the double-precision functions.
#include "worker/elman_tanh.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "tests/bit_hash.hpp"

namespace {

using softevo::worker::expm1_binary32;
using softevo::worker::tanh_binary32;

// Error of a binary32 result against an exact (double) value, in units of the binary32 spacing
// at the exact value.
double ulp_error(float got, double exact) {
  const float rounded = static_cast<float>(exact);
  const double spacing = std::fabs(rounded) < std::numeric_limits<float>::min()
                             ? std::ldexp(1.0, -149)
                             : std::ldexp(1.0, std::ilogb(rounded) - 23);
  return std::fabs(static_cast<double>(got) - exact) / spacing;
}

// Every 4099th binary32 bit pattern: about a million arguments spread over all exponents.
template <class F>
void for_sampled_floats(F f) {
  for (std::uint64_t bits = 0; bits < (1ull << 32); bits += 4099)
    f(std::bit_cast<float>(static_cast<std::uint32_t>(bits)));
}

// The hashes of glibc 2.36's tanhf on x86-64 over the controller's ranges (pinned from it before
// softevo had its own tanh, when tests/physics/test_libm_bits.cpp hashed std::tanh): the same
// hash here, on any CPU, means the same bits for each of these 2^18 arguments.
TEST(ElmanTanh, BitsEqualThePinnedX86Hashes) {
  const std::string wide = softevo::test::hash_float(-20.0f, 20.0f, tanh_binary32);
  const std::string near_zero = softevo::test::hash_float(-1.0f, 1.0f, tanh_binary32);
  std::printf("tanh_binary32 %s, near 0 %s\n", wide.c_str(), near_zero.c_str());
  EXPECT_EQ(wide, "981b7e580171452e");
  EXPECT_EQ(near_zero, "1b9b031000d46afe");
}

// On the platform the earlier results came from, compare with the C library directly over all
// exponents (the exhaustive comparison of all 2^32 inputs found no difference; it takes a minute).
TEST(ElmanTanh, EqualsGlibc236TanhfOnX86_64) {
#if defined(__x86_64__) && defined(__GLIBC__) && __GLIBC__ == 2 && __GLIBC_MINOR__ == 36
  long mismatches = 0;
  for_sampled_floats([&](float x) {
    const float libc = std::tanh(x);
    const float ours = tanh_binary32(x);
    const bool same = std::bit_cast<std::uint32_t>(libc) == std::bit_cast<std::uint32_t>(ours) ||
                      (std::isnan(libc) && std::isnan(ours));
    if (!same && ++mismatches <= 5) ADD_FAILURE() << "x = " << std::hexfloat << x;
  });
  EXPECT_EQ(mismatches, 0);
#else
  GTEST_SKIP() << "needs glibc 2.36 on x86-64, whose tanhf the earlier results used";
#endif
}

// Accuracy: within 2.5 ulp of the exact tanh (the worst seen over every 7th input is 2.16 ulp)
// and within 1 ulp for expm1 (worst seen 0.81).
TEST(ElmanTanh, IsAccurateAgainstDoublePrecision) {
  double worst_tanh = 0.0, worst_expm1 = 0.0;
  for_sampled_floats([&](float x) {
    if (!std::isfinite(x)) return;
    worst_tanh = std::max(worst_tanh, ulp_error(tanh_binary32(x), std::tanh(double{x})));
    const double e = std::expm1(double{x});
    if (std::fabs(e) < std::numeric_limits<float>::max())
      worst_expm1 = std::max(worst_expm1, ulp_error(expm1_binary32(x), e));
  });
  std::printf("worst error: tanh %.3f ulp, expm1 %.3f ulp\n", worst_tanh, worst_expm1);
  EXPECT_LE(worst_tanh, 2.5);
  EXPECT_LE(worst_expm1, 1.0);
}

TEST(ElmanTanh, IsOddAndMonotonic) {
  float previous = -1.0f;
  for (float x = -30.0f; x <= 30.0f; x += 0.001953125f) {  // 2^-9 steps
    const float t = tanh_binary32(x);
    EXPECT_EQ(std::bit_cast<std::uint32_t>(tanh_binary32(-x)), std::bit_cast<std::uint32_t>(-t))
        << x;
    EXPECT_GE(t, previous) << x;
    previous = t;
  }
}

TEST(ElmanTanh, SpecialValues) {
  EXPECT_FALSE(std::signbit(tanh_binary32(0.0f)));
  EXPECT_TRUE(std::signbit(tanh_binary32(-0.0f)));
  EXPECT_EQ(tanh_binary32(std::numeric_limits<float>::infinity()), 1.0f);
  EXPECT_EQ(tanh_binary32(-std::numeric_limits<float>::infinity()), -1.0f);
  EXPECT_TRUE(std::isnan(tanh_binary32(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_EQ(tanh_binary32(22.0f), 1.0f);
  EXPECT_EQ(tanh_binary32(-1e30f), -1.0f);
  const float tiny = 0x1.0p-60f;  // tanh x = x - x^3/3 rounds to x
  EXPECT_EQ(tanh_binary32(tiny), tiny);
  const float denormal = std::numeric_limits<float>::denorm_min();
  EXPECT_EQ(tanh_binary32(denormal), denormal);

  EXPECT_EQ(expm1_binary32(0.0f), 0.0f);
  EXPECT_EQ(expm1_binary32(-std::numeric_limits<float>::infinity()), -1.0f);
  EXPECT_EQ(expm1_binary32(-100.0f), -1.0f);
  EXPECT_EQ(expm1_binary32(89.0f), std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(expm1_binary32(std::numeric_limits<float>::quiet_NaN())));
}

}  // namespace
