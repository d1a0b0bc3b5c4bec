// acos, sin and cos of the physics (physics revisions 2 and 3, see physics/revision.hpp), written
// once with IEEE +, -, *, / and sqrt only, generic over the value type: a double, or a lane vector
// of the SIMD step passes. With -ffp-contract=off every width then gives the same bits as the
// scalar code, on every machine, and a whole lane vector is computed without a per-lane libm call.
//
// Why not libm: the reference simulator calls glibc's acos / sin / cos once per lane for
// large-angle links and fast-turning voxels; those scalar calls took 15-20% of a champion
// evaluation (issue 4 profile). glibc's vector variants (libmvec) round differently from its
// scalar functions and from each other across widths, so they cannot keep the widths
// bit-identical.
//
// Accuracy, worst error against mpmath at 50 digits over 60000 random arguments each (revision 3,
// Estrin; revision 2's Horner in brackets): acos 1.10 ulp (1.10), sin 0.73 (0.71), cos 0.74
// (0.73), sinc_cos_of_square 0.77 (0.68) and 0.53 (0.53). tests/physics/test_reproducible_math.cpp
// checks that every result is within 1 ulp of glibc's (itself within about half an ulp) for
// |x| <= 2^10.
// Beyond 2^10 rad, where the rounding of the Cody-Waite reduction below reaches 2 ulp, the
// callers use the C library's sin / cos (kSinCosReducedLimit); the physics only asks for the
// half angle a voxel turns in one step and the half angle of a link's bend, both below pi.
//
// Coefficients: Chebyshev fits (mpmath.chebyfit) rounded to double, see
// tools/dev/derive_math_coefficients.py:
//   asin(y) = y + y z P(z),              z = y^2 in [0, 1/4], 13 coefficients
//   sin(r)  = r + r z S(z),              z = r^2 in [0, (pi/4)^2], 7 coefficients
//   cos(r)  = 1 - z/2 + z^2 C(z),        z = r^2 in [0, (pi/4)^2], 7 coefficients
//
// Linkage: everything here is always_inline and the constants have internal linkage, because the
// step passes are also compiled for AVX2 / AVX-512 (physics/step_avx2.cpp): an out-of-line copy
// emitted there could be linked into the SSE2 code (checked by the PhysicsIsa tests, also in the
// unoptimised sanitizer build).
#pragma once

#include <cmath>

