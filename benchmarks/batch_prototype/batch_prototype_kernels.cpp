// The prototype's batched passes (batch_prototype.hpp): the formulas of physics/link_lanes.hpp and
// physics/voxel_pass.hpp, lane k = evaluation k of the same Model. A link's two end voxels are
// plain vector loads at the same index for every lane; constants are broadcast; what differs per
// lane (link mode, damping validity, floor contact) is masked per lane. Built with AVX-512 (and
// no FMA, as the physics), internal linkage like the physics' own step_<ISA>.cpp.
#if !defined(__AVX512F__)
#error "batch_prototype_kernels.cpp must be compiled with -mavx512f"
#endif
// GCC 12 reports its own AVX-512 intrinsics' undefined pass-through operand (_mm512_undefined_pd)
// as maybe uninitialized once inlined
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#include <immintrin.h>

#include <cmath>
#include <cstring>

#include "benchmarks/batch_prototype/batch_prototype.hpp"
#include "physics/floor_contact.hpp"
#include "physics/lane_math.hpp"
#include "physics/lanes.hpp"
#include "physics/lanes_avx2.hpp"
#include "physics/lanes_scalar.hpp"
#include "physics/link_lanes.hpp"

namespace softevo::physics {
namespace {

// 8 doubles of a 512-bit vector (the contract of physics/lanes.hpp).
struct Lanes8 {
  static constexpr int W = 8;
  using D = double __attribute__((vector_size(64)));
  using M = long long __attribute__((vector_size(64)));
  static D round_to_float(D x) { return _mm512_cvtps_pd(_mm512_cvtpd_ps(x)); }
  static D sqrt(D x) { return _mm512_sqrt_pd(x); }
  static int bits(M m) {
    return _mm512_cmplt_epi64_mask(reinterpret_cast<__m512i>(m), _mm512_setzero_si512());
  }
};

template <class L>
[[gnu::always_inline]] inline DV<L> ld(const double* p) {
  DV<L> v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class L>
[[gnu::always_inline]] inline void st(double* p, DV<L> v) {
  std::memcpy(p, &v, sizeof v);
}
// Store the lanes in `mask` only.
template <class L>
[[gnu::always_inline]] inline void st_masked(double* p, DV<L> v, int mask) {
  if (mask == kAllLanes<L>) {
    st<L>(p, v);
  } else if (mask) {
    if constexpr (L::W == 8) {
      _mm512_mask_storeu_pd(p, static_cast<__mmask8>(mask), v);
    } else {
      for (int k = 0; k < L::W; ++k)
        if (mask >> k & 1) p[k] = v[k];
    }
  }
}
template <class L>
[[gnu::always_inline]] inline VL<L> ld3(const std::vector<double>& a, int i) {
  const double* p = a.data() + static_cast<std::size_t>(i) * 3 * L::W;
  return {ld<L>(p), ld<L>(p + L::W), ld<L>(p + 2 * L::W)};
}
template <class L>
[[gnu::always_inline]] inline void st3(std::vector<double>& a, int i, const VL<L>& v, int mask) {
  double* p = a.data() + static_cast<std::size_t>(i) * 3 * L::W;
  st_masked<L>(p, v.x, mask);
  st_masked<L>(p + L::W, v.y, mask);
  st_masked<L>(p + 2 * L::W, v.z, mask);
}
template <class L>
[[gnu::always_inline]] inline QL<L> ld4(const std::vector<double>& a, int i) {
  const double* p = a.data() + static_cast<std::size_t>(i) * 4 * L::W;
  return {ld<L>(p), ld<L>(p + L::W), ld<L>(p + 2 * L::W), ld<L>(p + 3 * L::W)};
}
// Bit k set where byte p[k] is non-zero (k < W).
template <class L>
[[gnu::always_inline]] inline int flag_bits(const std::uint8_t* p) {
  std::uint64_t word = 0;
  std::memcpy(&word, p, L::W);
  const __m128i v = _mm_cvtsi64_si128(static_cast<long long>(word));
  return ~_mm_movemask_epi8(_mm_cmpeq_epi8(v, _mm_setzero_si128())) & kAllLanes<L>;
}
template <class L>
[[gnu::always_inline]] inline void set_flags(std::uint8_t* p, int mask, std::uint8_t value) {
  for (int k = 0; k < L::W; ++k)
    if (mask >> k & 1) p[k] = value;
}

using batch_prototype::Batch;

// orient_links of link i (§2.3), lanes = evaluations.
template <class L, Axis A>
[[gnu::always_inline]] inline LinkFrameL<L> orient_link(const Model& m, const Batch& b, int i) {
  const int n = m.link_neg[i], p = m.link_pos[i];
  const VL<L> pn = ld3<L>(b.pos, n), pp = ld3<L>(b.pos, p);
  const VL<L> d0 = to_x_lanes<A, L>(pp.x - pn.x, pp.y - pn.y, pp.z - pn.z);
  const QL<L> qn = to_x_lanes<A, L>(ld4<L>(b.orient, n));
  const QL<L> r{qn.w, -qn.x, -qn.y, -qn.z};
  LinkFrameL<L> f;
  rotate_c(r.w, r.x, r.y, r.z, d0.x, d0.y, d0.z, f.d.x, f.d.y, f.d.z);
  const QL<L> qp = to_x_lanes<A, L>(ld4<L>(b.orient, p));
  mul_c(r.w, r.x, r.y, r.z, qp.w, qp.x, qp.y, qp.z, f.q2.w, f.q2.x, f.q2.y, f.q2.z);
  return f;
}

// update_links (§2.3-2.6) of link i for every lane: `large` the lanes in large-angle mode after
// the test, `switched` the lanes that just entered their mode. The two modes differ only in the
// frame (pos2, a1, q2) and in turning F_N, M_N by q1*; those are computed for the large lanes and
// selected per lane, and everything else is the same formula in both modes, so each lane performs
// its own mode's scalar operations.
template <class L, Axis A, LinkPass K>
[[gnu::always_inline]] inline void update_link(const Model& m, Batch& b, int i,
                                               const LinkFrameL<L>& f, int large, int switched,
                                               int& diverged) {
  constexpr int active = kAllLanes<L>;
  constexpr int W = L::W;
  using D = DV<L>;
  const std::size_t iw = static_cast<std::size_t>(i) * W;
  const VL<L>& d = f.d;
  QL<L> q2 = f.q2;
  const D l = splat<L>(m.rest_length);
  const D zero = splat<L>(0.0);
  VL<L> pos2{d.x - l, d.y, d.z}, a1{zero, zero, zero};
  QL<L> q1;
  MV<L> lg{};
  if (large) {
    lg = mask_of<L>(large);
    const D len = L::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    VL<L> a1l;
    frame_to_pos_x_lanes<L>(d, len, q1, a1l);
    QL<L> q12;
    mul_c(q1.w, q1.x, q1.y, q1.z, q2.w, q2.x, q2.y, q2.z, q12.w, q12.x, q12.y, q12.z);
    if (large == kAllLanes<L>) {
      q2 = q12;
      pos2 = {len - l, zero, zero};
      a1 = a1l;
    } else {
      q2 = {select<L>(lg, q12.w, q2.w), select<L>(lg, q12.x, q2.x), select<L>(lg, q12.y, q2.y),
            select<L>(lg, q12.z, q2.z)};
      pos2 = {select<L>(lg, len - l, pos2.x), select<L>(lg, zero, pos2.y),
              select<L>(lg, zero, pos2.z)};
      a1 = {select<L>(lg, a1l.x, zero), select<L>(lg, a1l.y, zero), select<L>(lg, a1l.z, zero)};
    }
  }
  const VL<L> a2 = rotvec_lanes<L>(q2);
  const D strain = L::round_to_float(pos2.x / l);
  if constexpr (computes_forces(K)) {
    diverged |= L::bits(strain > splat<L>(kStrainDiverged)) & active;
    const auto cm = [&](int j) { return splat<L>(m.link_const_members[j][i]); };
    const D e_area = cm(0), area = cm(1), a2c = cm(2), b1 = cm(3), b2 = cm(4), b3 = cm(5);
    const D stress = L::round_to_float(e_area * strain);
    VL<L> fn{L::round_to_float(stress * area), b1 * pos2.y - b2 * (a1.z + a2.z),
             b1 * pos2.z + b2 * (a1.y + a2.y)};
    VL<L> fp{-fn.x, -fn.y, -fn.z};
    VL<L> mn{a2c * (a2.x - a1.x), -b2 * pos2.z - b3 * (2.0 * a1.y + a2.y),
             b2 * pos2.y - b3 * (2.0 * a1.z + a2.z)};
    VL<L> mp{a2c * (a1.x - a2.x), -b2 * pos2.z - b3 * (a1.y + 2.0 * a2.y),
             b2 * pos2.y - b3 * (a1.z + 2.0 * a2.z)};
    const int valid = flag_bits<L>(&b.link_vel_valid[iw]) & ~switched & active;
    if (valid) {
      const VL<L> old_pos2 = ld3<L>(b.link_pos2, i);
      VL<L> old_a1{zero, zero, zero};  // small-angle lanes: the constant zero (link_lanes.hpp)
      if (large) {
        const VL<L> o = ld3<L>(b.link_angle1v, i);
        old_a1 = {select<L>(lg, o.x, zero), select<L>(lg, o.y, zero), select<L>(lg, o.z, zero)};
      }
      const VL<L> old_a2 = ld3<L>(b.link_angle2v, i);
      const D dpx = 0.5 * (pos2.x - old_pos2.x), dpy = 0.5 * (pos2.y - old_pos2.y),
              dpz = 0.5 * (pos2.z - old_pos2.z);
      const D d1x = 0.5 * (a1.x - old_a1.x), d1y = 0.5 * (a1.y - old_a1.y),
              d1z = 0.5 * (a1.z - old_a1.z);
      const D d2x = 0.5 * (a2.x - old_a2.x), d2y = 0.5 * (a2.y - old_a2.y),
              d2z = 0.5 * (a2.z - old_a2.z);
      const D sq_a1 = cm(6), sq_a2 = cm(7), sq_b1 = cm(8), sq_b2 = cm(9), sq_b3 = cm(10);
      const D vx = sq_a1 * dpx, vy = sq_b1 * dpy - sq_b2 * (d1z + d2z),
              vz = sq_b1 * dpz + sq_b2 * (d1y + d2y);
      const D cn = splat<L>(b.damping_neg[i]), cp = splat<L>(b.damping_pos[i]);
      const D hn = 0.5 * cn, hp = 0.5 * cp;
      const VL<L> fn_d{fn.x + cn * vx, fn.y + cn * vy, fn.z + cn * vz};
      const VL<L> fp_d{fp.x - cp * vx, fp.y - cp * vy, fp.z - cp * vz};
      const VL<L> mn_d{mn.x - hn * (-sq_a2 * (d2x - d1x)),
                       mn.y - hn * (sq_b2 * dpz + sq_b3 * (2.0 * d1y + d2y)),
                       mn.z - hn * (-sq_b2 * dpy + sq_b3 * (2.0 * d1z + d2z))};
      const VL<L> mp_d{mp.x - hp * (sq_a2 * (d2x - d1x)),
                       mp.y - hp * (sq_b2 * dpz + sq_b3 * (d1y + 2.0 * d2y)),
                       mp.z - hp * (-sq_b2 * dpy + sq_b3 * (d1z + 2.0 * d2z))};
      if (valid == kAllLanes<L>) {
        fn = fn_d, fp = fp_d, mn = mn_d, mp = mp_d;
      } else {
        const MV<L> on = mask_of<L>(valid);
        fn = {select<L>(on, fn_d.x, fn.x), select<L>(on, fn_d.y, fn.y),
              select<L>(on, fn_d.z, fn.z)};
        fp = {select<L>(on, fp_d.x, fp.x), select<L>(on, fp_d.y, fp.y),
              select<L>(on, fp_d.z, fp.z)};
        mn = {select<L>(on, mn_d.x, mn.x), select<L>(on, mn_d.y, mn.y),
              select<L>(on, mn_d.z, mn.z)};
        mp = {select<L>(on, mp_d.x, mp.x), select<L>(on, mp_d.y, mp.y),
              select<L>(on, mp_d.z, mp.z)};
      }
    }
    if (large) {
      VL<L> fnl, mnl;
      rotate_c(q1.w, -q1.x, -q1.y, -q1.z, fn.x, fn.y, fn.z, fnl.x, fnl.y, fnl.z);
      rotate_c(q1.w, -q1.x, -q1.y, -q1.z, mn.x, mn.y, mn.z, mnl.x, mnl.y, mnl.z);
      fn = {select<L>(lg, fnl.x, fn.x), select<L>(lg, fnl.y, fn.y), select<L>(lg, fnl.z, fn.z)};
      mn = {select<L>(lg, mnl.x, mn.x), select<L>(lg, mnl.y, mn.y), select<L>(lg, mnl.z, mn.z)};
    }
    VL<L> fpl, mpl;
    rotate_c(q2.w, -q2.x, -q2.y, -q2.z, fp.x, fp.y, fp.z, fpl.x, fpl.y, fpl.z);
    rotate_c(q2.w, -q2.x, -q2.y, -q2.z, mp.x, mp.y, mp.z, mpl.x, mpl.y, mpl.z);
    const VL<L> fn_g = from_x_lanes<A, L>(fn), mn_g = from_x_lanes<A, L>(mn);
    const VL<L> fp_g = from_x_lanes<A, L>(fpl), mp_g = from_x_lanes<A, L>(mpl);
    double* out = b.end_load.data() + static_cast<std::size_t>(2 * i) * 6 * W;
    const D rec[12] = {fn_g.x, fn_g.y, fn_g.z, mn_g.x, mn_g.y, mn_g.z,
                       fp_g.x, fp_g.y, fp_g.z, mp_g.x, mp_g.y, mp_g.z};
    for (int j = 0; j < 12; ++j) st_masked<L>(out + j * W, rec[j], active);
  }
  const int state_lanes = stores_link_state(K) ? active : (active & switched);
  if (state_lanes) {
    float sf[W];
    to_floats<L>(strain, sf);
    for (int k = 0; k < W; ++k)
      if (state_lanes >> k & 1) b.link_strain[iw + k] = sf[k];
    st3<L>(b.link_pos2, i, pos2, state_lanes);
    st3<L>(b.link_angle1v, i, a1, state_lanes);
    st3<L>(b.link_angle2v, i, a2, state_lanes);
  }
  const int valid_lanes = marks_velocity_valid(K) ? active : (active & switched);
  if ((flag_bits<L>(&b.link_vel_valid[iw]) & valid_lanes) != valid_lanes)
    set_flags<L>(&b.link_vel_valid[iw], valid_lanes, 1);
  if (switched) {
    set_flags<L>(&b.link_small_angle[iw], switched & large, 0);
    set_flags<L>(&b.link_small_angle[iw], switched & ~large, 1);
  }
}

template <class L, Axis A, LinkPass K>
[[gnu::always_inline]] inline void link_pass_axis_batch(const Model& m, Batch& b, int& diverged) {
  const int begin = m.axis_link_begin[static_cast<int>(A)];
  const int end = m.axis_link_begin[static_cast<int>(A) + 1];
  for (int i = begin; i < end; ++i) {
    const LinkFrameL<L> f = orient_link<L, A>(m, b, i);
    const int small = flag_bits<L>(&b.link_small_angle[static_cast<std::size_t>(i) * L::W]);
    int keep_small = 0, keep_large = 0;
    if (small) keep_small = lanes_keeping_mode<L, false>(m, f.d) & small;
    if (small != kAllLanes<L>) keep_large = lanes_keeping_mode<L, true>(m, f.d) & ~small;
    const int now_small = keep_small | (~small & ~keep_large & kAllLanes<L>);
    const int now_large = ~now_small & kAllLanes<L>;
    const int switched = now_small ^ small;
    update_link<L, A, K>(m, b, i, f, now_large, switched, diverged);
  }
}

template <class L, LinkPass K>
[[gnu::noinline]] int link_pass_batch(const Model& m, Batch& b) {
  if (computes_forces(K) && !(b.previous_dt == b.damping_dt)) {  // as Scratch::link_damping_dt
    b.damping_dt = b.previous_dt;
    for (int i = 0; i < m.link_count; ++i) {
      b.damping_neg[i] = m.voxel_const[m.link_neg[i]].damp_base / b.previous_dt;
      b.damping_pos[i] = m.voxel_const[m.link_pos[i]].damp_base / b.previous_dt;
    }
  }
  int diverged = 0;
  link_pass_axis_batch<L, Axis::x, K>(m, b, diverged);
  link_pass_axis_batch<L, Axis::y, K>(m, b, diverged);
  link_pass_axis_batch<L, Axis::z, K>(m, b, diverged);
  return diverged;
}

// The voxel state of voxel v, lanes = evaluations.
template <class L>
[[gnu::always_inline]] inline void sum_links_batch(const Model& m, const Batch& b, int v,
                                                   VL<L>& lsum, VL<L>& msum) {
  constexpr int W = L::W;
  DV<L> s[6] = {};
  for (int slot : m.voxel_load_slots[v]) {
    const double* p = b.end_load.data() + static_cast<std::size_t>(slot) * 6 * W;
    for (int j = 0; j < 6; ++j) s[j] += ld<L>(p + j * W);
  }
  lsum = {s[0], s[1], s[2]};
  msum = {s[3], s[4], s[5]};
}

template <class L>
[[gnu::noinline]] int fork_voxel_passes_batch(const Model& m, Batch& b) {
  constexpr int W = L::W;
  using D = DV<L>;
  const float dtf = m.dt_f;
  const double dt = m.dt_f;
  const int nv = m.voxel_count;
  const D zero = splat<L>(0.0);
  VL<L> cog{zero, zero, zero};
  for (int v = 0; v < nv; ++v) {
    if (m.voxel_fixed[v]) continue;
    const VL<L> p = ld3<L>(b.pos, v);
    cog = {cog.x + p.x, cog.y + p.y, cog.z + p.z};
  }
  if (m.free_voxel_count > 0) {
    const double n = static_cast<double>(m.free_voxel_count);
    cog = {cog.x / n, cog.y / n, cog.z / n};
  }
  VL<L> la{zero, zero, zero}, lb{zero, zero, zero};
  b.previous_dt = dtf;
  for (int v = 0; v < nv; ++v) {
    if (m.voxel_fixed[v]) continue;
    const std::size_t vw = static_cast<std::size_t>(v) * W;
    VL<L> pos = ld3<L>(b.pos, v), mom = ld3<L>(b.lin_mom, v), am = ld3<L>(b.ang_mom, v);
    const QL<L> q = ld4<L>(b.orient, v);
    const auto cm = [&](int j) { return splat<L>(m.voxel_const_members[j][v]); };
    {
      const D rx = pos.x - cog.x, ry = pos.y - cog.y, rz = pos.z - cog.z;
      la = {la.x + ((ry * mom.z - rz * mom.y) + am.x), la.y + ((rz * mom.x - rx * mom.z) + am.y),
            la.z + ((rx * mom.y - ry * mom.x) + am.z)};
    }
    st3<L>(b.old_pos, v, pos, kAllLanes<L>);
    VL<L> lsum, msum;
    sum_links_batch<L>(m, b, v, lsum, msum);
    const D inv_mass = cm(1);
    const VL<L> vel{mom.x * inv_mass, mom.y * inv_mass, mom.z * inv_mass};
    VL<L> rl;
    rotate_c(q.w, q.x, q.y, q.z, lsum.x, lsum.y, lsum.z, rl.x, rl.y, rl.z);
    const D c_glob = cm(3);
    const VL<L> link_f{rl.x - vel.x * c_glob, rl.y - vel.y * c_glob, rl.z - vel.z * c_glob};
    const VL<L> e = ld3<L>(b.external_force, v);
    const VL<L> ext_f{L::round_to_float(e.x), L::round_to_float(e.y), L::round_to_float(e.z)};
    const VL<L> grav_f{zero, zero, cm(7)};
    const VL<L> col_f = ld3<L>(b.collision_force, v);
    VL<L> fric{zero, zero, zero};
    if (m.floor) {
      FloorContact fc[W];
      const int contact = ground_contacts<L>(m, pos, fc);
      if (contact) {
        const VL<L> fsum{((link_f.x + ext_f.x) + grav_f.x) + col_f.x,
                         ((link_f.y + ext_f.y) + grav_f.y) + col_f.y,
                         ((link_f.z + ext_f.z) + grav_f.z) + col_f.z};
        for (int k = 0; k < W; ++k) {
          if (!(contact >> k & 1)) continue;
          const Vec3 fr =
              floor_force(m.voxel_const[v], fc[k], Vec3(vel.x[k], vel.y[k], vel.z[k]),
                          Vec3(fsum.x[k], fsum.y[k], fsum.z[k]), b.static_friction[vw + k]);
          set_lane<L>(fric, k, fr);
        }
      }
      set_flags<L>(&b.static_friction[vw], ~contact & kAllLanes<L>, 0);
    }
    const VL<L> fle{link_f.x + ext_f.x, link_f.y + ext_f.y, link_f.z + ext_f.z};
    const D dt_m = L::round_to_float(dt * inv_mass);
    pos = {pos.x + fle.x * dt * dt_m, pos.y + fle.y * dt * dt_m, pos.z + fle.z * dt * dt_m};
    mom = {mom.x + fle.x * dt, mom.y + fle.y * dt, mom.z + fle.z * dt};
    VL<L> rm;
    rotate_c(q.w, q.x, q.y, q.z, msum.x, msum.y, msum.z, rm.x, rm.y, rm.z);
    const D inv_i = cm(2), c_rot = cm(4);
    const VL<L> cur_m{rm.x - am.x * inv_i * c_rot, rm.y - am.y * inv_i * c_rot,
                      rm.z - am.z * inv_i * c_rot};
    const D dt_i = L::round_to_float(dt * inv_i);
    const QL<L> dq =
        quat_from_rotvec_lanes<L>({cur_m.x * dt * dt_i, cur_m.y * dt * dt_i, cur_m.z * dt * dt_i});
    QL<L> qn;
    mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
    am = {am.x + cur_m.x * dt, am.y + cur_m.y * dt, am.z + cur_m.z * dt};
    st3<L>(b.pos, v, pos, kAllLanes<L>);
    st3<L>(b.lin_mom, v, mom, kAllLanes<L>);
    st3<L>(b.ang_mom, v, am, kAllLanes<L>);
    double* qp = b.orient.data() + static_cast<std::size_t>(v) * 4 * W;
    st<L>(qp, qn.w), st<L>(qp + W, qn.x), st<L>(qp + 2 * W, qn.y), st<L>(qp + 3 * W, qn.z);
    st3<L>(b.part2_force, v,
           VL<L>{(grav_f.x + col_f.x) + fric.x, (grav_f.y + col_f.y) + fric.y,
                 (grav_f.z + col_f.z) + fric.z},
           kAllLanes<L>);
    st3<L>(b.fric, v, fric, kAllLanes<L>);
    {
      const D rx = pos.x - cog.x, ry = pos.y - cog.y, rz = pos.z - cog.z;
      lb = {lb.x + ((ry * mom.z - rz * mom.y) + am.x), lb.y + ((rz * mom.x - rx * mom.z) + am.y),
            lb.z + ((rx * mom.y - ry * mom.x) + am.z)};
    }
  }
  link_pass_batch<L, LinkPass::state>(m, b);
  const double n_all = static_cast<double>(nv);
  const double dtd = dtf;
  const VL<L> dl{lb.x - la.x, lb.y - la.y, lb.z - la.z};
  const D me_x = L::round_to_float(-dl.x / dtd / n_all) * dt;
  const D me_y = L::round_to_float(-dl.y / dtd / n_all) * dt;
  const D me_z = L::round_to_float(-dl.z / dtd / n_all) * dt;
  D check = zero;
  for (int v = 0; v < nv; ++v) {
    if (m.voxel_fixed[v]) continue;
    const std::size_t vw = static_cast<std::size_t>(v) * W;
    VL<L> pos = ld3<L>(b.pos, v), mom = ld3<L>(b.lin_mom, v), am = ld3<L>(b.ang_mom, v);
    const QL<L> q = ld4<L>(b.orient, v);
    const VL<L> f2 = ld3<L>(b.part2_force, v);
    const D inv_mass = splat<L>(m.voxel_const_members[1][v]);
    const D dt_m = L::round_to_float(dt * inv_mass);
    pos = {pos.x + f2.x * dt * dt_m, pos.y + f2.y * dt * dt_m, pos.z + f2.z * dt * dt_m};
    pos = {pos.x + mom.x * dt_m, pos.y + mom.y * dt_m, pos.z + mom.z * dt_m};
    mom = {mom.x + f2.x * dt, mom.y + f2.y * dt, mom.z + f2.z * dt};
    if (m.floor) {
      FloorContact fc[W];
      const int contact = ground_contacts<L>(m, pos, fc);
      for (int k = 0; k < W; ++k) {
        if (!(contact >> k & 1)) continue;
        Vec3 pk(pos.x[k], pos.y[k], pos.z[k]), mk(mom.x[k], mom.y[k], mom.z[k]);
        const std::size_t c = static_cast<std::size_t>(v) * 3 * W + k;
        const Vec3 fr(b.fric[c], b.fric[c + W], b.fric[c + 2 * W]);
        const Vec3 op(b.old_pos[c], b.old_pos[c + W], b.old_pos[c + 2 * W]);
        fork_static_capture(m.voxel_const[v], fc[k], fr, op, pk, mk, b.static_friction[vw + k]);
        set_lane<L>(pos, k, pk);
        set_lane<L>(mom, k, mk);
      }
      set_flags<L>(&b.static_friction[vw], ~contact & kAllLanes<L>, 0);
    }
    am = {am.x + me_x, am.y + me_y, am.z + me_z};
    const D inv_i = splat<L>(m.voxel_const_members[2][v]);
    const QL<L> dq =
        quat_from_rotvec_lanes<L>({am.x * inv_i * dt, am.y * inv_i * dt, am.z * inv_i * dt});
    QL<L> qn;
    mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
    st3<L>(b.pos, v, pos, kAllLanes<L>);
    st3<L>(b.lin_mom, v, mom, kAllLanes<L>);
    st3<L>(b.ang_mom, v, am, kAllLanes<L>);
    double* qp = b.orient.data() + static_cast<std::size_t>(v) * 4 * W;
    st<L>(qp, qn.w), st<L>(qp + W, qn.x), st<L>(qp + 2 * W, qn.y), st<L>(qp + 3 * W, qn.z);
    check += pos.x + pos.y + pos.z + mom.x + mom.y + mom.z + am.x + am.y + am.z + qn.w;
  }
  int bad = 0;
  for (int k = 0; k < W; ++k)
    if (!std::isfinite(check[k])) bad |= 1 << k;
  return bad;
}

template <class L>
int step_batch(const Model& m, Batch& b) {
  const int diverged = link_pass_batch<L, LinkPass::forces>(m, b);
  if (diverged) return diverged;  // the prototype stops there (no per-lane freeze)
  return fork_voxel_passes_batch<L>(m, b);
}

}  // namespace
}  // namespace softevo::physics

namespace softevo::batch_prototype {

int step_k1(const physics::Model& model, Batch& batch) {
  return physics::step_batch<physics::LanesScalar>(model, batch);
}
int step_k4(const physics::Model& model, Batch& batch) {
  return physics::step_batch<physics::LanesAvx2>(model, batch);
}
int step_k8(const physics::Model& model, Batch& batch) {
  return physics::step_batch<physics::Lanes8>(model, batch);
}

}  // namespace softevo::batch_prototype
