// The link pass (§2.2-2.6), written once over the lane traits (physics/lanes.hpp): W links at
// a time, one link per lane, links in small-angle and in large-angle mode in separate groups. A
// link that switches between the modes (rare) runs the same formulas one lane wide
// (LanesScalar), which performs the reference's scalar IEEE operations in their order; so every
// width gives the same bits. Internal to physics/.
//
// Memory layout the groups rely on: link ids run axis by axis (Model), so the full groups of a
// link pass are consecutive ids; the per-link state that the groups read and write (mode and
// velocity flags, strains, pos2 / angle vectors by component), the link damping multipliers and
// the constants by member (Model::link_const_members) are then plain vector loads and stores.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>

#include "physics/lane_math.hpp"
#include "physics/lanes.hpp"
#include "physics/lanes_scalar.hpp"
#include "physics/link_mode.hpp"
#include "physics/model.hpp"
#include "physics/quat.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"

namespace softevo::physics {
namespace {

// The float constants of W links / voxels as double lanes (exact), indexed by member.
template <class L>
struct LinkConstL {
  DV<L> e_area, area, a2, b1, b2, b3, sq_a1, sq_a2xip, sq_b1, sq_b2xfmp, sq_b3xip;
};
template <class L, bool kContig>
[[gnu::always_inline]] inline LinkConstL<L> gather_link_const(const Model& m, const int* id) {
  static_assert(offsetof(LinkConst, e_area) == 0 && offsetof(LinkConst, sq_b3xip) == 40);
  DV<L> d[11];
  if constexpr (kContig) {  // by member, already doubles (Model::link_const_members)
    for (int j = 0; j < 11; ++j) d[j] = load_lanes<L>(&m.link_const_members[j][id[0]]);
  } else {
    const float* p[L::W];
    for (int k = 0; k < L::W; ++k) p[k] = &m.link_const[id[k]].e_area;
    DV<L> all[12];
    gather_f12<L>(p, all);
    for (int j = 0; j < 11; ++j) d[j] = all[j];
  }
  return {d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7], d[8], d[9], d[10]};
}

// ---- §2.2 axis permutation ("as if the link pointed along +X") --------------------------------
// The axis is a template parameter: the link pass runs one axis at a time (Model::axis_link_begin),
// so the permutations are free register moves instead of a data-dependent switch per link end.
// Written once per component, generic over T (a lane vector, or a double); a quaternion permutes
// its vector part the same way.
template <Axis A, class T>
[[gnu::always_inline]] inline void to_x_c(T x, T y, T z, T& ox, T& oy, T& oz) {
  if constexpr (A == Axis::x) {
    ox = x, oy = y, oz = z;
  } else if constexpr (A == Axis::y) {
    ox = y, oy = -x, oz = z;
  } else {
    ox = z, oy = y, oz = -x;
  }
}
template <Axis A, class T>
[[gnu::always_inline]] inline void from_x_c(T x, T y, T z, T& ox, T& oy, T& oz) {
  if constexpr (A == Axis::x) {
    ox = x, oy = y, oz = z;
  } else if constexpr (A == Axis::y) {
    ox = -y, oy = x, oz = z;
  } else {
    ox = -z, oy = y, oz = x;
  }
}
template <Axis A, class L>
[[gnu::always_inline]] inline VL<L> to_x_lanes(DV<L> x, DV<L> y, DV<L> z) {
  VL<L> r;
  to_x_c<A>(x, y, z, r.x, r.y, r.z);
  return r;
}
template <Axis A, class L>
[[gnu::always_inline]] inline QL<L> to_x_lanes(const QL<L>& q) {
  QL<L> r;
  r.w = q.w;
  to_x_c<A>(q.x, q.y, q.z, r.x, r.y, r.z);
  return r;
}
template <Axis A, class L>
[[gnu::always_inline]] inline VL<L> from_x_lanes(const VL<L>& v) {
  VL<L> r;
  from_x_c<A>(v.x, v.y, v.z, r.x, r.y, r.z);
  return r;
}

constexpr float kStrainDiverged = 100.0f;  // §2.12 step 1

// What a link pass computes and stores (the link kernels' template argument).
enum class LinkPass {
  // end loads and the new link state (pos2, angles, strain, mode, local-velocity validity): the
  // reference's link pass, as the symplectic integrator runs it
  forces_and_state,
  // end loads, mode and validity only: the pneuvox step's first pass, whose pos2, angles and
  // strain its mid-step pass (§2.12 step 6) overwrites before anything reads them
  forces,
  // the link state without loads: the pneuvox mid-step pass (§2.9 item 6)
  state,
  // pos2, angles and strain only, after a pneuvox step refused by its `forces` pass (§2.12 step
  // 1): the state that pass left out. Mode and validity are as that pass left them; every link
  // stays in the mode that pass gave it (it decided on the same positions), so each link's values
  // are those of the reference's pass.
  restore_state,
};
constexpr bool computes_forces(LinkPass k) {
  return k == LinkPass::forces_and_state || k == LinkPass::forces;
}
constexpr bool stores_link_state(LinkPass k) {
  return k != LinkPass::forces;
}
constexpr bool marks_velocity_valid(LinkPass k) {
  return k != LinkPass::restore_state;
}

// The link frame of §2.3 "orient link" for W links, before the mode is known.
template <class L>
struct LinkFrameL {
  VL<L> d;   // P's position relative to N, in N's frame with the link axis turned to +X [m]
  QL<L> q2;  // P's orientation in that frame (the large-angle mode turns it further by q1)
};

// §2.3 orient link, up to the mode test: the frame of links ids[0..W) of axis A.
template <class L, Axis A>
[[gnu::always_inline]] inline LinkFrameL<L> orient_links(const Model& m, const State& st,
                                                         const int* ids) {
  constexpr int W = L::W;
  int n[W], p[W];
  for (int k = 0; k < W; ++k) {
    n[k] = m.link_neg[ids[k]];
    p[k] = m.link_pos[ids[k]];
  }
  const VL<L> pn = gather<L>(st.pos, n);
  const VL<L> pp = gather<L>(st.pos, p);
  const VL<L> d0 = to_x_lanes<A, L>(pp.x - pn.x, pp.y - pn.y, pp.z - pn.z);
  const QL<L> qn = to_x_lanes<A, L>(gather<L>(st.orient, n));
  const QL<L> r{qn.w, -qn.x, -qn.y, -qn.z};  // conj: the total rotation of N so far
  LinkFrameL<L> f;
  rotate_c(r.w, r.x, r.y, r.z, d0.x, d0.y, d0.z, f.d.x, f.d.y, f.d.z);
  const QL<L> qp = to_x_lanes<A, L>(gather<L>(st.orient, p));
  mul_c(r.w, r.x, r.y, r.z, qp.w, qp.x, qp.y, qp.z, f.q2.w, f.q2.x, f.q2.y, f.q2.z);
  return f;
}

// §2.3 step 3, the small-angle test with hysteresis, for links whose last update was in
// large-angle (kLarge) or small-angle mode with link direction d: the lanes whose link keeps its
// mode (bit k = lane k). Taken from products where they decide it (link_mode.hpp), else from the
// reference's float quotients:
//   turn = float((|d_z| + |d_y|) / d_x),   ext = float(|1 - d_x / L|).
template <class L, bool kLarge>
[[gnu::always_inline]] inline int lanes_keeping_mode(const Model& m, const VL<L>& d) {
  using D = DV<L>;
  using M = MV<L>;
  const auto mode =
      link_mode::test_without_division<kLarge, LaneMathOps<L>>(d.x, d.y, d.z, m.inv_rest_length);
  if (L::bits(reinterpret_cast<M>(mode.decided)) == kAllLanes<L>) [[likely]] {
    return ~L::bits(reinterpret_cast<M>(mode.switches)) & kAllLanes<L>;
  }
  const D l = splat<L>(m.rest_length);
  const D turn = L::round_to_float((abs_lanes<L>(d.z) + abs_lanes<L>(d.y)) / d.x);
  const D ext = L::round_to_float(abs_lanes<L>(1.0 - d.x / l));
  if constexpr (kLarge) {
    return ~L::bits((turn < splat<L>(kSmallBend)) & (ext < splat<L>(kSmallExt))) & kAllLanes<L>;
  } else {
    return ~L::bits((turn > splat<L>(kHysteresis * kSmallBend)) |
                    (ext > splat<L>(kHysteresis * kSmallExt))) &
           kAllLanes<L>;
  }
}

// The formulas of one link update (§2.3-2.6), shared by the link pass of one robot (update_links:
// lanes = links) and the batched step (physics/batch_kernels.hpp: lanes = evaluations of one
// body). Each lane performs the reference's scalar operations in their order.

// §2.3 large-angle mode: the rotation q1 of the link frame onto +X and its rotation vector a1, P's
// orientation q2 turned by it, pos2 = (|d| - L, 0, 0).
template <class L>
[[gnu::always_inline]] inline void large_angle_frame(const VL<L>& d, DV<L> l, QL<L>& q1, VL<L>& a1,
                                                     QL<L>& q2, VL<L>& pos2) {
  const DV<L> zero = splat<L>(0.0);
  const DV<L> len = L::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);  // |d|
  frame_to_pos_x_lanes<L>(d, len, q1, a1);
  QL<L> q12;
  mul_c(q1.w, q1.x, q1.y, q1.z, q2.w, q2.x, q2.y, q2.z, q12.w, q12.x, q12.y, q12.z);
  q2 = q12;
  pos2 = {len - l, zero, zero};
}

