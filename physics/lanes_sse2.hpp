// Lane traits of the 2-lane step passes on x86-64 (SSE2, part of every x86-64 CPU), for
// step_sse2.cpp. The contract is in physics/lanes.hpp. Internal to physics/.
#pragma once

#if !defined(__SSE2__)
#error "lanes_sse2.hpp needs an SSE2 target (x86-64); physics/CMakeLists.txt builds it only there"
#endif
#include <emmintrin.h>

namespace softevo::physics {
namespace {

struct LanesSse2 {
  static constexpr int W = 2;
  using D = double __attribute__((vector_size(16)));
  using M = long long __attribute__((vector_size(16)));
  static D round_to_float(D x) { return _mm_cvtps_pd(_mm_cvtpd_ps(x)); }
  static D sqrt(D x) { return _mm_sqrt_pd(x); }
  static int bits(M m) { return _mm_movemask_pd(reinterpret_cast<__m128d>(m)); }
  // Lane k of (x, y, z) as the floats (x_k, y_k, z_k, 0) at out[k], k = 0..1 (round to nearest).
  static void store_float_rows(D x, D y, D z, float* const* out) {
    const __m128 xy = _mm_unpacklo_ps(_mm_cvtpd_ps(x), _mm_cvtpd_ps(y));   // x0 y0 x1 y1
    const __m128 z0 = _mm_unpacklo_ps(_mm_cvtpd_ps(z), _mm_setzero_ps());  // z0 0 z1 0
    _mm_storeu_ps(out[0], _mm_movelh_ps(xy, z0));
    _mm_storeu_ps(out[1], _mm_movehl_ps(z0, xy));
  }
  // Transposing record loads / stores (see physics/lanes.hpp).
  static void gather3(const double* const* p, D& x, D& y, D& z) {
    const __m128d r0 = _mm_loadu_pd(p[0]), r1 = _mm_loadu_pd(p[1]);
    x = _mm_unpacklo_pd(r0, r1);
    y = _mm_unpackhi_pd(r0, r1);
    z = _mm_loadh_pd(_mm_load_sd(p[0] + 2), p[1] + 2);
  }
  static void gather4(const double* const* p, D& w, D& x, D& y, D& z) {
    const __m128d a0 = _mm_loadu_pd(p[0]), a1 = _mm_loadu_pd(p[1]);
    const __m128d b0 = _mm_loadu_pd(p[0] + 2), b1 = _mm_loadu_pd(p[1] + 2);
    w = _mm_unpacklo_pd(a0, a1);
    x = _mm_unpackhi_pd(a0, a1);
    y = _mm_unpacklo_pd(b0, b1);
    z = _mm_unpackhi_pd(b0, b1);
  }
  static void scatter3(double* const* p, D x, D y, D z, int mask) {
    if (mask & 1) {
      _mm_storeu_pd(p[0], _mm_unpacklo_pd(x, y));
      _mm_store_sd(p[0] + 2, z);
    }
    if (mask & 2) {
      _mm_storeu_pd(p[1], _mm_unpackhi_pd(x, y));
      _mm_storeh_pd(p[1] + 2, z);
    }
  }
  // W = 2 consecutive records of N doubles at p <-> N lanes (lane k = record k).
  template <int N>
  static void load_records(const double* p, D (&c)[N]) {
    if constexpr (N == 3) {  // x0 y0 | z0 x1 | y1 z1
      const __m128d r0 = _mm_loadu_pd(p), r1 = _mm_loadu_pd(p + 2), r2 = _mm_loadu_pd(p + 4);
      c[0] = _mm_shuffle_pd(r0, r1, 0b10);
      c[1] = _mm_shuffle_pd(r0, r2, 0b01);
      c[2] = _mm_shuffle_pd(r1, r2, 0b10);
    } else {
      static_assert(N % 2 == 0);
      for (int j = 0; j < N; j += 2) {
        const __m128d r0 = _mm_loadu_pd(p + j), r1 = _mm_loadu_pd(p + N + j);
        c[j] = _mm_unpacklo_pd(r0, r1);
        c[j + 1] = _mm_unpackhi_pd(r0, r1);
      }
    }
  }
  template <int N>
  static void store_records(const D (&c)[N], double* p) {
    if constexpr (N == 3) {
      _mm_storeu_pd(p, _mm_unpacklo_pd(c[0], c[1]));
      _mm_storeu_pd(p + 2, _mm_shuffle_pd(c[2], c[0], 0b10));
      _mm_storeu_pd(p + 4, _mm_unpackhi_pd(c[1], c[2]));
    } else {
      static_assert(N % 2 == 0);
      for (int j = 0; j < N; j += 2) {
        _mm_storeu_pd(p + j, _mm_unpacklo_pd(c[j], c[j + 1]));
        _mm_storeu_pd(p + N + j, _mm_unpackhi_pd(c[j], c[j + 1]));
      }
    }
  }
  static void gather_f12(const float* const* p, D (&out)[12]) {
    for (int b = 0; b < 3; ++b) {
      const __m128 va = _mm_loadu_ps(p[0] + 4 * b), vb = _mm_loadu_ps(p[1] + 4 * b);
      const __m128 lo = _mm_unpacklo_ps(va, vb), hi = _mm_unpackhi_ps(va, vb);
      out[4 * b] = _mm_cvtps_pd(lo);
      out[4 * b + 1] = _mm_cvtps_pd(_mm_movehl_ps(lo, lo));
      out[4 * b + 2] = _mm_cvtps_pd(hi);
      out[4 * b + 3] = _mm_cvtps_pd(_mm_movehl_ps(hi, hi));
    }
  }
};

}  // namespace
}  // namespace softevo::physics
