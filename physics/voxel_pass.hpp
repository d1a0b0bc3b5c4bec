// The voxel passes of one step: the fork's two-part step (§2.12 steps 3-9) and the upstream
// symplectic Euler (§2.9), free voxels W at a time, one voxel per lane. Each formula is written
// once, over the lanes; a single voxel (the tail of a pass, a group with a fixed voxel) runs it
// one lane wide (LanesScalar), which performs the reference's scalar IEEE operations in the same
// order. Voxel groups are W consecutive voxel ids, so their records are runs. Internal to
// physics/ (see physics/lanes.hpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstring>
#include <span>

#include "physics/floor_contact.hpp"
#include "physics/lane_math.hpp"
#include "physics/lanes.hpp"
#include "physics/lanes_scalar.hpp"
#include "physics/link_lanes.hpp"
#include "physics/model.hpp"
#include "physics/quat.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"

namespace softevo::physics {
namespace {

template <class L>
struct VoxelConstL {
  DV<L> inv_mass, inv_inertia, c_glob, c_glob_rot, gravity_force;
};
// The constants of the W consecutive voxels first .. first + W - 1 (Model::voxel_const_members).
template <class L>
[[gnu::always_inline]] inline VoxelConstL<L> load_voxel_const_run(const Model& m, int first) {
  static_assert(offsetof(VoxelConst, mass) == 0 && offsetof(VoxelConst, inv_mass) == 4 &&
                offsetof(VoxelConst, inv_inertia) == 8 && offsetof(VoxelConst, c_glob) == 12 &&
                offsetof(VoxelConst, c_glob_rot) == 16 &&
                offsetof(VoxelConst, gravity_force) == 28);
  const auto member = [&](int j) { return load_lanes<L>(&m.voxel_const_members[j][first]); };
  return {member(1), member(2), member(3), member(4), member(7)};
}

// Sum of the link forces and moments acting on voxel v (local frame), direction order 0..5.
// The six sums in three pairs of doubles (fx fy | fz mx | my mz): element-wise additions in entry
// order from +0.0, so the same roundings as force += load.force; moment += load.moment on Vec3.
struct LinkSums {
  using Pair = double __attribute__((vector_size(16)));  // element-wise IEEE additions
  Pair fxy, fz_mx, myz;
};
[[gnu::always_inline]] inline LinkSums::Pair load_pair(const double* p) {
  LinkSums::Pair r;
  std::memcpy(&r, p, sizeof r);
  return r;
}
inline LinkSums sum_links(const Model& m, const Scratch& sc, int v) {
  static_assert(sizeof(Scratch::EndLoad) == 6 * sizeof(double));
  LinkSums s{};
  const Scratch::EndLoad* loads = sc.link_end_load.data();
  for (int slot : m.voxel_load_slots[v]) {  // six slots, missing links read the zero load
    const double* load = loads[slot].force.data();
    s.fxy += load_pair(load);
    s.fz_mx += load_pair(load + 2);
    s.myz += load_pair(load + 4);
  }
  return s;
}

// External forces of the W consecutive voxels first .. first + W - 1, each component rounded to
// float (the reference's External stores float), as lanes.
template <class L>
[[gnu::always_inline]] inline VL<L> load_external_force(std::span<const Vec3> ext, int first) {
  DV<L> c[3];
  load_records<L>(ext[first].data(), c);
  return {L::round_to_float(c[0]), L::round_to_float(c[1]), L::round_to_float(c[2])};
}

// The state and constants of W voxels as lanes. Voxel groups are W consecutive voxel ids v[k] =
// v[0] + k (free_group), so their records are loaded and stored as runs.
template <class L>
struct VoxelLanes {
  VL<L> pos, mom, am;
  QL<L> q;
  VoxelConstL<L> c;
};
template <class L>
[[gnu::always_inline]] inline VoxelLanes<L> load_voxels(const Model& m, const State& st,
                                                        const int* v) {
  return {load_run<L>(st.pos, v[0]), load_run<L>(st.lin_mom, v[0]), load_run<L>(st.ang_mom, v[0]),
          load_run<L>(st.orient, v[0]), load_voxel_const_run<L>(m, v[0])};
}
template <class L>
[[gnu::always_inline]] inline void store_voxels(const VL<L>& pos, const VL<L>& mom, const VL<L>& am,
                                                const QL<L>& q, State& st, const int* v) {
  store_run<L>(pos, st.pos, v[0]);
  store_run<L>(mom, st.lin_mom, v[0]);
  store_run<L>(am, st.ang_mom, v[0]);
  store_run<L>(q, st.orient, v[0]);
}
// sum_links of W voxels as lanes: sums of link forces (lsum) and moments (msum), local frame.
template <class L>
[[gnu::always_inline]] inline void gather_links_lanes(const Model& m, const Scratch& sc,
                                                      const int* v, VL<L>& lsum, VL<L>& msum) {
  LinkSums s[L::W];
  for (int k = 0; k < L::W; ++k) s[k] = sum_links(m, sc, v[k]);
  lsum = {make_lanes<L>([&](int k) { return s[k].fxy[0]; }),
          make_lanes<L>([&](int k) { return s[k].fxy[1]; }),
          make_lanes<L>([&](int k) { return s[k].fz_mx[0]; })};
  msum = {make_lanes<L>([&](int k) { return s[k].fz_mx[1]; }),
          make_lanes<L>([&](int k) { return s[k].myz[0]; }),
          make_lanes<L>([&](int k) { return s[k].myz[1]; })};
}

// The formulas of the fork's two parts (§2.12 steps 5 and 8), shared by the voxel passes of one
// robot (lanes = voxels) and the batched step (physics/batch_kernels.hpp: lanes = evaluations of
// one body). What the floor contact reads and writes one lane at a time comes from `lane`:
// lane.voxel_const(k), lane.static_friction(k) (a reference to the flag), and for part 2
// lane.fric(k) and lane.old_pos(k) (part 1's friction force and start position).

// Part 1 of W voxels from their state at the start of the step (`start`), the sums of their link
// loads (local frame), external force (rounded to float), collision force and the CoG: the new
// state (pos, mom, am, q), the force part 2 applies (part2) and the friction force (fric); the
// voxels' angular momentum about the CoG before (la) and after (lb) the part.
template <class L>
struct Part1L {
  VL<L> pos, mom, am;
  QL<L> q;
  VL<L> part2, fric, la, lb;
};
template <class L, class Lane>
[[gnu::always_inline]] inline Part1L<L> fork_part1_lanes(const Model& m, const VoxelLanes<L>& start,
                                                         const VL<L>& lsum, const VL<L>& msum,
                                                         const VL<L>& ext_f, const VL<L>& col_f,
                                                         const VL<L>& cog, Lane&& lane) {
  constexpr int W = L::W;
  using D = DV<L>;
  const double dt = m.dt_f;
  VL<L> pos = start.pos, mom = start.mom, am = start.am;
  const QL<L>& q = start.q;
  const VoxelConstL<L>& c = start.c;
  Part1L<L> r;
  {
    const D rx = pos.x - cog.x, ry = pos.y - cog.y,
            rz = pos.z - cog.z;  // cross(pos - cog, mom) + am
    r.la = {(ry * mom.z - rz * mom.y) + am.x, (rz * mom.x - rx * mom.z) + am.y,
            (rx * mom.y - ry * mom.x) + am.z};
  }
  const D inv_mass = c.inv_mass;
  const VL<L> vel{mom.x * inv_mass, mom.y * inv_mass, mom.z * inv_mass};
  VL<L> rl;
  rotate_c(q.w, q.x, q.y, q.z, lsum.x, lsum.y, lsum.z, rl.x, rl.y, rl.z);
  const D c_glob = c.c_glob;
  const VL<L> link_f{rl.x - vel.x * c_glob, rl.y - vel.y * c_glob, rl.z - vel.z * c_glob};
  const D zero = splat<L>(0.0);
  const VL<L> grav_f{zero, zero, c.gravity_force};
  VL<L> fric{zero, zero, zero};
  if (m.floor) {
    FloorContact fc[W];
    const int contact = ground_contacts<L>(m, pos, fc);
    const VL<L> fsum{((link_f.x + ext_f.x) + grav_f.x) + col_f.x,
                     ((link_f.y + ext_f.y) + grav_f.y) + col_f.y,
                     ((link_f.z + ext_f.z) + grav_f.z) + col_f.z};
    for (int k = 0; k < W; ++k) {
      std::uint8_t& sf = lane.static_friction(k);
      if (!(contact >> k & 1)) {
        sf = 0;  // floor_force without contact
        continue;
      }
      const Vec3 fr = floor_force(lane.voxel_const(k), fc[k], Vec3(vel.x[k], vel.y[k], vel.z[k]),
                                  Vec3(fsum.x[k], fsum.y[k], fsum.z[k]), sf);
      set_lane<L>(fric, k, fr);
    }
  }
  const VL<L> fle{link_f.x + ext_f.x, link_f.y + ext_f.y, link_f.z + ext_f.z};
  const D dt_m = L::round_to_float(dt * inv_mass);  // float dt * (1/m)
  pos = {pos.x + fle.x * dt * dt_m, pos.y + fle.y * dt * dt_m, pos.z + fle.z * dt * dt_m};
  mom = {mom.x + fle.x * dt, mom.y + fle.y * dt, mom.z + fle.z * dt};
  VL<L> rm;
  rotate_c(q.w, q.x, q.y, q.z, msum.x, msum.y, msum.z, rm.x, rm.y, rm.z);
  const D inv_i = c.inv_inertia;
  const D c_rot = c.c_glob_rot;
  const VL<L> cur_m{rm.x - am.x * inv_i * c_rot, rm.y - am.y * inv_i * c_rot,
                    rm.z - am.z * inv_i * c_rot};
  const D dt_i = L::round_to_float(dt * inv_i);  // float dt * (1/I)
  const QL<L> dq =
      quat_from_rotvec_lanes<L>({cur_m.x * dt * dt_i, cur_m.y * dt * dt_i, cur_m.z * dt * dt_i});
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, r.q.w, r.q.x, r.q.y, r.q.z);
  am = {am.x + cur_m.x * dt, am.y + cur_m.y * dt, am.z + cur_m.z * dt};
  r.part2 = {(grav_f.x + col_f.x) + fric.x, (grav_f.y + col_f.y) + fric.y,
             (grav_f.z + col_f.z) + fric.z};
  r.fric = fric;
  {
    const D rx = pos.x - cog.x, ry = pos.y - cog.y, rz = pos.z - cog.z;
    r.lb = {(ry * mom.z - rz * mom.y) + am.x, (rz * mom.x - rx * mom.z) + am.y,
            (rx * mom.y - ry * mom.x) + am.z};
  }
  r.pos = pos;
  r.mom = mom;
  r.am = am;
  return r;
}

// The lane access of the passes of one robot: lane k = voxel v[k].
struct VoxelLaneAccess {
  const Model& m;
  State& st;
  Scratch& sc;
  const int* v;
  const VoxelConst& voxel_const(int k) const { return m.voxel_const[v[k]]; }
  std::uint8_t& static_friction(int k) const { return st.static_friction[v[k]]; }
  const Vec3& fric(int k) const { return sc.fric[v[k]]; }
  const Vec3& old_pos(int k) const { return sc.old_pos[v[k]]; }
};

// §2.12 step 5, part 1 of the fork's step for W free voxels v[0..W), one per lane (the floor
// force of §2.8 and the large-rotation branch of quat_from_rotvec per lane in scalar code).
// Returns each voxel's angular momentum about the CoG before (la) and after (lb) the part.
template <class L>
inline void fork_part1_group(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                             const int* v, const Vec3& cog, VL<L>& la, VL<L>& lb) {
  const VoxelLanes<L> start = load_voxels<L>(m, st, v);
  store_run<L>(start.pos, sc.old_pos, v[0]);
  VL<L> lsum, msum;
  gather_links_lanes<L>(m, sc, v, lsum, msum);
  const DV<L> zero = splat<L>(0.0);
  VL<L> ext_f{zero, zero, zero};
  if (!ext.empty()) {  // the reference's External stores float
    ext_f = load_external_force<L>(ext, v[0]);
  }
  const VL<L> col_f = load_run<L>(sc.collision_force, v[0]);
  const VL<L> cg{splat<L>(cog.x()), splat<L>(cog.y()), splat<L>(cog.z())};
  const Part1L<L> r =
      fork_part1_lanes<L>(m, start, lsum, msum, ext_f, col_f, cg, VoxelLaneAccess{m, st, sc, v});
  store_voxels<L>(r.pos, r.mom, r.am, r.q, st, v);
  store_run<L>(r.part2, sc.part2_force, v[0]);
  store_run<L>(r.fric, sc.fric, v[0]);
  la = r.la;
  lb = r.lb;
}

// The end of a voxel update (§2.9, §2.12 step 8): the orientation turned by the new angular
// momentum, q <- quat_from_rotvec(angMom (1/I) dt) q, and the sum of the new state (added to a
// finiteness check: NaN / inf anywhere makes it non-finite; finite values beyond ~1e307 that
// overflow the sum are reported as non-finite too).
template <class L>
[[gnu::always_inline]] inline QL<L> turned(const VL<L>& pos, const VL<L>& mom, const VL<L>& am,
                                           const QL<L>& q, DV<L> inv_i, double dt, DV<L>& sum) {
  const QL<L> dq =
      quat_from_rotvec_lanes<L>({am.x * inv_i * dt, am.y * inv_i * dt, am.z * inv_i * dt});
  QL<L> qn;
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
  sum = pos.x + pos.y + pos.z + mom.x + mom.y + mom.z + am.x + am.y + am.z + qn.w;
  return qn;
}
// turned(), the new state stored, and its sum added to `check` lane by lane.
template <class L>
[[gnu::always_inline]] inline void turn_and_store(const VL<L>& pos, const VL<L>& mom,
                                                  const VL<L>& am, const QL<L>& q, DV<L> inv_i,
                                                  double dt, State& st, const int* v,
                                                  double& check) {
  DV<L> sum;
  const QL<L> qn = turned<L>(pos, mom, am, q, inv_i, dt, sum);
  store_voxels<L>(pos, mom, am, qn, st, v);
  for (int k = 0; k < L::W; ++k) check += sum[k];
}

// Part 2 of W voxels from their state after part 1 (`start`) and part 1's force f2, with the
// correction moment times dt (me_dt): the new state; its sum (turned()) in `sum`.
template <class L>
struct Part2L {
  VL<L> pos, mom, am;
  QL<L> q;
};
template <class L, class Lane>
[[gnu::always_inline]] inline Part2L<L> fork_part2_lanes(const Model& m, const VoxelLanes<L>& start,
                                                         const VL<L>& f2, const VL<L>& me_dt,
                                                         Lane&& lane, DV<L>& sum) {
  constexpr int W = L::W;
  using D = DV<L>;
  const double dt = m.dt_f;
  VL<L> pos = start.pos, mom = start.mom, am = start.am;
  const D inv_mass = start.c.inv_mass;
  const D dt_m = L::round_to_float(dt * inv_mass);  // float dt * (1/m)
  pos = {pos.x + f2.x * dt * dt_m, pos.y + f2.y * dt * dt_m, pos.z + f2.z * dt * dt_m};
  pos = {pos.x + mom.x * dt_m, pos.y + mom.y * dt_m, pos.z + mom.z * dt_m};
  mom = {mom.x + f2.x * dt, mom.y + f2.y * dt, mom.z + f2.z * dt};
  if (m.floor) {
    FloorContact fc[W];
    const int contact = ground_contacts<L>(m, pos, fc);
    for (int k = 0; k < W; ++k) {
      if (!(contact >> k & 1)) {
        lane.static_friction(k) = 0;
        continue;
      }
      Vec3 pk(pos.x[k], pos.y[k], pos.z[k]), mk(mom.x[k], mom.y[k], mom.z[k]);
      fork_static_capture(lane.voxel_const(k), fc[k], lane.fric(k), lane.old_pos(k), pk, mk,
                          lane.static_friction(k));
      set_lane<L>(pos, k, pk);
      set_lane<L>(mom, k, mk);
    }
  }
  am = {am.x + me_dt.x, am.y + me_dt.y, am.z + me_dt.z};
  Part2L<L> r{pos, mom, am, {}};
  r.q = turned<L>(pos, mom, am, start.q, start.c.inv_inertia, dt, sum);
  return r;
}

// §2.12 step 8, part 2 of the fork's step for W free voxels v[0..W), one per lane; adds the
// voxels' state to `check` (turned()).
template <class L>
inline void fork_part2_group(const Model& m, State& st, Scratch& sc, const int* v, float me_x,
                             float me_y, float me_z, double& check) {
  const double dt = m.dt_f;
  const VoxelLanes<L> start = load_voxels<L>(m, st, v);
  const VL<L> f2 = load_run<L>(sc.part2_force, v[0]);
  const VL<L> me_dt{splat<L>(static_cast<double>(me_x) * dt),
                    splat<L>(static_cast<double>(me_y) * dt),
                    splat<L>(static_cast<double>(me_z) * dt)};
  DV<L> sum;
  const Part2L<L> r = fork_part2_lanes<L>(m, start, f2, me_dt, VoxelLaneAccess{m, st, sc, v}, sum);
  store_voxels<L>(r.pos, r.mom, r.am, r.q, st, v);
  for (int k = 0; k < L::W; ++k) check += sum[k];
}

// One free voxel through the same formulas one lane wide (LanesScalar): the last voxels of a pass
// (voxel_count not a multiple of W) and the groups that hold a fixed voxel.
inline void fork_part1_voxel(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                             int v, const Vec3& cog, Vec3& la, Vec3& lb) {
  VL<LanesScalar> a, b;
  fork_part1_group<LanesScalar>(m, st, sc, ext, &v, cog, a, b);
  la = Vec3(a.x[0], a.y[0], a.z[0]);
  lb = Vec3(b.x[0], b.y[0], b.z[0]);
}
inline void fork_part2_voxel(const Model& m, State& st, Scratch& sc, int v, float me_x, float me_y,
                             float me_z, double& check) {
  fork_part2_group<LanesScalar>(m, st, sc, &v, me_x, me_y, me_z, check);
}

// W consecutive voxels v0 .. v0 + W - 1 as lane ids; true if none of them is fixed.
template <class L>
[[gnu::always_inline]] inline bool free_group(const Model& m, int v0, int* ids) {
  bool any_fixed = false;
  for (int k = 0; k < L::W; ++k) {
    ids[k] = v0 + k;
    any_fixed |= m.voxel_fixed[v0 + k] != 0;
  }
  return !any_fixed;
}

// §2.12 steps 3-9 (after the link pass and the collisions): the fork's two-part step. Free
// voxels go through the parts W at a time; sums over voxels keep list order.
template <class L>
[[gnu::noinline]] bool fork_voxel_passes(const Model& m, State& st, Scratch& sc,
                                         std::span<const Vec3> ext) {
  constexpr int W = L::W;
  const float dt = m.dt_f;
  const int nv = m.voxel_count;
  // 4. CoG = mean position of the non-fixed voxels
  Vec3 cog = Vec3::Zero();
  for (int v = 0; v < nv; ++v)
    if (!m.voxel_fixed[v]) cog += st.pos[v];
  if (m.free_voxel_count > 0) cog /= static_cast<double>(m.free_voxel_count);
  Vec3 la = Vec3::Zero(), lb = Vec3::Zero();
  st.previous_dt = dt;

  // 5. part 1; L_A (start state) and L_B (after part 1) are summed per voxel in list order
  auto part1 = [&](int v) {
    Vec3 a, b;
    fork_part1_voxel(m, st, sc, ext, v, cog, a, b);
    la += a;
    lb += b;
  };
  int ids[W];
  int v = 0;
  for (; v + W <= nv; v += W) {
    if (free_group<L>(m, v, ids)) {
      VL<L> a, b;
      fork_part1_group<L>(m, st, sc, ext, ids, cog, a, b);
      for (int k = 0; k < W; ++k) la += Vec3(a.x[k], a.y[k], a.z[k]);
      for (int k = 0; k < W; ++k) lb += Vec3(b.x[k], b.y[k], b.z[k]);
    } else {
      for (int k = 0; k < W; ++k)
        if (!m.voxel_fixed[v + k]) part1(v + k);
    }
  }
  for (; v < nv; ++v)
    if (!m.voxel_fixed[v]) part1(v);

  // 6. mid-step link update (state only)
  link_pass_state<L, LinkPass::state>(m, st, sc);

  // 7. correction moment -dL / dt / N_all (float), same for every non-fixed voxel
  const Vec3 dl = lb - la;
  const double n_all = static_cast<double>(nv);
  const double dtd = dt;
  const float me_x = static_cast<float>(-dl.x() / dtd / n_all);
  const float me_y = static_cast<float>(-dl.y() / dtd / n_all);
  const float me_z = static_cast<float>(-dl.z() / dtd / n_all);

  // 8. part 2
  double check = 0.0;
  for (v = 0; v + W <= nv; v += W) {
    if (free_group<L>(m, v, ids)) {
      fork_part2_group<L>(m, st, sc, ids, me_x, me_y, me_z, check);
    } else {
      for (int k = 0; k < W; ++k)
        if (!m.voxel_fixed[v + k]) fork_part2_voxel(m, st, sc, v + k, me_x, me_y, me_z, check);
    }
  }
  for (; v < nv; ++v)
    if (!m.voxel_fixed[v]) fork_part2_voxel(m, st, sc, v, me_x, me_y, me_z, check);
  return std::isfinite(check);
}

// §2.9 upstream single-pass symplectic Euler with the same forces for W free voxels v[0..W), one
// per lane (the floor contact of §2.8 and the large-rotation branch of quat_from_rotvec per lane
// in scalar code); adds the voxels' state to `check` as fork_part2_group.
template <class L>
inline void symplectic_group(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                             const int* v, double& check) {
  constexpr int W = L::W;
  using D = DV<L>;
  const double dt = m.dt_f;
  const auto& vc = m.voxel_const;
  VL<L> lsum, msum;
  gather_links_lanes<L>(m, sc, v, lsum, msum);
  const VoxelLanes<L> start = load_voxels<L>(m, st, v);
  VL<L> pos = start.pos, mom = start.mom, am = start.am;
  const QL<L> q = start.q;
  const VoxelConstL<L>& c = start.c;
  const D inv_mass = c.inv_mass;
  const VL<L> vel{mom.x * inv_mass, mom.y * inv_mass, mom.z * inv_mass};
  VL<L> f;
  rotate_c(q.w, q.x, q.y, q.z, lsum.x, lsum.y, lsum.z, f.x, f.y, f.z);
  if (!ext.empty()) {  // the reference's External stores float
    const VL<L> ext_f = load_external_force<L>(ext, v[0]);
    f = {f.x + ext_f.x, f.y + ext_f.y, f.z + ext_f.z};
  }
  const D c_glob = c.c_glob;
  f = {f.x - vel.x * c_glob, f.y - vel.y * c_glob, f.z - vel.z * c_glob};
  f.z = f.z + c.gravity_force;
  const VL<L> col = load_run<L>(sc.collision_force, v[0]);
  f = {f.x + col.x, f.y + col.y, f.z + col.z};
  int contact = 0;  // lane bits
  FloorContact fc[W];
  if (m.floor) {
    contact = ground_contacts<L>(m, pos, fc);
    const D zero = splat<L>(0.0);
    VL<L> fric{zero, zero, zero};
    for (int k = 0; k < W; ++k) {
      std::uint8_t& sf = st.static_friction[v[k]];
      if (!(contact >> k & 1)) {
        sf = 0;  // floor_force without contact
        continue;
      }
      const Vec3 fr = floor_force(vc[v[k]], fc[k], Vec3(vel.x[k], vel.y[k], vel.z[k]),
                                  Vec3(f.x[k], f.y[k], f.z[k]), sf);
      set_lane<L>(fric, k, fr);
    }
    f = {f.x + fric.x, f.y + fric.y, f.z + fric.z};
  }
  mom = {mom.x + f.x * dt, mom.y + f.y * dt, mom.z + f.z * dt};
  const D dt_m = L::round_to_float(dt * inv_mass);  // float dt * (1/m)
  VL<L> tr{mom.x * dt_m, mom.y * dt_m, mom.z * dt_m};
  for (int k = 0; k < W; ++k) {
    if (!(contact >> k & 1)) continue;
    Vec3 mk(mom.x[k], mom.y[k], mom.z[k]), tk(tr.x[k], tr.y[k], tr.z[k]);
    symplectic_static_capture(vc[v[k]], fc[k], Vec3(f.x[k], f.y[k], f.z[k]), mk, tk,
                              st.static_friction[v[k]]);
    set_lane<L>(mom, k, mk);
    set_lane<L>(tr, k, tk);
  }
  pos = {pos.x + tr.x, pos.y + tr.y, pos.z + tr.z};
  VL<L> rm;
  rotate_c(q.w, q.x, q.y, q.z, msum.x, msum.y, msum.z, rm.x, rm.y, rm.z);
  const D inv_i = c.inv_inertia;
  const D c_rot = c.c_glob_rot;
  const VL<L> cur_m{rm.x - am.x * inv_i * c_rot, rm.y - am.y * inv_i * c_rot,
                    rm.z - am.z * inv_i * c_rot};
  am = {am.x + cur_m.x * dt, am.y + cur_m.y * dt, am.z + cur_m.z * dt};
  turn_and_store<L>(pos, mom, am, q, inv_i, dt, st, v, check);
}

// One free voxel one lane wide (see fork_part1_voxel).
inline void symplectic_voxel(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                             int v, double& check) {
  symplectic_group<LanesScalar>(m, st, sc, ext, &v, check);
}

// §2.9 upstream single-pass symplectic Euler with the same forces; free voxels W at a time.
template <class L>
[[gnu::noinline]] bool symplectic_voxel_pass(const Model& m, State& st, Scratch& sc,
                                             std::span<const Vec3> ext) {
  constexpr int W = L::W;
  const int nv = m.voxel_count;
  st.previous_dt = m.dt_f;
  double check = 0.0;
  int ids[W];
  int v = 0;
  for (; v + W <= nv; v += W) {
    if (free_group<L>(m, v, ids)) {
      symplectic_group<L>(m, st, sc, ext, ids, check);
    } else {
      for (int k = 0; k < W; ++k)
        if (!m.voxel_fixed[v + k]) symplectic_voxel(m, st, sc, ext, v + k, check);
    }
  }
  for (; v < nv; ++v)
    if (!m.voxel_fixed[v]) symplectic_voxel(m, st, sc, ext, v, check);
  return std::isfinite(check);
}

}  // namespace
}  // namespace softevo::physics
