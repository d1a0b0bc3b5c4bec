// Lane traits of the 4-lane step passes (contract: physics/lanes.hpp), for the translation units
// built with AVX2 (step_avx2.cpp) and with AVX-512VL (step_avx512.cpp: the same 256-bit
// operations, encoded with 32 vector registers instead of 16). Internal to physics/.
#pragma once

// No FMA instructions with GCC; clang cannot leave them out of AVX-512 and relies on
// -ffp-contract=off (physics/CMakeLists.txt).
#if !defined(__AVX2__) || (defined(__FMA__) && !defined(__clang__))
#error "lanes_avx2.hpp needs -mavx2 and, with GCC, no FMA (see physics/CMakeLists.txt)"
#endif
#include <immintrin.h>

namespace softevo::physics {
namespace {

struct LanesAvx2 {
  static constexpr int W = 4;
  using D = double __attribute__((vector_size(32)));
  using M = long long __attribute__((vector_size(32)));
  static D round_to_float(D x) { return _mm256_cvtps_pd(_mm256_cvtpd_ps(x)); }
  static D sqrt(D x) { return _mm256_sqrt_pd(x); }
  static int bits(M m) { return _mm256_movemask_pd(reinterpret_cast<__m256d>(m)); }
  static void to_floats(D x, float* out) { _mm_storeu_ps(out, _mm256_cvtpd_ps(x)); }
  // Lane k of (x, y, z) as the floats (x_k, y_k, z_k, 0) at out[k], k = 0..3 (round to nearest).
  static void store_float_rows(D x, D y, D z, float* const* out) {
    __m128 r0 = _mm256_cvtpd_ps(x), r1 = _mm256_cvtpd_ps(y), r2 = _mm256_cvtpd_ps(z);
    __m128 r3 = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    _mm_storeu_ps(out[0], r0);
    _mm_storeu_ps(out[1], r1);
    _mm_storeu_ps(out[2], r2);
    _mm_storeu_ps(out[3], r3);
  }
  // Transposing record loads / stores (see physics/lanes.hpp). A Vec3 record is read and written
  // with a 3-lane mask, so nothing beyond it is touched.
  static __m256i mask3() { return _mm256_setr_epi64x(-1, -1, -1, 0); }
  static void gather3(const double* const* p, D& x, D& y, D& z) {
    const __m256i m = mask3();
    const __m256d r0 = _mm256_maskload_pd(p[0], m), r1 = _mm256_maskload_pd(p[1], m);
    const __m256d r2 = _mm256_maskload_pd(p[2], m), r3 = _mm256_maskload_pd(p[3], m);
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1);  // x0 x1 z0 z1
    const __m256d t1 = _mm256_unpackhi_pd(r0, r1);  // y0 y1 .. ..
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3);  // x2 x3 z2 z3
    const __m256d t3 = _mm256_unpackhi_pd(r2, r3);  // y2 y3 .. ..
    x = _mm256_permute2f128_pd(t0, t2, 0x20);
    y = _mm256_permute2f128_pd(t1, t3, 0x20);
    z = _mm256_permute2f128_pd(t0, t2, 0x31);
  }
  static void gather4(const double* const* p, D& w, D& x, D& y, D& z) {
    const __m256d r0 = _mm256_loadu_pd(p[0]), r1 = _mm256_loadu_pd(p[1]);
    const __m256d r2 = _mm256_loadu_pd(p[2]), r3 = _mm256_loadu_pd(p[3]);
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1);  // w0 w1 y0 y1
    const __m256d t1 = _mm256_unpackhi_pd(r0, r1);  // x0 x1 z0 z1
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3);
    const __m256d t3 = _mm256_unpackhi_pd(r2, r3);
    w = _mm256_permute2f128_pd(t0, t2, 0x20);
    y = _mm256_permute2f128_pd(t0, t2, 0x31);
    x = _mm256_permute2f128_pd(t1, t3, 0x20);
    z = _mm256_permute2f128_pd(t1, t3, 0x31);
  }
  static void scatter3(double* const* p, D x, D y, D z, int mask) {
    const __m256d t0 = _mm256_unpacklo_pd(x, y);  // x0 y0 x2 y2
    const __m256d t1 = _mm256_unpackhi_pd(x, y);  // x1 y1 x3 y3
    const __m256d t2 = _mm256_unpacklo_pd(z, z);  // z0 z0 z2 z2
    const __m256d t3 = _mm256_unpackhi_pd(z, z);  // z1 z1 z3 z3
    const __m256i m = mask3();
    if (mask & 1) _mm256_maskstore_pd(p[0], m, _mm256_permute2f128_pd(t0, t2, 0x20));
    if (mask & 2) _mm256_maskstore_pd(p[1], m, _mm256_permute2f128_pd(t1, t3, 0x20));
    if (mask & 4) _mm256_maskstore_pd(p[2], m, _mm256_permute2f128_pd(t0, t2, 0x31));
    if (mask & 8) _mm256_maskstore_pd(p[3], m, _mm256_permute2f128_pd(t1, t3, 0x31));
  }
  // W = 4 consecutive records of N doubles at p <-> N lanes (lane k = record k).
  template <int N>
  static void load_records(const double* p, D (&c)[N]) {
    if constexpr (N == 3) {  // x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3
      const __m256d r0 = _mm256_loadu_pd(p), r1 = _mm256_loadu_pd(p + 4);
      const __m256d r2 = _mm256_loadu_pd(p + 8);
      const __m256d a = _mm256_blend_pd(r0, r1, 0b1100);       // x0 y0 x2 y2
      const __m256d b = _mm256_permute2f128_pd(r0, r2, 0x21);  // z0 x1 z2 x3
      const __m256d d = _mm256_blend_pd(r1, r2, 0b1100);       // y1 z1 y3 z3
      c[0] = _mm256_shuffle_pd(a, b, 0b1010);
      c[1] = _mm256_shuffle_pd(a, d, 0b0101);
      c[2] = _mm256_shuffle_pd(b, d, 0b1010);
    } else {
      static_assert(N % 4 == 0);
      for (int j = 0; j < N; j += 4) {  // a 4 x 4 transpose per block of four members
        const __m256d r0 = _mm256_loadu_pd(p + j), r1 = _mm256_loadu_pd(p + N + j);
        const __m256d r2 = _mm256_loadu_pd(p + 2 * N + j), r3 = _mm256_loadu_pd(p + 3 * N + j);
        const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
        const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
        c[j] = _mm256_permute2f128_pd(t0, t2, 0x20);
        c[j + 1] = _mm256_permute2f128_pd(t1, t3, 0x20);
        c[j + 2] = _mm256_permute2f128_pd(t0, t2, 0x31);
        c[j + 3] = _mm256_permute2f128_pd(t1, t3, 0x31);
      }
    }
  }
  template <int N>
  static void store_records(const D (&c)[N], double* p) {
    if constexpr (N == 3) {
      const __m256d a = _mm256_unpacklo_pd(c[0], c[1]);         // x0 y0 x2 y2
      const __m256d b = _mm256_shuffle_pd(c[2], c[0], 0b1010);  // z0 x1 z2 x3
      const __m256d d = _mm256_unpackhi_pd(c[1], c[2]);         // y1 z1 y3 z3
      _mm256_storeu_pd(p, _mm256_permute2f128_pd(a, b, 0x20));
      _mm256_storeu_pd(p + 4, _mm256_blend_pd(d, a, 0b1100));
      _mm256_storeu_pd(p + 8, _mm256_permute2f128_pd(b, d, 0x31));
    } else {
      static_assert(N % 4 == 0);
      for (int j = 0; j < N; j += 4) {
        const __m256d t0 = _mm256_unpacklo_pd(c[j], c[j + 1]);      // a0 b0 a2 b2
        const __m256d t1 = _mm256_unpackhi_pd(c[j], c[j + 1]);      // a1 b1 a3 b3
        const __m256d t2 = _mm256_unpacklo_pd(c[j + 2], c[j + 3]);  // c0 d0 c2 d2
        const __m256d t3 = _mm256_unpackhi_pd(c[j + 2], c[j + 3]);  // c1 d1 c3 d3
        _mm256_storeu_pd(p + j, _mm256_permute2f128_pd(t0, t2, 0x20));
        _mm256_storeu_pd(p + N + j, _mm256_permute2f128_pd(t1, t3, 0x20));
        _mm256_storeu_pd(p + 2 * N + j, _mm256_permute2f128_pd(t0, t2, 0x31));
        _mm256_storeu_pd(p + 3 * N + j, _mm256_permute2f128_pd(t1, t3, 0x31));
      }
    }
  }
  static void gather_f12(const float* const* p, D (&out)[12]) {
    for (int b = 0; b < 3; ++b) {
      __m128 r0 = _mm_loadu_ps(p[0] + 4 * b), r1 = _mm_loadu_ps(p[1] + 4 * b);
      __m128 r2 = _mm_loadu_ps(p[2] + 4 * b), r3 = _mm_loadu_ps(p[3] + 4 * b);
      _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
      out[4 * b] = _mm256_cvtps_pd(r0);
      out[4 * b + 1] = _mm256_cvtps_pd(r1);
      out[4 * b + 2] = _mm256_cvtps_pd(r2);
      out[4 * b + 3] = _mm256_cvtps_pd(r3);
    }
  }
};

}  // namespace
}  // namespace softevo::physics