namespace softevo::physics::rmath {

// Ops of a value type T: sqrt (correctly rounded), abs, select(mask, a, b) = mask ? a : b, where
// a comparison of T gives the mask. ScalarOps is the double version; the step passes supply the
// lane version.
struct ScalarOps {
  [[gnu::always_inline]] static double sqrt(double x) { return std::sqrt(x); }
  [[gnu::always_inline]] static double abs(double x) { return std::fabs(x); }
  [[gnu::always_inline]] static double select(bool mask, double a, double b) {
    return mask ? a : b;
  }
};

constexpr double kAsinCoeff[13] = {
    0x1.5555555555556p-3, 0x1.3333333332ecap-4, 0x1.6db6db6e31f13p-5, 0x1.f1c71c1db0623p-6,
    0x1.6e8bb1c8209a2p-6, 0x1.1c4d35cf95421p-6, 0x1.c9cf07674736ap-7, 0x1.782651caa6547p-7,
    0x1.52420b04b37bep-7, 0x1.65a9c4dfcf8b2p-8, 0x1.1d189408314eep-6, -0x1.e6aaa8a0a04ccp-7,
    0x1.d72b2bc8155f8p-6};
constexpr double kSinCoeff[7] = {
    -0x1.5555555555555p-3,  0x1.1111111111110p-7,  -0x1.a01a01a019937p-13, 0x1.71de3a54607a5p-19,
    -0x1.ae64541295cdfp-26, 0x1.61217ee5cca1bp-33, -0x1.ab17bdcbd3414p-41};
constexpr double kCosCoeff[7] = {
    0x1.5555555555555p-5,  -0x1.6c16c16c16c16p-10, 0x1.a01a01a019d0ap-16, -0x1.27e4fb7712ca2p-22,
    0x1.1eed8deb82809p-29, -0x1.9394b9eb4d56dp-37, 0x1.ab78473be59d7p-45};
// pi/2 and pi as double + remainder; pi/2 in three parts of which the first two have 33
// significant bits, so k * part is exact for |k| < 2^20 (Cody-Waite reduction).
constexpr double kHalfPiHi = 0x1.921fb54442d18p+0, kHalfPiLo = 0x1.1a62633145c07p-54;
constexpr double kPiHi = 0x1.921fb54442d18p+1, kPiLo = 0x1.1a62633145c07p-53;
constexpr double kHalfPi1 = 0x1.921fb54400000p+0, kHalfPi2 = 0x1.0b4611a600000p-34,
                 kHalfPi3 = 0x1.3198a2e037073p-69;
constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
// x + 1.5 * 2^52 - 1.5 * 2^52 rounds x to the nearest integer (ties to even) for |x| < 2^51.
constexpr double kRoundMagic = 0x1.8p52;
// |x| above which sincos_reduced must not be used.
constexpr double kSinCosReducedLimit = 0x1p10;

// c[0] + c[1] z + ... + c[N-1] z^(N-1) by Estrin's scheme (physics revision 3): the pairs
// c[2k] + c[2k+1] z, then pairs of those joined by z^2, then by z^4, ...: a chain of about
// log2(N) dependent multiply-adds instead of Horner's N - 1. The lane passes are bound by the
// latency of these chains where a link or voxel takes an acos / sin / cos branch (issue 4).
template <class T, int N>
[[gnu::always_inline]] inline T estrin(const T& z, const double (&c)[N]) {
  T level[(N + 1) / 2];
  int n = 0;
  for (int k = 0; k < N; k += 2) level[n++] = k + 1 < N ? c[k] + z * c[k + 1] : T{} + c[k];
  T power = z * z;  // z^2, then z^4, z^8
  while (n > 1) {
    int m = 0;
    for (int k = 0; k < n; k += 2)
      level[m++] = k + 1 < n ? level[k] + power * level[k + 1] : level[k];
    n = m;
    if (n > 1) power = power * power;
  }
  return level[0];
}

// asin(y) for y in [0, 1/2].
template <class T>
[[gnu::always_inline]] inline T asin_small(const T& y) {
  const T z = y * y;
  return y + y * (z * estrin(z, kAsinCoeff));
}

// cos(r) = 1 - z/2 + z^2 C(z) from z = r^2, |r| <= pi/4, with the rounding error of 1 - z/2 added
// back (keeps cos within 1 ulp near pi/4).
template <class T>
[[gnu::always_inline]] inline T cos_of_square(const T& z) {
  const T half_z = 0.5 * z;
  const T one_minus = 1.0 - half_z;
  return one_minus + (((1.0 - one_minus) - half_z) + z * z * estrin(z, kCosCoeff));
}

// acos(x) for x in [-1, 1] (NaN outside):
//   |x| <= 1/2:  pi/2 - asin(x)
//   x > 1/2:     2 asin(sqrt((1 - x) / 2))       (1 - x exact: Sterbenz)
//   x < -1/2:    pi - 2 asin(sqrt((1 + x) / 2))
template <class Ops, class T>
[[gnu::always_inline]] inline T acos(const T& x) {
  const T ax = Ops::abs(x);
  const auto near_zero = ax <= 0.5;
  const T y = Ops::select(near_zero, ax, Ops::sqrt((1.0 - ax) * 0.5));
  const T s = asin_small(y);
  const T centre = kHalfPiHi - (Ops::select(x < 0.0, -s, s) - kHalfPiLo);
  const T ends = Ops::select(x < 0.0, kPiHi - (2.0 * s - kPiLo), 2.0 * s);
  return Ops::select(near_zero, centre, ends);
}

// sin(x) and cos(x) for |x| <= kSinCosReducedLimit: x = k pi/2 + r with |r| <= pi/4, then the
// quadrant k mod 4 picks +-sin(r) / +-cos(r).
template <class Ops, class T>
[[gnu::always_inline]] inline void sincos_reduced(const T& x, T& sin_x, T& cos_x) {
  const T k = (x * kTwoOverPi + kRoundMagic) - kRoundMagic;
  const T r = ((x - k * kHalfPi1) - k * kHalfPi2) - k * kHalfPi3;
  const T z = r * r;
  const T sin_r = r + r * (z * estrin(z, kSinCoeff));
  const T cos_r = cos_of_square(z);
  // quadrant = k - 4 round(k / 4), in {-2, -1, 0, 1, 2} (+-2 are the same quadrant)
  const T quadrant = k - 4.0 * ((k * 0.25 + kRoundMagic) - kRoundMagic);
  const auto odd = (quadrant == 1.0) | (quadrant == -1.0);
  const T s = Ops::select(odd, cos_r, sin_r), c = Ops::select(odd, sin_r, cos_r);
  // sin: + in quadrants 0, 1; - in 2, 3 (= -1).   cos: + in 0, 3; - in 1, 2.
  const auto sin_negative = (quadrant == 2.0) | (quadrant == -2.0) | (quadrant == -1.0);
  const auto cos_negative = (quadrant == 2.0) | (quadrant == -2.0) | (quadrant == 1.0);
  // r + r z S(z) turns r = -0 into +0; sin(+-0) = +-0 as IEEE asks
  sin_x = Ops::select(x == 0.0, x, Ops::select(sin_negative, -s, s));
  cos_x = Ops::select(cos_negative, -c, c);
}

// sin(r) / r and cos(r) from z = r^2 <= kSincCosSquareLimit (physics revision 3), with the sin /
// cos polynomials above: sin(r) / r = 1 + z S(z), cos(r) = 1 - z/2 + z^2 C(z). quat_from_rotvec
// (§2.11) needs exactly these of the half angle |theta| and has its square t = |theta|^2, so it
// takes neither the square root, the range reduction nor the division sin(|theta|) / |theta|.
// [rad^2] below (pi/4)^2 = 0.6169, the interval of the sin / cos polynomials
constexpr double kSincCosSquareLimit = 0.6;
template <class T>
[[gnu::always_inline]] inline void sinc_cos_of_square(const T& z, T& sinc, T& cos_r) {
  sinc = 1.0 + z * estrin(z, kSinCoeff);
  cos_r = cos_of_square(z);
}

// Scalar entry points (quat.hpp): the C library beyond the reduction's range.
[[gnu::always_inline]] inline double acos(double x) {
  return acos<ScalarOps>(x);
}
[[gnu::always_inline]] inline void sincos(double x, double& sin_x, double& cos_x) {
  if (std::fabs(x) <= kSinCosReducedLimit) {
    sincos_reduced<ScalarOps>(x, sin_x, cos_x);
  } else {
    sin_x = std::sin(x);
    cos_x = std::cos(x);
  }
}

}  // namespace softevo::physics::rmath
