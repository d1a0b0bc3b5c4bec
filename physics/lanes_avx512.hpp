// Lane traits of 8 doubles in a 512-bit vector (contract: physics/lanes.hpp), for the batched
// step's passes in step_avx512.cpp (physics/batch_kernels.hpp: lane k = evaluation k). The
// one-robot passes of that file stay 4 lanes wide (lanes_avx2.hpp): over the links of one robot
// 8 lanes gained nothing (docs/scaling.md). Internal to physics/.
#pragma once

#if !defined(__AVX512F__) || (defined(__FMA__) && !defined(__clang__))
#error "lanes_avx512.hpp needs -mavx512f and, with GCC, no FMA (see physics/CMakeLists.txt)"
#endif
#include <immintrin.h>

namespace softevo::physics {
namespace {

struct LanesAvx512 {
  static constexpr int W = 8;
  using D = double __attribute__((vector_size(64)));
  using M = long long __attribute__((vector_size(64)));
  using F = float __attribute__((vector_size(32)));
  // round to nearest float and back (vcvtpd2ps, vcvtps2pd); written as conversions of GCC
  // vectors because GCC 12's _mm512_cvtpd_ps passes an undefined vector it then warns about
  static D round_to_float(D x) { return __builtin_convertvector(__builtin_convertvector(x, F), D); }
  // vsqrtpd, correctly rounded (with GCC the builtin: the intrinsic's undefined pass-through
  // warns as above)
  static D sqrt(D x) {
#if defined(__clang__)
    return _mm512_sqrt_pd(x);
#else
    return __builtin_ia32_sqrtpd512_mask(x, x, static_cast<__mmask8>(-1), _MM_FROUND_CUR_DIRECTION);
#endif
  }
  static int bits(M m) {
    return _mm512_cmplt_epi64_mask(reinterpret_cast<__m512i>(m), _mm512_setzero_si512());
  }
};

}  // namespace
}  // namespace softevo::physics