// Force and moment on ends N and P in the link frame (§2.4-2.5).
template <class L>
struct LinkLoadsL {
  VL<L> fn, fp, mn, mp;
};
// §2.4: sigma = E_L strain (linear material, float);
//   F_N = (sigma A, b1 y - b2 (t1z + t2z), b1 z + b2 (t1y + t2y)), F_P = -F_N
template <class L>
[[gnu::always_inline]] inline LinkLoadsL<L> elastic_link_loads(const LinkConstL<L>& c, DV<L> strain,
                                                               const VL<L>& pos2, const VL<L>& a1,
                                                               const VL<L>& a2) {
  using D = DV<L>;
  const D stress = L::round_to_float(c.e_area * strain);
  const D b1 = c.b1;
  const D b2 = c.b2;
  const D b3 = c.b3;
  const D a2c = c.a2;
  LinkLoadsL<L> r;
  r.fn = {L::round_to_float(stress * c.area), b1 * pos2.y - b2 * (a1.z + a2.z),
          b1 * pos2.z + b2 * (a1.y + a2.y)};
  r.fp = {-r.fn.x, -r.fn.y, -r.fn.z};
  r.mn = {a2c * (a2.x - a1.x), -b2 * pos2.z - b3 * (2.0 * a1.y + a2.y),
          b2 * pos2.y - b3 * (2.0 * a1.z + a2.z)};
  r.mp = {a2c * (a1.x - a2.x), -b2 * pos2.z - b3 * (a1.y + 2.0 * a2.y),
          b2 * pos2.y - b3 * (a1.z + 2.0 * a2.z)};
  return r;
}
// §2.5 internal damping from the change since the previous link update (old_*), with the end
// voxels' damping multipliers cn, cp: the elastic loads e plus the damping terms.
template <class L>
[[gnu::always_inline]] inline LinkLoadsL<L> damped_link_loads(
    const LinkConstL<L>& c, DV<L> cn, DV<L> cp, const LinkLoadsL<L>& e, const VL<L>& pos2,
    const VL<L>& a1, const VL<L>& a2, const VL<L>& old_pos2, const VL<L>& old_a1,
    const VL<L>& old_a2) {
  using D = DV<L>;
  const D dpx = 0.5 * (pos2.x - old_pos2.x), dpy = 0.5 * (pos2.y - old_pos2.y),
          dpz = 0.5 * (pos2.z - old_pos2.z);
  const D d1x = 0.5 * (a1.x - old_a1.x), d1y = 0.5 * (a1.y - old_a1.y),
          d1z = 0.5 * (a1.z - old_a1.z);
  const D d2x = 0.5 * (a2.x - old_a2.x), d2y = 0.5 * (a2.y - old_a2.y),
          d2z = 0.5 * (a2.z - old_a2.z);
  const D sq_a1 = c.sq_a1;
  const D sq_a2 = c.sq_a2xip;
  const D sq_b1 = c.sq_b1;
  const D sq_b2 = c.sq_b2xfmp;
  const D sq_b3 = c.sq_b3xip;
  const D vx = sq_a1 * dpx, vy = sq_b1 * dpy - sq_b2 * (d1z + d2z),
          vz = sq_b1 * dpz + sq_b2 * (d1y + d2y);
  const D hn = 0.5 * cn, hp = 0.5 * cp;
  LinkLoadsL<L> r;
  r.fn = {e.fn.x + cn * vx, e.fn.y + cn * vy, e.fn.z + cn * vz};
  r.fp = {e.fp.x - cp * vx, e.fp.y - cp * vy, e.fp.z - cp * vz};
  r.mn = {e.mn.x - hn * (-sq_a2 * (d2x - d1x)),
          e.mn.y - hn * (sq_b2 * dpz + sq_b3 * (2.0 * d1y + d2y)),
          e.mn.z - hn * (-sq_b2 * dpy + sq_b3 * (2.0 * d1z + d2z))};
  r.mp = {e.mp.x - hp * (sq_a2 * (d2x - d1x)),
          e.mp.y - hp * (sq_b2 * dpz + sq_b3 * (d1y + 2.0 * d2y)),
          e.mp.z - hp * (-sq_b2 * dpy + sq_b3 * (d1z + 2.0 * d2z))};
  return r;
}
// Lane by lane: a where `on`, else b.
template <class L>
[[gnu::always_inline]] inline VL<L> select(MV<L> on, const VL<L>& a, const VL<L>& b) {
  return {select<L>(on, a.x, b.x), select<L>(on, a.y, b.y), select<L>(on, a.z, b.z)};
}
template <class L>
[[gnu::always_inline]] inline QL<L> select(MV<L> on, const QL<L>& a, const QL<L>& b) {
  return {select<L>(on, a.w, b.w), select<L>(on, a.x, b.x), select<L>(on, a.y, b.y),
          select<L>(on, a.z, b.z)};
}
template <class L>
[[gnu::always_inline]] inline LinkLoadsL<L> select(MV<L> on, const LinkLoadsL<L>& a,
                                                   const LinkLoadsL<L>& b) {
  return {select<L>(on, a.fn, b.fn), select<L>(on, a.fp, b.fp), select<L>(on, a.mn, b.mn),
          select<L>(on, a.mp, b.mp)};
}
// v turned by the conjugate of q (§2.6: a link-frame load into an end voxel's frame).
template <class L>
[[gnu::always_inline]] inline VL<L> rotate_by_conj(const QL<L>& q, const VL<L>& v) {
  VL<L> r;
  rotate_c(q.w, -q.x, -q.y, -q.z, v.x, v.y, v.z, r.x, r.y, r.z);
  return r;
}

