// Known-answer and statistical tests of the deterministic RNG (common/rng.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "common/rng.hpp"

namespace softevo {

// Known answers of the published algorithms, independent of this implementation:
// SplitMix64 from state 0 gives 0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4, ... (Vigna's reference
// splitmix64.c), and xoshiro256** from the state {1, 2, 3, 4} starts 11520, 0, 1509978240,
// 1215971899390074240 (reference xoshiro256starstar.c).
TEST(Rng, SplitMix64KnownAnswers) {
  std::uint64_t s = 0;
  EXPECT_EQ(splitmix64(s), 0xE220A8397B1DCDAFULL);
  EXPECT_EQ(splitmix64(s), 0x6E789E6AA1B965F4ULL);
  EXPECT_EQ(splitmix64(s), 0x06C45D188009454FULL);
}

TEST(Rng, Xoshiro256StarStarKnownAnswers) {
  Rng rng;
  rng.set_state({1, 2, 3, 4});
  EXPECT_EQ(rng.next_u64(), 11520ULL);
  EXPECT_EQ(rng.next_u64(), 0ULL);
  EXPECT_EQ(rng.next_u64(), 1509978240ULL);
  EXPECT_EQ(rng.next_u64(), 1215971899390074240ULL);
}

TEST(Rng, SameSeedSameStreamAndStateRestores) {
  Rng a(42), b(42);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.next_u64(), b.next_u64());
  const auto saved = a.state();
  const double x = a.normal();
  a.set_state(saved);
  EXPECT_EQ(a.normal(), x);
  EXPECT_THROW(a.set_state({0, 0, 0, 0}), std::invalid_argument);
}

TEST(Rng, UniformMomentsAndRange) {
  Rng rng(7);
  const int n = 200000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sum2 += u * u;
  }
  const double mean = sum / n, var = sum2 / n - mean * mean;
  // Standard error of the mean: sqrt(1/12/n) = 6.5e-4; allow 4 standard errors.
  EXPECT_NEAR(mean, 0.5, 4 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(var, 1.0 / 12, 0.002);
}

TEST(Rng, NormalMoments) {
  Rng rng(11);
  const int n = 200000;
  double sum = 0, sum2 = 0, sum4 = 0;
  for (int i = 0; i < n; ++i) {
    const double z = rng.normal();
    sum += z;
    sum2 += z * z;
    sum4 += z * z * z * z;
  }
  EXPECT_NEAR(sum / n, 0.0, 4 / std::sqrt(n));          // SE of the mean = 1/sqrt(n)
  EXPECT_NEAR(sum2 / n, 1.0, 4 * std::sqrt(2.0 / n));   // SE of the variance
  EXPECT_NEAR(sum4 / n, 3.0, 4 * std::sqrt(96.0 / n));  // kurtosis 3, Var(z^4) = 96
}

TEST(Rng, UniformIntIsUniform) {
  Rng rng(3);
  const int n = 7, draws = 70000;
  int counts[7] = {};
  for (int i = 0; i < draws; ++i) {
    const auto k = rng.uniform_int(n);
    ASSERT_LT(k, static_cast<std::uint64_t>(n));
    ++counts[k];
  }
  // Chi-square with 6 degrees of freedom: 99.9% quantile is 22.46.
  double chi2 = 0;
  for (int c : counts) chi2 += (c - draws / 7.0) * (c - draws / 7.0) / (draws / 7.0);
  EXPECT_LT(chi2, 22.46);
  EXPECT_THROW(rng.uniform_int(0), std::invalid_argument);
}

TEST(Rng, DeriveSeedKnownValuesAndIndependence) {
  // Golden values: derive_seed is part of the archive contract (a changed function changes
  // every run), so its outputs are pinned. Computed independently with a few lines of Python
  // implementing the documented SplitMix64 chain.
  EXPECT_EQ(derive_seed(1, 0, 0, -1), derive_seed(1, 0, 0, -1));
  EXPECT_NE(derive_seed(1, 0, 0, -1), derive_seed(1, 0, 0, 0));
  EXPECT_NE(derive_seed(1, 0, 1, 0), derive_seed(1, 1, 0, 0));
  EXPECT_NE(derive_seed(1, 2, 3, 4), derive_seed(2, 2, 3, 4));
  EXPECT_EQ(derive_seed(1, 2, 3, 4), 0xD55CCD4AEB3CCAFBULL);
  EXPECT_EQ(derive_seed(1, 0, 0, -1), 0xE0C5016D2DD30D35ULL);
}

}  // namespace softevo
