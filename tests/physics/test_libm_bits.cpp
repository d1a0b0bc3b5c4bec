// The C library's functions that the evaluation outside physics/ calls (worker/: sin and cos of
// the controller's oscillator phase and of the target direction, acos of the heading and
// direction terms) must give the same bits on every platform softevo
// supports: a hash of their results over many arguments of the ranges they see is pinned here
// from x86-64 (glibc 2.36, Debian 12; the same with glibc's FMA variants turned off) and checked
// on AArch64 by `tools/bootstrap.sh aarch64` (under qemu). The physics itself uses its own
// reproducible functions (physics/reproducible_math.hpp) and does not depend on these.
//
// The Elman network's tanh is not the C library's (glibc's tanhf differs between x86-64 and
// AArch64): softevo computes it itself, tests/worker/test_elman_tanh.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/bit_hash.hpp"

namespace {

using softevo::test::hash_double;

// The oscillator phase (simulation.cpp) and the direction angle (fitness.cpp): sin and cos over
// a few turns.
TEST(LibmBits, SinAndCosOfDoubles) {
  const std::string s = hash_double(-30.0, 30.0, [](double x) { return std::sin(x); });
  const std::string c = hash_double(-30.0, 30.0, [](double x) { return std::cos(x); });
  std::printf("sin %s, cos %s\n", s.c_str(), c.c_str());
  EXPECT_EQ(s, "e78a987c6f5446a9");
  EXPECT_EQ(c, "d585e67bcc24a159");
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
