// Lane traits of the 2-lane step passes on AArch64 (Advanced SIMD / NEON, float64x2: part of every
// AArch64 CPU), for step_neon.cpp. The contract is in physics/lanes.hpp. Internal to physics/.
//
// No fused multiply-add: the passes write products and sums as separate vector operations
// (GCC's vmulq_f64 / vaddq_f64 are those operators too), and -ffp-contract=off keeps the compiler
// from fusing them into fmla / fmls; tools/bootstrap.sh aarch64 checks the object for fused
// instructions.
#pragma once

#if !defined(__aarch64__) || !defined(__ARM_NEON)
#error "lanes_neon.hpp needs an AArch64 target; physics/CMakeLists.txt builds it only there"
#endif
#include <arm_neon.h>

namespace softevo::physics {
namespace {

struct LanesNeon {
  static constexpr int W = 2;
  using D = double __attribute__((vector_size(16)));
  using M = long long __attribute__((vector_size(16)));
  static float64x2_t neon(D x) { return reinterpret_cast<float64x2_t>(x); }
  static D lanes(float64x2_t x) { return reinterpret_cast<D>(x); }
  static D round_to_float(D x) { return lanes(vcvt_f64_f32(vcvt_f32_f64(neon(x)))); }
  static D sqrt(D x) { return lanes(vsqrtq_f64(neon(x))); }
  static int bits(M m) {
    const uint64x2_t top = vshrq_n_u64(reinterpret_cast<uint64x2_t>(m), 63);  // 1 where true
    return static_cast<int>(vgetq_lane_u64(top, 0) | vgetq_lane_u64(top, 1) << 1);
  }
  // W = 2 consecutive records of N doubles at p <-> N lanes (lane k = record k): the
  // de-interleaving structure loads / stores (3 and 4 members; others: generic).
  template <int N>
  requires(N == 3 || N == 4) static void load_records(const double* p, D (&c)[N]) {
    if constexpr (N == 3) {
      const float64x2x3_t r = vld3q_f64(p);
      for (int j = 0; j < 3; ++j) c[j] = lanes(r.val[j]);
    } else {
      const float64x2x4_t r = vld4q_f64(p);
      for (int j = 0; j < 4; ++j) c[j] = lanes(r.val[j]);
    }
  }
  template <int N>
  requires(N == 3 || N == 4) static void store_records(const D (&c)[N], double* p) {
    if constexpr (N == 3) {
      vst3q_f64(p, float64x2x3_t{{neon(c[0]), neon(c[1]), neon(c[2])}});
    } else {
      vst4q_f64(p, float64x2x4_t{{neon(c[0]), neon(c[1]), neon(c[2]), neon(c[3])}});
    }
  }
};

}  // namespace
}  // namespace softevo::physics
