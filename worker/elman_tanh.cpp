// tanh and e^x - 1 in binary32 from IEEE operations only (docs/model.md §4.7). See
// elman_tanh.hpp for why. The operations and their order are part of the result: every one of
// them rounds, and the bits must match the values the controller gave before this function
// existed. Build flags keep them unfused (-ffp-contract=off, CMakeLists.txt).
#include "worker/elman_tanh.hpp"

#include <bit>
#include <cstdint>
#include <limits>

namespace softevo::worker {
namespace {

constexpr std::uint32_t kSignBit = 0x80000000u;
constexpr std::uint32_t kInfinityBits = 0x7f800000u;

// ln 2 split so that k * kLn2High is exact for the |k| <= 128 that occur: kLn2High keeps 16
// significant bits; kLn2Low is the binary32 nearest to ln 2 - kLn2High.
constexpr float kLn2High = 0x1.62e3p-1f;
constexpr float kLn2Low = 0x1.2fefa2p-17f;
constexpr float kInverseLn2 = 0x1.715476p+0f;

// Argument bounds, as binary32 bit patterns of |x|.
constexpr std::uint32_t kHalfLn2Bits = 0x3eb17218u;           // ln 2 / 2
constexpr std::uint32_t kThreeHalvesLn2Bits = 0x3f851592u;    // 1.5 ln 2
constexpr std::uint32_t kTwoPowMinus25Bits = 0x33000000u;     // below: e^x - 1 rounds to x
constexpr std::uint32_t kSaturateMinusOneBits = 0x4195b844u;  // 27 ln 2: e^-|x| - 1 rounds to -1
constexpr std::uint32_t kOverflowCheckBits = 0x42b17218u;     // ~88.72, near ln(FLT_MAX)
constexpr float kOverflowThreshold = 0x1.62e3p+6f;            // 88.72168: e^x - 1 overflows above

// The rational correction on the reduced range |r| <= ln 2 / 2 (§4.7): with h = r^2 / 2,
// R(h) = 1 + h (Q1 + h (Q2 + h (Q3 + h (Q4 + h Q5)))) approximates (r/2) coth(r/2) scaled so that
// e^r - 1 = r + h + r E with E = h (R - T) / (6 - r T), T = 3 - R r / 2.
constexpr float kQ1 = -0x1.111112p-5f;   // -3.3333335072e-02
constexpr float kQ2 = 0x1.a01a02p-10f;   //  1.5873016091e-03
constexpr float kQ3 = -0x1.4ce19ap-14f;  // -7.9365076090e-05
constexpr float kQ4 = 0x1.0cfca8p-18f;   //  4.0082177293e-06
constexpr float kQ5 = -0x1.afdb76p-23f;  // -2.0109921195e-07

std::uint32_t bits_of(float x) {
  return std::bit_cast<std::uint32_t>(x);
}
float float_of(std::uint32_t bits) {
  return std::bit_cast<float>(bits);
}

// y * 2^k by adding k to the exponent field (y is a normal number and the result stays normal
// or reaches infinity, which the callers' ranges ensure).
float scale_by_power_of_two(float y, int k) {
  return std::bit_cast<float>(std::bit_cast<std::int32_t>(y) + k * (1 << 23));
}

}  // namespace

float expm1_binary32(float x) {
  const std::uint32_t magnitude = bits_of(x) & ~kSignBit;
  const bool negative = (bits_of(x) & kSignBit) != 0;

  if (magnitude >= kSaturateMinusOneBits) {
    if (magnitude >= kOverflowCheckBits) {
      if (magnitude > kInfinityBits) return x + x;  // NaN stays NaN
      if (magnitude == kInfinityBits) return negative ? -1.0f : x;
      if (x > kOverflowThreshold) return std::numeric_limits<float>::infinity();
    }
    if (negative) return -1.0f;
  }

  // Reduction x = k ln 2 + r, |r| <= ln 2 / 2, with r carried as (r, correction) because
  // x - k ln2 loses the low bits of ln 2 (§4.7).
  int k = 0;
  float correction = 0.0f;
  if (magnitude > kHalfLn2Bits) {
    float high, low;
    if (magnitude < kThreeHalvesLn2Bits) {
      k = negative ? -1 : 1;
      high = negative ? x + kLn2High : x - kLn2High;
      low = negative ? -kLn2Low : kLn2Low;
    } else {
      k = static_cast<int>(kInverseLn2 * x + (negative ? -0.5f : 0.5f));  // round to nearest
      const float kf = static_cast<float>(k);
      high = x - kf * kLn2High;
      low = kf * kLn2Low;
    }
    x = high - low;
    correction = (high - x) - low;
  } else if (magnitude < kTwoPowMinus25Bits) {
    return x;
  }

  const float half_r = 0.5f * x;
  const float h = x * half_r;
  const float rational = 1.0f + h * (kQ1 + h * (kQ2 + h * (kQ3 + h * (kQ4 + h * kQ5))));
  const float t = 3.0f - rational * half_r;
  float e = h * ((rational - t) / (6.0f - x * t));
  if (k == 0) return x - (x * e - h);

  // e^x - 1 = 2^k (e^r - 1) + (2^k - 1), with e^r - 1 = r - (e' - h) and e' including the
  // reduction's correction; the forms below keep the cancellation exact for each k.
  e = x * (e - correction) - correction;
  e -= h;
  if (k == -1) return 0.5f * (x - e) - 0.5f;
  if (k == 1) return x < -0.25f ? -2.0f * (e - (x + 0.5f)) : 1.0f + 2.0f * (x - e);
  if (k <= -2 || k > 56) return scale_by_power_of_two(1.0f - (e - x), k) - 1.0f;
  if (k < 23) {
    const float one_minus_two_pow_minus_k = float_of(0x3f800000u - (0x1000000u >> k));
    return scale_by_power_of_two(one_minus_two_pow_minus_k - (e - x), k);
  }
  const float two_pow_minus_k = float_of(static_cast<std::uint32_t>(0x7f - k) << 23);
  return scale_by_power_of_two((x - (e + two_pow_minus_k)) + 1.0f, k);
}

float tanh_binary32(float x) {
  const std::uint32_t magnitude = bits_of(x) & ~kSignBit;
  const bool negative = (bits_of(x) & kSignBit) != 0;
  constexpr std::uint32_t kSaturateBits = 0x41b00000u;  // 22: tanh rounds to ±1 beyond
  constexpr std::uint32_t kTinyBits = 0x24000000u;      // 2^-55: tanh x rounds to x below
  constexpr std::uint32_t kOneBits = 0x3f800000u;

  if (magnitude >= kInfinityBits) return negative ? 1.0f / x - 1.0f : 1.0f / x + 1.0f;
  if (magnitude == 0) return x;  // keeps the sign of zero
  if (magnitude < kTinyBits) return x * (1.0f + x);

  // tanh|x| = 1 - 2 / (e^{2|x|} + 1) for |x| >= 1, and -m / (m + 2) with m = e^{-2|x|} - 1 below,
  // where the first form would cancel.
  float magnitude_tanh;
  if (magnitude >= kSaturateBits) {
    magnitude_tanh = 1.0f;
  } else if (magnitude >= kOneBits) {
    const float m = expm1_binary32(2.0f * float_of(magnitude));
    magnitude_tanh = 1.0f - 2.0f / (m + 2.0f);
  } else {
    const float m = expm1_binary32(-2.0f * float_of(magnitude));
    magnitude_tanh = -m / (m + 2.0f);
  }
  return negative ? -magnitude_tanh : magnitude_tanh;
}

}  // namespace softevo::worker
