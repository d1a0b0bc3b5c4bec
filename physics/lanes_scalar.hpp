// Lane traits of width 1: the step passes on any CPU, with no instruction-set extension (the
// generic fallback of every architecture without wider traits; step_scalar.cpp). A lane vector is
// a GCC vector of one double, so the passes' arithmetic is the plain scalar IEEE arithmetic. The
// contract is in physics/lanes.hpp. Internal to physics/.
#pragma once

#include <cmath>

namespace softevo::physics {
namespace {

struct LanesScalar {
  static constexpr int W = 1;
  using D = double __attribute__((vector_size(8)));
  using M = long long __attribute__((vector_size(8)));
  static D round_to_float(D x) { return D{static_cast<double>(static_cast<float>(x[0]))}; }
  static D sqrt(D x) { return D{std::sqrt(x[0])}; }
  static int bits(M m) { return static_cast<int>(m[0] & 1); }
};

}  // namespace
}  // namespace softevo::physics