// §2.3-2.6 for the lanes `done` (bit k = lane k) of links ids[0..W) of axis A with frame f, in
// large-angle (kLarge) or small-angle mode: the new link state and, with forces
// (computes_forces(K)), the end loads, a strain > 100 ORed into `diverged`. With kContig the ids
// are consecutive (ids[k] = ids[0] + k), so the per-link flags and strains are read and written as
// runs. kSwitched: the links have just entered that mode (orient link's hysteresis), so their
// local velocity is not valid (§2.5: no damping) and their whole state is stored, mode flag and
// validity included, whatever K (the reference's update of a switching link). Otherwise they were
// in that mode at their last update; see link_group.
template <class L, Axis A, LinkPass K, bool kLarge, bool kSwitched, bool kContig>
[[gnu::always_inline]] inline void update_links(const Model& m, State& st, Scratch& sc,
                                                const int* ids, const LinkFrameL<L>& f, int done,
                                                bool& diverged) {
  constexpr int W = L::W;
  using D = DV<L>;
  constexpr bool kStoresState = stores_link_state(K) || kSwitched;
  constexpr bool kMarksValid = marks_velocity_valid(K) || kSwitched;
  const VL<L>& d = f.d;
  QL<L> q2 = f.q2;
  const D l = splat<L>(m.rest_length);
  const D zero = splat<L>(0.0);
  VL<L> pos2, a1;
  QL<L> q1;  // large-angle mode: rotation of the link frame onto +X
  if constexpr (kLarge) {
    large_angle_frame<L>(d, l, q1, a1, q2, pos2);
  } else {
    pos2 = {d.x - l, d.y, d.z};
    a1 = {zero, zero, zero};  // rotvec(identity)
  }
  const VL<L> a2 = rotvec_lanes<L>(q2);
  // §2.4: strain = pos2.x / L (float)
  const D strain = L::round_to_float(pos2.x / l);

  int valid = 0;  // lanes whose local velocity was valid (the forces pass reads it)
  if constexpr (computes_forces(K)) {
    if (L::bits(strain > splat<L>(kStrainDiverged)) & done) diverged = true;
    const LinkConstL<L> c = gather_link_const<L, kContig>(m, ids);
    LinkLoadsL<L> loads = elastic_link_loads<L>(c, strain, pos2, a1, a2);

    // §2.5 internal damping from the change since the previous link update, in the lanes with a
    // valid local velocity (skipped after a mode switch and at the first update)
    if constexpr (!kSwitched) {
      if constexpr (kContig) {
        valid = nonzero_flags<L>(&st.link_vel_valid[ids[0]]);
      } else {
        for (int k = 0; k < W; ++k) valid |= st.link_vel_valid[ids[k]] != 0 ? 1 << k : 0;
      }
    }
    if (valid) {
      const VL<L> old_pos2 = gather<L, kContig>(st.link_pos2, ids);
      VL<L> old_a1{zero, zero, zero};  // small-angle links: see link_group
      if constexpr (kLarge) old_a1 = gather<L, kContig>(st.link_angle1v, ids);
      const VL<L> old_a2 = gather<L, kContig>(st.link_angle2v, ids);
      D cn, cp;
      if constexpr (kContig) {
        cn = load_lanes<L>(&sc.link_damping_neg[ids[0]]);
        cp = load_lanes<L>(&sc.link_damping_pos[ids[0]]);
      } else {
        cn = make_lanes<L>([&](int k) { return sc.link_damping_neg[ids[k]]; });
        cp = make_lanes<L>([&](int k) { return sc.link_damping_pos[ids[k]]; });
      }
      const LinkLoadsL<L> damped =
          damped_link_loads<L>(c, cn, cp, loads, pos2, a1, a2, old_pos2, old_a1, old_a2);
      if (valid == kAllLanes<L>) {  // every lane (the usual case)
        loads = damped;
      } else {
        loads = select<L>(mask_of<L>(valid), damped, loads);
      }
    }
    // §2.6: in small-angle mode F_N and M_N are already in N's frame, in large-angle mode they
    // rotate by q1*; F_P, M_P rotate by q2*
    if constexpr (kLarge) {
      loads.fn = rotate_by_conj<L>(q1, loads.fn);
      loads.mn = rotate_by_conj<L>(q1, loads.mn);
    }
    const VL<L> fn_g = from_x_lanes<A, L>(loads.fn), mn_g = from_x_lanes<A, L>(loads.mn);
    const VL<L> fp_g = from_x_lanes<A, L>(rotate_by_conj<L>(q2, loads.fp));
    const VL<L> mp_g = from_x_lanes<A, L>(rotate_by_conj<L>(q2, loads.mp));
    // end loads of the lanes in `done`: (force, moment) of end N, then of end P; consecutive
    // links have consecutive records (2 ends x 6 doubles each)
    static_assert(sizeof(Scratch::EndLoad) == 6 * sizeof(double));
    if (kContig && done == kAllLanes<L>) {
      const DV<L> records[12] = {fn_g.x, fn_g.y, fn_g.z, mn_g.x, mn_g.y, mn_g.z,
                                 fp_g.x, fp_g.y, fp_g.z, mp_g.x, mp_g.y, mp_g.z};
      store_records<L>(records,
                       sc.link_end_load[2 * static_cast<std::size_t>(ids[0])].force.data());
    } else {
      double* out[4][W];
      for (int k = 0; k < W; ++k) {
        Scratch::EndLoad* load = &sc.link_end_load[2 * static_cast<std::size_t>(ids[k])];
        out[0][k] = load[0].force.data();
        out[1][k] = load[0].moment.data();
        out[2][k] = load[1].force.data();
        out[3][k] = load[1].moment.data();
      }
      scatter3<L>(out[0], fn_g.x, fn_g.y, fn_g.z, done);
      scatter3<L>(out[1], mn_g.x, mn_g.y, mn_g.z, done);
      scatter3<L>(out[2], fp_g.x, fp_g.y, fp_g.z, done);
      scatter3<L>(out[3], mp_g.x, mp_g.y, mp_g.z, done);
    }
  }
  // float(strain) per lane (exact: strain is a float value); the local velocity becomes valid
  // (already is, after a step)
  if (kContig && done == kAllLanes<L>) {
    if constexpr (kStoresState) to_floats<L>(strain, &st.link_strain[ids[0]]);
    if (kMarksValid && valid != kAllLanes<L>) std::memset(&st.link_vel_valid[ids[0]], 1, W);
  } else {
    if constexpr (kStoresState) {
      float strain_f[W];
      to_floats<L>(strain, strain_f);
      for (int k = 0; k < W; ++k) {
        if (!(done >> k & 1)) continue;
        st.link_strain[ids[k]] = strain_f[k];
      }
    }
    if (kMarksValid && (valid & done) != done) {
      for (int k = 0; k < W; ++k)
        if (done >> k & 1) st.link_vel_valid[ids[k]] = 1;
    }
  }
  if constexpr (kSwitched) {
    for (int k = 0; k < W; ++k)
      if (done >> k & 1) st.link_small_angle[ids[k]] = kLarge ? 0 : 1;
  }
  if constexpr (kStoresState) {
    scatter<L, kContig>(pos2, st.link_pos2, ids, done);
    // a link staying in small-angle mode keeps its stored angle1v = 0 (see link_group)
    if constexpr (kLarge || kSwitched) scatter<L, kContig>(a1, st.link_angle1v, ids, done);
    scatter<L, kContig>(a2, st.link_angle2v, ids, done);
  }
}

