// Lane utilities of the step passes, generic over the lane traits L of one instruction set
// (physics/lanes_scalar.hpp, lanes_sse2.hpp, lanes_avx2.hpp, lanes_neon.hpp). Internal to
// physics/: everything has internal linkage (anonymous namespace), so the copies that the
// step_<ISA>.cpp translation units build with different instruction sets never meet in the
// linker.
//
// Lane traits L: static constexpr int W (lanes); using D = double vector of W lanes (a GCC
// vector type: + - * / and comparisons are the IEEE operations lane by lane); using M = long long
// vector of W lanes (comparison result, all ones = true); static D round_to_float(D);
// static D sqrt(D) (IEEE, correctly rounded); static int bits(M) (bit k = lane k true);
// optionally faster transposing loads / stores (gather3, gather4, scatter3, gather_f12,
// load_records, store_records, store_float_rows, to_floats; generic fallbacks below).
//
// Every lane performs exactly the scalar IEEE operations in the written order (the build uses
// -ffp-contract=off: no fused multiply-add on any target), so every width and every instruction
// set gives the same bits.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "physics/model.hpp"
#include "physics/state.hpp"

namespace softevo::physics {
namespace {

template <class L>
using DV = typename L::D;
template <class L>
using MV = typename L::M;
template <class L>
constexpr int kAllLanes = (1 << L::W) - 1;

template <class L, class F, std::size_t... K>
[[gnu::always_inline]] inline DV<L> make_lanes(F& f, std::index_sequence<K...>) {
  return DV<L>{f(static_cast<int>(K))...};
}
// The vector whose lane k is f(k) (a double).
template <class L, class F>
[[gnu::always_inline]] inline DV<L> make_lanes(F&& f) {
  return make_lanes<L>(f, std::make_index_sequence<L::W>{});
}
template <class L>
[[gnu::always_inline]] inline DV<L> splat(double x) {
  return make_lanes<L>([x](int) { return x; });
}
template <class L>
[[gnu::always_inline]] inline DV<L> abs_lanes(DV<L> x) {  // clear the sign bit
  return reinterpret_cast<DV<L>>(reinterpret_cast<MV<L>>(x) & 0x7fffffffffffffffLL);
}
template <class L>
[[gnu::always_inline]] inline DV<L> select(MV<L> mask, DV<L> a, DV<L> b) {  // mask ? a : b
  return reinterpret_cast<DV<L>>((reinterpret_cast<MV<L>>(a) & mask) |
                                 (reinterpret_cast<MV<L>>(b) & ~mask));
}
// Lane mask with bits `on` set to all ones.
template <class L>
[[gnu::always_inline]] inline MV<L> mask_of(int on) {
  MV<L> m{};
  for (int k = 0; k < L::W; ++k) m[k] = (on >> k & 1) ? -1LL : 0LL;
  return m;
}

// Bit k set where the byte flag p[k] is non-zero, for the W consecutive flags at p: the flags as
// one word, the top bit of each byte set where the byte is non-zero ((b & 0x7f) + 0x7f carries
// into it for any b != 0), then the four top bits moved to bits 0..3 by one multiplication (the
// four shifted copies land on distinct bits, so nothing carries). Integer only: any target.
template <class L>
[[gnu::always_inline]] inline int nonzero_flags(const std::uint8_t* p) {
  static_assert(L::W <= 4);
  std::uint32_t word = 0;
  std::memcpy(&word, p, L::W);
  if constexpr (std::endian::native == std::endian::big) word = __builtin_bswap32(word);
  const std::uint32_t top = (((word & 0x7f7f7f7fu) + 0x7f7f7f7fu) | word) & 0x80808080u;
  return static_cast<int>(((top >> 7) * 0x00204081u) >> 21) & kAllLanes<L>;
}

template <class L>
struct VL {  // W Vec3
  DV<L> x, y, z;
};
template <class L>
struct QL {  // W Quat
  DV<L> w, x, y, z;
};
// Lane k of v = a scalar value (the per-lane fallback of a rare branch: floor friction).
template <class L>
[[gnu::always_inline]] inline void set_lane(VL<L>& v, int k, const Vec3& value) {
  v.x[k] = value.x();
  v.y[k] = value.y();
  v.z[k] = value.z();
}

// Transposing loads and stores between W records and lanes. Lane traits may supply faster
// versions (whole-record loads and register transposes: L::gather3, L::gather4, L::scatter3,
// L::gather_f12, L::store_float_rows, L::load_records, L::store_records,
// L::to_floats); these are the generic fallbacks. Records: 3 or 4 consecutive doubles, or 12
// consecutive floats (LinkConst, VoxelConst).
template <class L>
[[gnu::always_inline]] inline void gather3(const double* const* p, DV<L>& x, DV<L>& y, DV<L>& z) {
  if constexpr (requires { L::gather3(p, x, y, z); }) {
    L::gather3(p, x, y, z);
  } else {
    x = make_lanes<L>([&](int k) { return p[k][0]; });
    y = make_lanes<L>([&](int k) { return p[k][1]; });
    z = make_lanes<L>([&](int k) { return p[k][2]; });
  }
}
template <class L>
[[gnu::always_inline]] inline void scatter3(double* const* p, DV<L> x, DV<L> y, DV<L> z, int mask) {
  if constexpr (requires { L::scatter3(p, x, y, z, mask); }) {
    L::scatter3(p, x, y, z, mask);
  } else {
    for (int k = 0; k < L::W; ++k) {
      if (!(mask >> k & 1)) continue;
      p[k][0] = x[k];
      p[k][1] = y[k];
      p[k][2] = z[k];
    }
  }
}
// W consecutive records of N doubles at p <-> N lanes, lane k = record k (the link groups of
// consecutive ids, the voxel groups).
template <class L, int N>
[[gnu::always_inline]] inline void load_records(const double* p, DV<L> (&c)[N]) {
  if constexpr (requires { L::template load_records<N>(p, c); }) {
    L::template load_records<N>(p, c);
  } else {
    for (int j = 0; j < N; ++j) c[j] = make_lanes<L>([&](int k) { return p[N * k + j]; });
  }
}
template <class L, int N>
[[gnu::always_inline]] inline void store_records(const DV<L> (&c)[N], double* p) {
  if constexpr (requires { L::template store_records<N>(c, p); }) {
    L::template store_records<N>(c, p);
  } else {
    for (int k = 0; k < L::W; ++k)
      for (int j = 0; j < N; ++j) p[N * k + j] = c[j][k];
  }
}
// Member j of W records of 12 floats, as doubles (exact).
template <class L>
[[gnu::always_inline]] inline void gather_f12(const float* const* p, DV<L> (&out)[12]) {
  if constexpr (requires { L::gather_f12(p, out); }) {
    L::gather_f12(p, out);
  } else {
    for (int j = 0; j < 12; ++j)
      out[j] = make_lanes<L>([&](int k) { return static_cast<double>(p[k][j]); });
  }
}

// Lane k of (x, y, z) stored as the floats (x_k, y_k, z_k, 0) at out[k] (round to nearest).
template <class L>
[[gnu::always_inline]] inline void store_float_rows(DV<L> x, DV<L> y, DV<L> z, float* const* out) {
  if constexpr (requires { L::store_float_rows(x, y, z, out); }) {
    L::store_float_rows(x, y, z, out);
  } else {
    for (int k = 0; k < L::W; ++k) {
      out[k][0] = static_cast<float>(x[k]);
      out[k][1] = static_cast<float>(y[k]);
      out[k][2] = static_cast<float>(z[k]);
      out[k][3] = 0.0f;
    }
  }
}
// Lane k of x as a float (round to nearest).
template <class L>
[[gnu::always_inline]] inline void to_floats(DV<L> x, float* out) {
  if constexpr (requires { L::to_floats(x, out); }) {
    L::to_floats(x, out);
  } else {
    for (int k = 0; k < L::W; ++k) out[k] = static_cast<float>(x[k]);
  }
}

static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(Quat) == 4 * sizeof(double));
static_assert(sizeof(LinkConst) == 12 * sizeof(float) && sizeof(VoxelConst) == 12 * sizeof(float));

template <class L>
[[gnu::always_inline]] inline VL<L> gather(const std::vector<Vec3>& a, const int* id) {
  const double* p[L::W];
  for (int k = 0; k < L::W; ++k) p[k] = a[id[k]].data();
  VL<L> v;
  gather3<L>(p, v.x, v.y, v.z);
  return v;
}
template <class L>
[[gnu::always_inline]] inline QL<L> gather(const std::vector<Quat>& a, const int* id) {
  const double* p[L::W];
  for (int k = 0; k < L::W; ++k) p[k] = &a[id[k]].w;
  QL<L> q;
  if constexpr (requires { L::gather4(p, q.w, q.x, q.y, q.z); }) {
    L::gather4(p, q.w, q.x, q.y, q.z);
  } else {
    q.w = make_lanes<L>([&](int k) { return p[k][0]; });
    q.x = make_lanes<L>([&](int k) { return p[k][1]; });
    q.y = make_lanes<L>([&](int k) { return p[k][2]; });
    q.z = make_lanes<L>([&](int k) { return p[k][3]; });
  }
  return q;
}
// Records a[first .. first + W) as lanes, and back (the voxel groups: consecutive voxel ids).
template <class L>
[[gnu::always_inline]] inline VL<L> load_run(const std::vector<Vec3>& a, int first) {
  DV<L> c[3];
  load_records<L>(a[first].data(), c);
  return {c[0], c[1], c[2]};
}
template <class L>
[[gnu::always_inline]] inline QL<L> load_run(const std::vector<Quat>& a, int first) {
  DV<L> c[4];
  load_records<L>(&a[first].w, c);
  return {c[0], c[1], c[2], c[3]};
}
template <class L>
[[gnu::always_inline]] inline void store_run(const VL<L>& v, std::vector<Vec3>& a, int first) {
  const DV<L> c[3] = {v.x, v.y, v.z};
  store_records<L>(c, a[first].data());
}
template <class L>
[[gnu::always_inline]] inline void store_run(const QL<L>& q, std::vector<Quat>& a, int first) {
  const DV<L> c[4] = {q.w, q.x, q.y, q.z};
  store_records<L>(c, &a[first].w);
}
// Links ids[0..W) of a LinkVec3Columns as lanes, and back for the lanes in `mask`. With kContig
// the ids are consecutive: one vector load / store per component.
template <class L>
[[gnu::always_inline]] inline DV<L> load_lanes(const double* p) {
  DV<L> v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class L, bool kContig>
[[gnu::always_inline]] inline VL<L> gather(const LinkVec3Columns& a, const int* id) {
  if constexpr (kContig) {
    return {load_lanes<L>(&a.x[id[0]]), load_lanes<L>(&a.y[id[0]]), load_lanes<L>(&a.z[id[0]])};
  } else {
    return {make_lanes<L>([&](int k) { return a.x[id[k]]; }),
            make_lanes<L>([&](int k) { return a.y[id[k]]; }),
            make_lanes<L>([&](int k) { return a.z[id[k]]; })};
  }
}
template <class L, bool kContig>
[[gnu::always_inline]] inline void scatter(const VL<L>& v, LinkVec3Columns& a, const int* id,
                                           int mask) {
  if (kContig && mask == kAllLanes<L>) {
    std::memcpy(&a.x[id[0]], &v.x, sizeof v.x);
    std::memcpy(&a.y[id[0]], &v.y, sizeof v.y);
    std::memcpy(&a.z[id[0]], &v.z, sizeof v.z);
    return;
  }
  for (int k = 0; k < L::W; ++k) {
    if (!(mask >> k & 1)) continue;
    a.x[id[k]] = v.x[k];
    a.y[id[k]] = v.y[k];
    a.z[id[k]] = v.z[k];
  }
}

}  // namespace
}  // namespace softevo::physics
