// The passes of the batched step (physics/batch.hpp), written once over the lane traits L: lane k
// of a vector = evaluation g * W + k of one Model (lane group g). The formulas are those of the
// one-robot passes (link_lanes.hpp: large_angle_frame, elastic_link_loads, damped_link_loads;
// voxel_pass.hpp: fork_part1_lanes, fork_part2_lanes), so each lane performs the scalar step's
// operations in its order. Internal to physics/: included by the step_<ISA>.cpp translation units
// through step_kernels.hpp (internal linkage, see lanes.hpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "physics/batch.hpp"
#include "physics/lanes.hpp"
#include "physics/link_lanes.hpp"
#include "physics/voxel_pass.hpp"

namespace softevo::physics {
namespace {

template <class L>
[[gnu::always_inline]] inline DV<L> load_at(const double* p) {
  DV<L> v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// The lanes in `mask` of v stored at p (the others keep their values).
template <class L>
[[gnu::always_inline]] inline void store_at(double* p, DV<L> v, int mask) {
  if (mask == kAllLanes<L>) {
    std::memcpy(p, &v, sizeof v);
  } else if (mask) {
    for (int k = 0; k < L::W; ++k)
      if (mask >> k & 1) p[k] = v[k];
  }
}
// Bit k set where the byte flag p[k] is non-zero, k < W <= 8 (nonzero_flags for up to 8 lanes:
// the top bit of each non-zero byte, moved to bit k by one multiplication whose shifted copies
// land on distinct bits).
template <class L>
[[gnu::always_inline]] inline int lane_flags(const std::uint8_t* p) {
  if constexpr (L::W <= 4) {
    return nonzero_flags<L>(p);
  } else {
    static_assert(L::W <= 8);
    std::uint64_t word = 0;
    std::memcpy(&word, p, L::W);
    if constexpr (std::endian::native == std::endian::big) word = __builtin_bswap64(word);
    const std::uint64_t top =
        (((word & 0x7f7f7f7f7f7f7f7full) + 0x7f7f7f7f7f7f7f7full) | word) & 0x8080808080808080ull;
    return static_cast<int>(((top >> 7) * 0x0102040810204080ull) >> 56) & kAllLanes<L>;
  }
}
template <class L>
[[gnu::always_inline]] inline void set_flags(std::uint8_t* p, int mask, std::uint8_t value) {
  for (int k = 0; k < L::W; ++k)
    if (mask >> k & 1) p[k] = value;
}

// Element e of a 3- or 4-component batch array, lane group g.
template <class L>
struct BatchAt {
  int padded, g;
  std::size_t at(int e, int components, int c) const {
    return (static_cast<std::size_t>(e) * components + c) * padded + g * L::W;
  }
  VL<L> vec(const std::vector<double>& a, int e) const {
    return {load_at<L>(&a[at(e, 3, 0)]), load_at<L>(&a[at(e, 3, 1)]), load_at<L>(&a[at(e, 3, 2)])};
  }
  QL<L> quat(const std::vector<double>& a, int e) const {
    return {load_at<L>(&a[at(e, 4, 0)]), load_at<L>(&a[at(e, 4, 1)]), load_at<L>(&a[at(e, 4, 2)]),
            load_at<L>(&a[at(e, 4, 3)])};
  }
  void put(std::vector<double>& a, int e, const VL<L>& v, int mask) const {
    store_at<L>(&a[at(e, 3, 0)], v.x, mask);
    store_at<L>(&a[at(e, 3, 1)], v.y, mask);
    store_at<L>(&a[at(e, 3, 2)], v.z, mask);
  }
  void put(std::vector<double>& a, int e, const QL<L>& q) const {
    store_at<L>(&a[at(e, 4, 0)], q.w, kAllLanes<L>);
    store_at<L>(&a[at(e, 4, 1)], q.x, kAllLanes<L>);
    store_at<L>(&a[at(e, 4, 2)], q.y, kAllLanes<L>);
    store_at<L>(&a[at(e, 4, 3)], q.z, kAllLanes<L>);
  }
  std::size_t flag(int e) const { return static_cast<std::size_t>(e) * padded + g * L::W; }
};

// §2.3-2.6 for link i of axis A in every lane of group `at` (orient_links and update_links of
// link_lanes.hpp with lanes = evaluations). Returns the lanes whose strain > 100 (forces only).
template <class L, Axis A, LinkPass K>
[[gnu::always_inline]] inline int batch_link(const Model& m, BatchState& b, BatchScratch& sc,
                                             const BatchAt<L>& at, int i) {
  constexpr int W = L::W;
  constexpr int kAll = kAllLanes<L>;
  using D = DV<L>;
  // §2.3 orient link
  const int n = m.link_neg[i], p = m.link_pos[i];
  const VL<L> pn = at.vec(b.pos, n), pp = at.vec(b.pos, p);
  const VL<L> d0 = to_x_lanes<A, L>(pp.x - pn.x, pp.y - pn.y, pp.z - pn.z);
  const QL<L> qn = to_x_lanes<A, L>(at.quat(b.orient, n));
  const QL<L> r{qn.w, -qn.x, -qn.y, -qn.z};
  VL<L> d;
  rotate_c(r.w, r.x, r.y, r.z, d0.x, d0.y, d0.z, d.x, d.y, d.z);
  const QL<L> qp = to_x_lanes<A, L>(at.quat(b.orient, p));
  QL<L> q2;
  mul_c(r.w, r.x, r.y, r.z, qp.w, qp.x, qp.y, qp.z, q2.w, q2.x, q2.y, q2.z);
  // §2.3 step 3: each lane's mode test from its own mode
  const std::size_t fi = at.flag(i);
  const int small = lane_flags<L>(&b.link_small_angle[fi]);
  int keep_small = 0, keep_large = 0;
  if (small) keep_small = lanes_keeping_mode<L, false>(m, d) & small;
  if (small != kAll) keep_large = lanes_keeping_mode<L, true>(m, d) & ~small & kAll;
  const int now_small = keep_small | (~small & ~keep_large & kAll);
  const int large = ~now_small & kAll;
  const int switched = now_small ^ small;

  const D l = splat<L>(m.rest_length);
  const D zero = splat<L>(0.0);
  VL<L> pos2{d.x - l, d.y, d.z}, a1{zero, zero, zero};
  QL<L> q1;
  MV<L> lg{};
  if (large) {  // the large-angle frame for the large lanes, selected per lane
    lg = mask_of<L>(large);
    VL<L> a1l, pos2l;
    QL<L> q2l = q2;
    large_angle_frame<L>(d, l, q1, a1l, q2l, pos2l);
    q2 = select<L>(lg, q2l, q2);
    pos2 = select<L>(lg, pos2l, pos2);
    a1 = select<L>(lg, a1l, a1);
  }
  const VL<L> a2 = rotvec_lanes<L>(q2);
  const D strain = L::round_to_float(pos2.x / l);  // §2.4
  int diverged = 0;
  if constexpr (computes_forces(K)) {
    diverged = L::bits(strain > splat<L>(kStrainDiverged));
    const auto cm = [&](int j) { return splat<L>(m.link_const_members[j][i]); };
    const LinkConstL<L> c{cm(0), cm(1), cm(2), cm(3), cm(4), cm(5),
                          cm(6), cm(7), cm(8), cm(9), cm(10)};
    LinkLoadsL<L> loads = elastic_link_loads<L>(c, strain, pos2, a1, a2);
    // §2.5 damping in the lanes with a valid local velocity that kept their mode
    const int valid = lane_flags<L>(&b.link_vel_valid[fi]) & ~switched & kAll;
    if (valid) {
      VL<L> old_a1{zero, zero, zero};  // small-angle lanes: the constant zero (see link_group)
      if (large) old_a1 = select<L>(lg, at.vec(b.link_angle1v, i), old_a1);
      const LinkLoadsL<L> damped = damped_link_loads<L>(
          c, splat<L>(sc.damping_neg[i]), splat<L>(sc.damping_pos[i]), loads, pos2, a1, a2,
          at.vec(b.link_pos2, i), old_a1, at.vec(b.link_angle2v, i));
      loads = valid == kAll ? damped : select<L>(mask_of<L>(valid), damped, loads);
    }
    // §2.6: F_N, M_N turn by q1* in large-angle lanes; F_P, M_P by q2*
    if (large) {
      loads.fn = select<L>(lg, rotate_by_conj<L>(q1, loads.fn), loads.fn);
      loads.mn = select<L>(lg, rotate_by_conj<L>(q1, loads.mn), loads.mn);
    }
    const VL<L> rec[4] = {from_x_lanes<A, L>(loads.fn), from_x_lanes<A, L>(loads.mn),
                          from_x_lanes<A, L>(rotate_by_conj<L>(q2, loads.fp)),
                          from_x_lanes<A, L>(rotate_by_conj<L>(q2, loads.mp))};
    // end loads: slot 2i = end N (force, moment), 2i + 1 = end P
    for (int j = 0; j < 4; ++j) {
      const int slot = 2 * i + j / 2;
      double* out =
          &sc.end_load[(static_cast<std::size_t>(slot) * 6 + 3 * (j % 2)) * at.padded + at.g * W];
      store_at<L>(out, rec[j].x, kAll);
      store_at<L>(out + at.padded, rec[j].y, kAll);
      store_at<L>(out + 2 * at.padded, rec[j].z, kAll);
    }
  }
  // the link state: every lane in a pass that stores it, else the lanes that switched mode
  const int state_lanes = stores_link_state(K) ? kAll : switched;
  if (state_lanes) {
    float strain_f[W];
    to_floats<L>(strain, strain_f);
    for (int k = 0; k < W; ++k)
      if (state_lanes >> k & 1) b.link_strain[fi + k] = strain_f[k];
    at.put(b.link_pos2, i, pos2, state_lanes);
    at.put(b.link_angle1v, i, a1, state_lanes);
    at.put(b.link_angle2v, i, a2, state_lanes);
  }
  const int valid_lanes = marks_velocity_valid(K) ? kAll : switched;
  if ((lane_flags<L>(&b.link_vel_valid[fi]) & valid_lanes) != valid_lanes)
    set_flags<L>(&b.link_vel_valid[fi], valid_lanes, 1);
  if (switched) {
    set_flags<L>(&b.link_small_angle[fi], switched & large, 0);
    set_flags<L>(&b.link_small_angle[fi], switched & now_small, 1);
  }
  return diverged;
}

template <class L, Axis A, LinkPass K>
inline int batch_link_axis(const Model& m, BatchState& b, BatchScratch& sc) {
  const int begin = m.axis_link_begin[static_cast<int>(A)];
  const int end = m.axis_link_begin[static_cast<int>(A) + 1];
  const int groups = b.padded / L::W;
  int diverged = 0;
  for (int i = begin; i < end; ++i)
    for (int g = 0; g < groups; ++g)
      diverged |= batch_link<L, A, K>(m, b, sc, BatchAt<L>{b.padded, g}, i) << (g * L::W);
  return diverged;
}

// A link pass over every link of every lane; the lanes (bit k = lane k) with a strain > 100.
template <class L, LinkPass K>
[[gnu::noinline]] int batch_link_pass(const Model& m, BatchState& b, BatchScratch& sc) {
  return batch_link_axis<L, Axis::x, K>(m, b, sc) | batch_link_axis<L, Axis::y, K>(m, b, sc) |
         batch_link_axis<L, Axis::z, K>(m, b, sc);
}

// The lane access of the floor contact (voxel_pass.hpp) in a batch: lane k of group `at`, voxel v.
template <class L>
struct BatchLaneAccess {
  const Model& m;
  BatchState& b;
  const BatchScratch& sc;
  const BatchAt<L>& at;
  int v;
  const VoxelConst& voxel_const(int) const { return m.voxel_const[v]; }
  std::uint8_t& static_friction(int k) const { return b.static_friction[at.flag(v) + k]; }
  Vec3 fric(int k) const { return get(sc.fric, k); }
  Vec3 old_pos(int k) const { return get(sc.old_pos, k); }
  Vec3 get(const std::vector<double>& a, int k) const {
    return Vec3(a[at.at(v, 3, 0) + k], a[at.at(v, 3, 1) + k], a[at.at(v, 3, 2) + k]);
  }
};

template <class L>
[[gnu::always_inline]] inline VoxelLanes<L> batch_voxel(const Model& m, const BatchState& b,
                                                        const BatchAt<L>& at, int v) {
  const auto cm = [&](int j) { return splat<L>(m.voxel_const_members[j][v]); };
  return {at.vec(b.pos, v), at.vec(b.lin_mom, v), at.vec(b.ang_mom, v), at.quat(b.orient, v),
          VoxelConstL<L>{cm(1), cm(2), cm(3), cm(4), cm(7)}};
}

// §2.12 steps 3-9 of every lane (fork_voxel_passes with lanes = evaluations): the lanes (bit k =
// lane k) whose state became non-finite. Sums over voxels keep voxel order in every lane.
template <class L>
[[gnu::noinline]] int batch_voxel_passes(const Model& m, BatchState& b, BatchScratch& sc) {
  constexpr int W = L::W;
  using D = DV<L>;
  const int groups = b.padded / W;
  const int nv = m.voxel_count;
  const D zero = splat<L>(0.0);
  // 4. CoG of each lane; 5. part 1 with L_A, L_B summed per lane in voxel order
  VL<L> cog[kMaxBatchLanes], la[kMaxBatchLanes], lb[kMaxBatchLanes];
  for (int g = 0; g < groups; ++g) cog[g] = la[g] = lb[g] = VL<L>{zero, zero, zero};
  for (int v = 0; v < nv; ++v) {
    if (m.voxel_fixed[v]) continue;
    for (int g = 0; g < groups; ++g) {
      const VL<L> p = BatchAt<L>{b.padded, g}.vec(b.pos, v);
      cog[g] = {cog[g].x + p.x, cog[g].y + p.y, cog[g].z + p.z};
    }
  }
  if (m.free_voxel_count > 0) {
    const double n = static_cast<double>(m.free_voxel_count);
    for (int g = 0; g < groups; ++g) cog[g] = {cog[g].x / n, cog[g].y / n, cog[g].z / n};
  }
  for (int v = 0; v < nv; ++v) {
    if (m.voxel_fixed[v]) continue;
    for (int g = 0; g < groups; ++g) {
      const BatchAt<L> at{b.padded, g};
      const VoxelLanes<L> start = batch_voxel<L>(m, b, at, v);
      at.put(sc.old_pos, v, start.pos, kAllLanes<L>);
      VL<L> lsum{zero, zero, zero}, msum{zero, zero, zero};
      for (int slot : m.voxel_load_slots[v]) {  // six slots in order, from +0 (sum_links)
        const VL<L> f = at.vec(sc.end_load, 2 * slot), mo = at.vec(sc.end_load, 2 * slot + 1);
        lsum = {lsum.x + f.x, lsum.y + f.y, lsum.z + f.z};
        msum = {msum.x + mo.x, msum.y + mo.y, msum.z + mo.z};
      }
      const VL<L> e = at.vec(sc.external_force, v);
      const VL<L> ext_f{L::round_to_float(e.x), L::round_to_float(e.y), L::round_to_float(e.z)};
      const Part1L<L> r =
          fork_part1_lanes<L>(m, start, lsum, msum, ext_f, at.vec(sc.collision_force, v), cog[g],
                              BatchLaneAccess<L>{m, b, sc, at, v});
      at.put(b.pos, v, r.pos, kAllLanes<L>);
      at.put(b.lin_mom, v, r.mom, kAllLanes<L>);
      at.put(b.ang_mom, v, r.am, kAllLanes<L>);
      at.put(b.orient, v, r.q);
      at.put(sc.part2_force, v, r.part2, kAllLanes<L>);
      at.put(sc.fric, v, r.fric, kAllLanes<L>);
      la[g] = {la[g].x + r.la.x, la[g].y + r.la.y, la[g].z + r.la.z};
      lb[g] = {lb[g].x + r.lb.x, lb[g].y + r.lb.y, lb[g].z + r.lb.z};
    }
  }
  // 6. mid-step link update (state only)
  batch_link_pass<L, LinkPass::state>(m, b, sc);
  // 7. correction moment -dL / dt / N_all (float) per lane, times dt as part 2 adds it
  const double dt = m.dt_f;
  const double n_all = static_cast<double>(nv);
  VL<L> me_dt[kMaxBatchLanes];
  for (int g = 0; g < groups; ++g) {
    const VL<L> dl{lb[g].x - la[g].x, lb[g].y - la[g].y, lb[g].z - la[g].z};
    me_dt[g] = {L::round_to_float(-dl.x / dt / n_all) * dt,
                L::round_to_float(-dl.y / dt / n_all) * dt,
                L::round_to_float(-dl.z / dt / n_all) * dt};
  }
  // 8. part 2, the state's sum per lane in voxel order
  D check[kMaxBatchLanes];
  for (int g = 0; g < groups; ++g) check[g] = zero;
  for (int v = 0; v < nv; ++v) {
    if (m.voxel_fixed[v]) continue;
    for (int g = 0; g < groups; ++g) {
      const BatchAt<L> at{b.padded, g};
      D sum;
      const Part2L<L> r =
          fork_part2_lanes<L>(m, batch_voxel<L>(m, b, at, v), at.vec(sc.part2_force, v), me_dt[g],
                              BatchLaneAccess<L>{m, b, sc, at, v}, sum);
      at.put(b.pos, v, r.pos, kAllLanes<L>);
      at.put(b.lin_mom, v, r.mom, kAllLanes<L>);
      at.put(b.ang_mom, v, r.am, kAllLanes<L>);
      at.put(b.orient, v, r.q);
      check[g] += sum;
    }
  }
  int non_finite = 0;
  for (int g = 0; g < groups; ++g)
    for (int k = 0; k < W; ++k)
      if (!std::isfinite(check[g][k])) non_finite |= 1 << (g * W + k);
  return non_finite;
}

}  // namespace
}  // namespace softevo::physics