// Links ids[0..W) of axis A, all in the same mode at their last update: small-angle mode
// (kLarge false) or large-angle mode (kLarge true), the caller's choice. Each lane whose link
// stays in that mode (§2.3 hysteresis) is updated (update_links); returns those lanes (bit k =
// lane k). Lanes that switch mode are left unchanged for the caller's links_switching_mode.
// A link may fill several lanes (padding of a partial group): all loads precede all stores, so
// its lanes compute and store the same values.
// Invariant used for small-angle links: a link whose last update was in small-angle mode has
// angle1v = (+0, +0, +0) stored (every small-angle update stores rotvec(identity) = 0, and so
// does initial_state), so the old angle1v is the constant zero and the new one need not be
// stored again. The mode flag of a lane that stays in its mode need not be stored either.
template <class L, Axis A, LinkPass K, bool kLarge, bool kContig>
[[gnu::always_inline]] inline int link_group(const Model& m, State& st, Scratch& sc, const int* ids,
                                             bool& diverged) {
  const LinkFrameL<L> f = orient_links<L, A>(m, st, ids);
  const int done = lanes_keeping_mode<L, kLarge>(m, f.d);
  if (!done) return 0;
  update_links<L, A, K, kLarge, false, kContig>(m, st, sc, ids, f, done, diverged);
  return done;
}

