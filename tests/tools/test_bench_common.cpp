// tools/bench_common.hpp: the OS's clock figure read from /proc/cpuinfo for the cross-check of
// `softevo bench physics --cycles`, and the measured clock's basic sanity (positive, finite;
// never a range: tests assume no machine's speed).
#include "tools/bench_common.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

namespace softevo::cli {
namespace {

const char* const kTwoCpus =
    "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu MHz\t\t: 2596.096\n\n"
    "processor\t: 1\nvendor_id\t: AuthenticAMD\ncpu MHz\t\t: 3100.5\n\n";

TEST(BenchCommon, CpuinfoGivesTheClockOfTheNamedProcessor) {
  std::istringstream first(kTwoCpus);
  EXPECT_DOUBLE_EQ(cpuinfo_clock_hz(first, 0).value(), 2596.096e6);
  std::istringstream second(kTwoCpus);
  EXPECT_DOUBLE_EQ(cpuinfo_clock_hz(second, 1).value(), 3100.5e6);
}

TEST(BenchCommon, CpuinfoWithoutAFigureGivesNothing) {
  std::istringstream missing_cpu(kTwoCpus);
  EXPECT_FALSE(cpuinfo_clock_hz(missing_cpu, 2).has_value());
  // AArch64 kernels print no "cpu MHz"
  std::istringstream arm("processor\t: 0\nBogoMIPS\t: 50.00\nFeatures\t: fp asimd\n");
  EXPECT_FALSE(cpuinfo_clock_hz(arm, 0).has_value());
  std::istringstream garbage("processor\t: x\ncpu MHz\t: -3\ncpu MHz : nan\n");
  EXPECT_FALSE(cpuinfo_clock_hz(garbage, 0).has_value());
}

#if defined(__x86_64__) || defined(__aarch64__)
TEST(BenchCommon, TheMeasuredClockIsAPositiveFiniteRate) {
  const double hz = measure_core_clock_hz(0.005, 2).value();
  EXPECT_TRUE(std::isfinite(hz) && hz > 0.0) << hz;
}
#endif

}  // namespace
}  // namespace softevo::cli
