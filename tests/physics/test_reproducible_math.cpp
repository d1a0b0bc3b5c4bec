// physics/reproducible_math.hpp: acos / sin / cos within 1 ulp of the C library (glibc's are
// themselves within about half an ulp of the true value) for |x| <= 2^10, the exact values at the
// branch ends, and the same bits for a lane vector as for the scalar code (what keeps every SIMD
// width of the step passes identical; the step passes themselves are checked by the tumbling golden
// scene of test_determinism.cpp at every width).
#include "physics/reproducible_math.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>

namespace softevo::physics::rmath {
namespace {

// Distance in ulps between two finite doubles of the same sign (0 when equal).
double ulps(double got, double want) {
  if (got == want) return 0.0;
  const double ulp = std::nextafter(std::fabs(want), INFINITY) - std::fabs(want);
  return std::fabs(got - want) / ulp;
}

double ours_sin(double x) {
  double s, c;
  sincos(x, s, c);
  return s;
}
double ours_cos(double x) {
  double s, c;
  sincos(x, s, c);
  return c;
}

TEST(ReproducibleMath, AcosIsWithinOneUlpOfTheCLibrary) {
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  double worst = 0.0, worst_x = 0.0;
  auto check = [&](double x) {
    const double e = ulps(acos(x), std::acos(x));
    if (e > worst) worst = e, worst_x = x;
  };
  for (int i = 0; i < 1'000'000; ++i) check(uniform(gen));
  // near the branch points and the ends, where cancellation would show
  for (double centre : {-1.0, -0.5, 0.0, 0.5, 1.0}) {
    double x = centre;
    for (int i = 0; i < 2000; ++i) {
      if (x > -1.0) check(x = std::nextafter(x, -2.0));
    }
    x = centre;
    for (int i = 0; i < 2000; ++i) {
      if (x < 1.0) check(x = std::nextafter(x, 2.0));
    }
  }
  for (double x = 1e-300; x < 1.0; x *= 3.7) check(1.0 - x), check(-1.0 + x), check(x);
  std::printf("acos: worst %.3f ulp at x = %a\n", worst, worst_x);
  EXPECT_LE(worst, 1.0) << "at x = " << worst_x;
}

TEST(ReproducibleMath, AcosExactValuesAndDomain) {
  EXPECT_EQ(acos(1.0), 0.0);
  EXPECT_EQ(acos(-1.0), std::acos(-1.0));  // pi rounded
  EXPECT_EQ(acos(0.0), std::acos(0.0));    // pi/2 rounded
  EXPECT_EQ(acos(-0.0), std::acos(0.0));
  EXPECT_TRUE(std::isnan(acos(std::nextafter(1.0, 2.0))));
  EXPECT_TRUE(std::isnan(acos(-1.5)));
  EXPECT_TRUE(std::isnan(acos(std::numeric_limits<double>::quiet_NaN())));
}

TEST(ReproducibleMath, SinCosAreWithinOneUlpOfTheCLibrary) {
  std::mt19937_64 gen(12);
  double worst_sin = 0.0, worst_cos = 0.0, at_sin = 0.0, at_cos = 0.0;
  auto check = [&](double x) {
    const double es = ulps(ours_sin(x), std::sin(x));
    const double ec = ulps(ours_cos(x), std::cos(x));
    if (es > worst_sin) worst_sin = es, at_sin = x;
    if (ec > worst_cos) worst_cos = ec, at_cos = x;
  };
  // the range the physics uses (half rotation angles of one step), then wider
  for (double limit : {1e-3, 1.0, 4.0, 100.0, kSinCosReducedLimit}) {
    std::uniform_real_distribution<double> uniform(-limit, limit);
    for (int i = 0; i < 300'000; ++i) check(uniform(gen));
  }
  // near the quadrant boundaries and the zeros of sin and cos
  for (int k = -64; k <= 64; ++k) {
    double x = k * (M_PI / 4);
    for (int i = 0; i < 200; ++i) check(x = std::nextafter(x, INFINITY));
  }
  for (double x = 1e-300; x < 1.0; x *= 3.7) check(x), check(-x);
  std::printf("sin: worst %.3f ulp at x = %a; cos: worst %.3f ulp at x = %a\n", worst_sin, at_sin,
              worst_cos, at_cos);
  EXPECT_LE(worst_sin, 1.0) << "at x = " << at_sin;
  EXPECT_LE(worst_cos, 1.0) << "at x = " << at_cos;
}

TEST(ReproducibleMath, SinCosSymmetryAndSpecialValues) {
  std::mt19937_64 gen(13);
  std::uniform_real_distribution<double> uniform(0.0, 50.0);
  for (int i = 0; i < 100'000; ++i) {
    const double x = uniform(gen);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(ours_sin(-x)),
              std::bit_cast<std::uint64_t>(-ours_sin(x)));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(ours_cos(-x)),
              std::bit_cast<std::uint64_t>(ours_cos(x)));
  }
  EXPECT_EQ(ours_sin(0.0), 0.0);
  EXPECT_EQ(ours_cos(0.0), 1.0);
  EXPECT_TRUE(std::signbit(ours_sin(-0.0)));
  // beyond the three-part reduction the C library answers
  for (double x : {kSinCosReducedLimit * 1.5, 1e6, -3e9, 1e300}) {
    EXPECT_EQ(ours_sin(x), std::sin(x)) << x;
    EXPECT_EQ(ours_cos(x), std::cos(x)) << x;
  }
  EXPECT_TRUE(std::isnan(ours_sin(INFINITY)));
  EXPECT_TRUE(std::isnan(ours_cos(std::numeric_limits<double>::quiet_NaN())));
}

// sinc_cos_of_square(z) against sin(r) / r and cos(r), r = sqrt(z), in long double (64-bit
// significand: 11 bits beyond a double, so the reference's own error is about 1/2000 ulp).
TEST(ReproducibleMath, SincCosOfSquareIsWithinOneUlp) {
  std::mt19937_64 gen(15);
  double worst_sinc = 0.0, worst_cos = 0.0, at_sinc = 0.0, at_cos = 0.0;
  auto check = [&](double z) {
    double sinc, cos_r;
    sinc_cos_of_square(z, sinc, cos_r);
    const long double r = std::sqrt(static_cast<long double>(z));
    const double want_sinc = z == 0.0 ? 1.0 : static_cast<double>(std::sin(r) / r);
    const double want_cos = static_cast<double>(std::cos(r));
    const double es = ulps(sinc, want_sinc), ec = ulps(cos_r, want_cos);
    if (es > worst_sinc) worst_sinc = es, at_sinc = z;
    if (ec > worst_cos) worst_cos = ec, at_cos = z;
  };
  // quat_from_rotvec's range: from its Taylor branch's end (t^2 = 5.3e-15) to the limit
  for (double limit : {1e-6, 1e-3, kSincCosSquareLimit}) {
    std::uniform_real_distribution<double> uniform(0.0, limit);
    for (int i = 0; i < 300'000; ++i) check(uniform(gen));
  }
  for (double z = 1e-300; z < kSincCosSquareLimit; z *= 3.7) check(z);
  check(0.0);
  check(kSincCosSquareLimit);
  std::printf("sinc: worst %.3f ulp at z = %a; cos: worst %.3f ulp at z = %a\n", worst_sinc,
              at_sinc, worst_cos, at_cos);
  EXPECT_LE(worst_sinc, 1.0) << "at z = " << at_sinc;
  EXPECT_LE(worst_cos, 1.0) << "at z = " << at_cos;
  EXPECT_LT(kSincCosSquareLimit, (M_PI / 4) * (M_PI / 4));  // inside the polynomials' interval
}

// The same formulas on a 2-lane vector (GCC vector extension, as the SSE2 step passes' lane type)
// give every lane the scalar function's bits.
using V2 = double __attribute__((vector_size(16)));
struct V2Ops {
  static V2 sqrt(V2 x) { return V2{std::sqrt(x[0]), std::sqrt(x[1])}; }
  static V2 abs(V2 x) { return V2{std::fabs(x[0]), std::fabs(x[1])}; }
  template <class Mask>  // lane by lane: GCC 12 cannot expand the bitwise blend here (ICE)
  static V2 select(Mask mask, V2 a, V2 b) {
    return V2{mask[0] ? a[0] : b[0], mask[1] ? a[1] : b[1]};
  }
};

TEST(ReproducibleMath, LaneVectorsGiveTheScalarBits) {
  std::mt19937_64 gen(14);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), angle(-20.0, 20.0);
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (int i = 0; i < 100'000; ++i) {
    // mixed lanes: the acos branches and the quadrants meet in one vector
    const V2 x{unit(gen), i % 7 == 0 ? 1.0 : unit(gen) * 0.6};
    const V2 a = acos<V2Ops>(x);
    const V2 r{angle(gen), angle(gen) * 1e-3};
    V2 s, c;
    sincos_reduced<V2Ops>(r, s, c);
    const V2 z{r[0] * r[0] * 1e-3, r[1] * r[1] * 1e-3};
    V2 sinc, cos_r;
    sinc_cos_of_square(z, sinc, cos_r);
    for (int k = 0; k < 2; ++k) {
      double sinc_k, cos_k;
      sinc_cos_of_square(z[k], sinc_k, cos_k);
      ASSERT_EQ(bits(sinc[k]), bits(sinc_k)) << z[k];
      ASSERT_EQ(bits(cos_r[k]), bits(cos_k)) << z[k];
      ASSERT_EQ(bits(a[k]), bits(acos(x[k]))) << x[k];
      double ss, cc;
      sincos(r[k], ss, cc);
      ASSERT_EQ(bits(s[k]), bits(ss)) << r[k];
      ASSERT_EQ(bits(c[k]), bits(cc)) << r[k];
    }
  }
}

}  // namespace
}  // namespace softevo::physics::rmath