// The lanes of a group that link_group left undone: their links leave large-angle (kLarge) or
// small-angle mode. Each runs the same formulas one lane wide in its new mode. Out of line: rare.
template <Axis A, LinkPass K, bool kLarge>
[[gnu::noinline]] void links_switching_mode(const Model& m, State& st, Scratch& sc,
                                            const int* group, int count, int done, bool& diverged) {
  for (int k = 0; k < count; ++k) {
    if (done >> k & 1) continue;
    const LinkFrameL<LanesScalar> f = orient_links<LanesScalar, A>(m, st, &group[k]);
    update_links<LanesScalar, A, K, !kLarge, true, false>(m, st, sc, &group[k], f, 1, diverged);
  }
}

// The links list[0..count) of axis A, all in small-angle (!kLarge) or large-angle (kLarge) mode at
// their last update, W at a time (the last group padded with its last link).
template <class L, Axis A, LinkPass K, bool kLarge>
[[gnu::noinline]] void run_link_list(const Model& m, State& st, Scratch& sc, const int* list,
                                     int count, bool& diverged) {
  constexpr int W = L::W;
  int j = 0;
  for (; j + W <= count; j += W) {
    const int done = link_group<L, A, K, kLarge, false>(m, st, sc, list + j, diverged);
    if (done != kAllLanes<L>)
      links_switching_mode<A, K, kLarge>(m, st, sc, list + j, W, done, diverged);
  }
  if (j < count) {
    int group[W];
    for (int k = 0; k < W; ++k) group[k] = list[std::min(j + k, count - 1)];
    const int done = link_group<L, A, K, kLarge, false>(m, st, sc, group, diverged);
    if (done != kAllLanes<L>)
      links_switching_mode<A, K, kLarge>(m, st, sc, group, count - j, done, diverged);
  }
}

