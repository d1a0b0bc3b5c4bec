// physics/link_mode.hpp: the division-free mode test of the SIMD link passes decides exactly as
// the reference's float test (§2.3 step 3) wherever it decides, including inputs a few ulps from
// every threshold, and leaves only such near-threshold or NaN links undecided.
#include "physics/link_mode.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "physics/reproducible_math.hpp"

namespace softevo::physics::link_mode {
namespace {

// The reference's test (physics/link_lanes.hpp lanes_keeping_mode, when the products do not
// decide): true if the link leaves its mode.
bool exact_switches(bool large, double dx, double dy, double dz, double l) {
  const float turn = static_cast<float>((std::fabs(dz) + std::fabs(dy)) / dx);
  const float ext = static_cast<float>(std::fabs(1 - dx / l));
  if (large) return turn < kSmallBend && ext < kSmallExt;
  return turn > kHysteresis * kSmallBend || ext > kHysteresis * kSmallExt;
}

struct Tally {
  long cases = 0, decided = 0;
};

// Checks one input in both modes; counts the decided ones.
void check(double dx, double dy, double dz, double l, Tally& tally) {
  const double inv_l = 1.0 / l;
  for (const bool large : {false, true}) {
    const auto got = large ? test_without_division<true, rmath::ScalarOps>(dx, dy, dz, inv_l)
                           : test_without_division<false, rmath::ScalarOps>(dx, dy, dz, inv_l);
    ++tally.cases;
    if (!got.decided) continue;
    ++tally.decided;
    ASSERT_EQ(static_cast<bool>(got.switches), exact_switches(large, dx, dy, dz, l))
        << (large ? "large" : "small") << " mode, d = (" << dx << ", " << dy << ", " << dz
        << "), L = " << l;
  }
}

// Values of q a few ulps (double) and a few float ulps around a threshold t.
std::vector<double> around(double t) {
  std::vector<double> q;
  for (const double rel : {0.0, 0x1p-52, 0x1p-40, 0x1p-30, 0x1p-25, 0x1p-24, 0x1p-23, 0x1p-22,
                           0x1p-21, 0x1p-20, 0x1p-19, 0x1p-10}) {
    q.push_back(t * (1.0 + rel));
    q.push_back(t * (1.0 - rel));
  }
  double up = t, down = t;
  for (int k = 0; k < 8; ++k) {
    up = std::nextafter(up, INFINITY);
    down = std::nextafter(down, 0.0);
    q.push_back(up);
    q.push_back(down);
  }
  // the float midpoints next to t, where float(q) changes
  const float tf = static_cast<float>(t);
  for (const float f : {std::nextafter(tf, INFINITY), std::nextafter(tf, 0.0f)}) {
    const double mid = 0.5 * (static_cast<double>(tf) + static_cast<double>(f));
    for (int k = -3; k <= 3; ++k) q.push_back(mid + k * std::fabs(mid) * 0x1p-52);
  }
  return q;
}

TEST(LinkMode, DecidesAsTheFloatTestNearEveryThreshold) {
  Tally tally;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const double l : {0.01, 0.0123, 1.0, 3.7e-3}) {
    // turn = (|dz| + |dy|) / dx at each turn threshold, ext well inside
    for (const double t :
         {static_cast<double>(kSmallBend), static_cast<double>(kHysteresis * kSmallBend)}) {
      for (const double q : around(t)) {
        const double dx = l * (1.0 + 0.2 * (unit(rng) - 0.5));
        const double share = unit(rng);
        const double num = q * dx;
        check(dx, share * num, -(1.0 - share) * num, l, tally);
        check(dx, num, 0.0, l, tally);
      }
    }
    // ext = |1 - dx / L| at each ext threshold, both signs, turn small
    for (const double e :
         {static_cast<double>(kSmallExt), static_cast<double>(kHysteresis * kSmallExt)}) {
      for (const double q : around(e)) {
        for (const double sign : {1.0, -1.0}) {
          const double dx = l * (1.0 + sign * q);
          check(dx, 1e-3 * dx, 0.0, l, tally);
        }
      }
    }
  }
  // random links, and the special values
  for (int k = 0; k < 200000; ++k) {
    const double l = 0.01;
    const double dx = l * (2.0 * unit(rng) - 0.5), dy = 0.2 * l * (unit(rng) - 0.5),
                 dz = 0.2 * l * (unit(rng) - 0.5);
    check(dx, dy, dz, l, tally);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = INFINITY;
  for (const double dx : {0.0, -0.0, -0.01, 0.01, nan, inf, -inf, 1e300, 5e-324})
    for (const double dy : {0.0, 1e-3, nan, inf, -1e300})
      for (const double dz : {0.0, -2e-3, nan, inf}) check(dx, dy, dz, 0.01, tally);
  std::printf("mode test: %ld of %ld cases decided without division, all as the float test\n",
              tally.decided, tally.cases);
  EXPECT_GT(tally.decided, tally.cases / 2);
}

template <bool kLarge>
auto test(double dx, double dy, double dz, double inv_l) {
  return test_without_division<kLarge, rmath::ScalarOps>(dx, dy, dz, inv_l);
}

TEST(LinkMode, UndecidedOnlyNearThresholdsOrForNaN) {
  const double l = 0.01, inv_l = 1.0 / l;
  // a typical small bend and stretch: decided in both modes
  EXPECT_TRUE(test<false>(l * 1.01, 1e-4, 0.0, inv_l).decided);
  EXPECT_TRUE(test<true>(l * 1.01, 1e-4, 0.0, inv_l).decided);
  // exactly at the threshold: left to the division
  const double t = static_cast<double>(kSmallBend);
  EXPECT_FALSE(test<true>(l, t * l, 0.0, inv_l).decided);
  // NaN: undecided
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(test<true>(nan, 0.0, 0.0, inv_l).decided);
  EXPECT_FALSE(test<false>(l, nan, 0.0, inv_l).decided);
  // d_x <= 0: the turn comparison is not taken from products, but ext = |1 - d_x / L| >= 1 is
  // above both ext thresholds, which decides: large-angle mode stays (the float test's turn is
  // NaN or negative, and ext >= 1 fails ext < kSmallExt), small-angle mode is left
  const auto zero = test<true>(-0.0, 0.0, 0.0, inv_l);
  EXPECT_TRUE(zero.decided);
  EXPECT_FALSE(zero.switches);
  const auto back = test<false>(-l, 0.0, 0.0, inv_l);
  EXPECT_TRUE(back.decided);
  EXPECT_TRUE(back.switches);
}

// A lane vector decides lane by lane as the scalar code does (the form the SIMD passes use).
struct LaneOps {
  using D = double __attribute__((vector_size(16)));
  static D abs(D x) {
    using M = long long __attribute__((vector_size(16)));
    return reinterpret_cast<D>(reinterpret_cast<M>(x) & 0x7fffffffffffffffLL);
  }
};
TEST(LinkMode, LanesDecideAsScalars) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double l = 0.01, inv_l = 1.0 / l;
  for (int k = 0; k < 20000; ++k) {
    LaneOps::D dx, dy, dz;
    for (int j = 0; j < 2; ++j) {
      dx[j] = l * (2.0 * unit(rng) - 0.5);
      dy[j] = 0.2 * l * (unit(rng) - 0.5);
      dz[j] = 0.2 * l * (unit(rng) - 0.5);
    }
    const auto lanes = test_without_division<false, LaneOps>(dx, dy, dz, inv_l);
    for (int j = 0; j < 2; ++j) {
      const auto one = test_without_division<false, rmath::ScalarOps>(dx[j], dy[j], dz[j], inv_l);
      ASSERT_EQ(lanes.decided[j] != 0, static_cast<bool>(one.decided));
      ASSERT_EQ(lanes.switches[j] != 0, static_cast<bool>(one.switches));
    }
  }
}

}  // namespace
}  // namespace softevo::physics::link_mode