// Full groups of consecutive links from link j on, as long as all W links of the next group are
// in small-angle mode (!kLarge) or all in large-angle mode (kLarge); returns the first link not
// handled. One call runs a whole stretch of groups (the usual case: a solid body is one stretch
// per axis), so the call and its register saves are paid once per stretch.
template <class L, Axis A, LinkPass K, bool kLarge>
[[gnu::noinline]] int run_link_stretch(const Model& m, State& st, Scratch& sc, int j, int end,
                                       bool& diverged) {
  constexpr int W = L::W;
  constexpr int kMode = kLarge ? 0 : kAllLanes<L>;  // small-angle flags of the whole group
  for (; j + W <= end && nonzero_flags<L>(&st.link_small_angle[j]) == kMode; j += W) {
    int group[W];
    for (int k = 0; k < W; ++k) group[k] = j + k;
    const int done = link_group<L, A, K, kLarge, true>(m, st, sc, group, diverged);
    if (done != kAllLanes<L>)
      links_switching_mode<A, K, kLarge>(m, st, sc, group, W, done, diverged);
  }
  return j;
}

// Link pass (§2.3-2.6) over the links of axis A: links go through link_group W at a time, those
// in small-angle mode at their last update and those in large-angle mode in separate groups (a
// lane that switches mode runs one lane wide, links_switching_mode). W consecutive links of the
// axis (ids are contiguous per axis, see Model) that share a mode, the usual case, form a group as
// they are; the others are collected per mode into lists (Scratch) and run after the axis's
// stretches. Links are independent within a pass, so this order gives the same results as list
// order. With forces (computes_forces(K)) the end loads are computed and the return value is true
// if any strain > 100; without, only the link state (LinkPass::state and restore_state).
template <class L, Axis A, LinkPass K>
bool link_pass_axis(const Model& m, State& st, Scratch& sc) {
  constexpr int W = L::W;
  bool diverged = false;
  const int begin = m.axis_link_begin[static_cast<int>(A)];
  const int end = m.axis_link_begin[static_cast<int>(A) + 1];
  // links of mixed groups, collected per mode (without a branch: mixed groups have no pattern)
  int* small = sc.link_list_small.data();
  int* large = sc.link_list_large.data();
  int small_count = 0, large_count = 0;
  auto collect = [&](int i) {
    const int is_small = st.link_small_angle[i] != 0;
    small[small_count] = i;
    large[large_count] = i;
    small_count += is_small;
    large_count += 1 - is_small;
  };
  int j = begin;
  while (j + W <= end) {
    const int small_lanes = nonzero_flags<L>(&st.link_small_angle[j]);
    if (small_lanes == kAllLanes<L>) {
      j = run_link_stretch<L, A, K, false>(m, st, sc, j, end, diverged);
    } else if (small_lanes == 0) {
      j = run_link_stretch<L, A, K, true>(m, st, sc, j, end, diverged);
    } else {
      for (int k = 0; k < W; ++k) collect(j + k);
      j += W;
    }
  }
  for (; j < end; ++j) collect(j);
  if (small_count > 0) run_link_list<L, A, K, false>(m, st, sc, small, small_count, diverged);
  if (large_count > 0) run_link_list<L, A, K, true>(m, st, sc, large, large_count, diverged);
  return diverged;
}

// Full link pass (§2.3-2.6) over all links with forces (K = forces_and_state or forces). Returns
// true if any strain > 100. (The passes are kept out of line, once per step, so that profiles
// attribute their cost.)
template <class L, LinkPass K>
[[gnu::noinline]] bool link_pass_forces(const Model& m, State& st, Scratch& sc) {
  static_assert(computes_forces(K));
  // c_V = 2 sqrt(m_V) zeta_int / previousDt_V (float, §2.5); only read by links with a valid
  // local velocity, i.e. after a step has set previous_dt
  const float prev_dt = st.previous_dt;
  if (!(prev_dt == sc.link_damping_dt)) {  // a pure function of prev_dt: recompute on change only
    for (int i = 0; i < m.link_count; ++i) {
      sc.link_damping_neg[i] = m.voxel_const[m.link_neg[i]].damp_base / prev_dt;
      sc.link_damping_pos[i] = m.voxel_const[m.link_pos[i]].damp_base / prev_dt;
    }
    sc.link_damping_dt = prev_dt;
  }
  const bool dx = link_pass_axis<L, Axis::x, K>(m, st, sc);
  const bool dy = link_pass_axis<L, Axis::y, K>(m, st, sc);
  const bool dz = link_pass_axis<L, Axis::z, K>(m, st, sc);
  return dx || dy || dz;
}

// Link pass without forces (K = state: the mid-step pass of the fork, §2.9 item 6; K =
// restore_state: the link state a refused pneuvox step's `forces` pass left out).
template <class L, LinkPass K>
[[gnu::noinline]] void link_pass_state(const Model& m, State& st, Scratch& sc) {
  static_assert(!computes_forces(K));
  link_pass_axis<L, Axis::x, K>(m, st, sc);
  link_pass_axis<L, Axis::y, K>(m, st, sc);
  link_pass_axis<L, Axis::z, K>(m, st, sc);
}

}  // namespace
}  // namespace softevo::physics
