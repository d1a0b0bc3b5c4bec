// The passes of one physics time step (pneuvox-model.md §2.3-2.13), written once over a SIMD lane
// width. Internal to physics/: included only by the step_*.cpp translation units, each of which
// supplies its lane traits L and is compiled for its own instruction set (step.cpp: SSE2, W = 2;
// step_avx2.cpp: AVX2, W = 4). Everything here has internal linkage (anonymous namespace), so
// the copies built with different instruction sets never meet in the linker; the only thing a
// translation unit exports is its StepKernels table (checked by the PhysicsIsa ctest).
//
// Precision: state is double; constants are float (Model); products the reference forms in float
// (dt * (1/m), k_pen * pen, mu * N, strain, stress * A, collision forces) are formed in float
// here too, and a float times a double is promoted exactly as in the reference. The build uses
// -ffp-contract=off, so the written operation order is the executed one.
//
// Lanes: links (small-angle and large-angle mode in separate groups) and free voxels go through
// the passes W at a time, one link or voxel per lane of a W x double vector. Every lane performs
// exactly the scalar path's IEEE operations in the same order (the quaternion formulas are the
// shared templates of quat.hpp; float roundings are a float conversion of the same double;
// float x float products and float / float quotients are formed in double and rounded to float,
// which gives the float result exactly since 53 >= 2 x 24 + 2), so every width gives results
// bit-identical to the scalar reference path (link_scalar, fork_part1_voxel, ...), and thus to
// each other. The acos / sin / cos branches of rotvec, frame_to_pos_x and quat_from_rotvec run on
// the lanes too (physics/reproducible_math.hpp: the scalar functions' bits); rare branches (a link
// switching mode, floor contact) run per lane in the scalar code.
//
// Lane traits L: static constexpr int W; using D = double vector of W lanes; using M = long long
// vector of W lanes (comparison result, all ones = true); static D round_to_float(D);
// static D sqrt(D) (IEEE, correctly rounded); static int bits(M) (bit k = lane k true);
// optionally faster transposing loads / stores (gather3, gather4, scatter3, gather_f12,
// load_records, store_records, to_floats; generic fallbacks below).
//
// Memory layout the groups rely on: link ids run axis by axis (Model), so the full groups of a
// link pass are consecutive ids; voxel groups are consecutive voxel ids. Per-link state that the
// groups read and write (mode and velocity flags, strains, pos2 / angle vectors by component),
// the link damping multipliers and the constants by member (Model::*_const_members) are then
// plain vector loads and stores; voxel and end-load records are runs of W records.
#pragma once

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <utility>

#include "physics/link_mode.hpp"
#include "physics/model.hpp"
#include "physics/pneumatics.hpp"
#include "physics/pneumatics_triangle.hpp"
#include "physics/reproducible_math.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {
namespace {

// ---- §2.2 axis permutation ("as if the link pointed along +X") --------------------------------
// The axis is a template parameter: the link pass runs one axis at a time (Model::axis_link_begin),
// so the permutations are free register moves instead of a data-dependent switch per link end.
// Written once per component, generic over T (double, or a lane vector of the grouped passes);
// a quaternion permutes its vector part the same way.
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
template <Axis A>
inline Vec3 to_x(double x, double y, double z) {
  Vec3 r;
  to_x_c<A>(x, y, z, r.x(), r.y(), r.z());
  return r;
}
template <Axis A>
inline Quat to_x(const Quat& q) {
  Quat r{q.w};
  to_x_c<A>(q.x, q.y, q.z, r.x, r.y, r.z);
  return r;
}
template <Axis A>
inline Vec3 from_x(const Vec3& v) {
  Vec3 r;
  from_x_c<A>(v.x(), v.y(), v.z(), r.x(), r.y(), r.z());
  return r;
}

constexpr float kStrainDiverged = 100.0f;  // §2.12 item 1

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
  // pos2, angles and strain only, after a pneuvox step refused by its `forces` pass (§2.12 item
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

// Result of the link kinematics (§2.3): the new link state and the frame quaternions. Kept in
// locals (not written through State references) so the force code reads registers.
struct LinkKinematics {
  Vec3 pos2;  // [m]
  Vec3 a1v;   // [rad]
  Vec3 a2v;   // [rad]
  Quat q1;    // rotation to +X of the large-angle frame (identity in small-angle mode)
  Quat q2;    // orientation of P in the link frame
  bool small;
  bool switched;  // the hysteresis changed mode: local velocity becomes invalid
};

// §2.3 "orient link": pos2, angle1v, angle2v and the small-angle flag with hysteresis. Reads
// voxel state and the link's current mode only; the caller stores the result.
template <Axis A>
inline void orient_link(const Model& m, const State& st, int i, LinkKinematics& k) {
  const int n = m.link_neg[i], p = m.link_pos[i];
  const Vec3& pn = st.pos[n];
  const Vec3& pp = st.pos[p];
  const Vec3 d0 = to_x<A>(pp.x() - pn.x(), pp.y() - pn.y(), pp.z() - pn.z());
  const Quat r = conj(to_x<A>(st.orient[n]));  // total rotation so far = conj(q1)
  const Vec3 d = rotate(r, d0);
  k.q1 = Quat{};
  k.q2 = mul(r, to_x<A>(st.orient[p]));
  const double l = m.rest_length;
  // §2.3 step 3: small-angle test in float with floating-point abs.
  const float turn = static_cast<float>((std::fabs(d.z()) + std::fabs(d.y())) / d.x());
  const float ext = static_cast<float>(std::fabs(1 - d.x() / l));
  const bool was_small = st.link_small_angle[i] != 0;
  bool small = was_small;
  if (!was_small && turn < kSmallBend && ext < kSmallExt) {
    small = true;
  } else if (was_small && (turn > kHysteresis * kSmallBend || ext > kHysteresis * kSmallExt)) {
    small = false;
  }
  k.small = small;
  k.switched = small != was_small;
  if (small) {
    k.pos2 = Vec3(d.x() - l, d.y(), d.z());
    k.a1v = Vec3::Zero();  // rotvec(identity) = 0
  } else {
    frame_to_pos_x(d, k.q1, k.a1v);
    k.q2 = mul(k.q1, k.q2);
    k.pos2 = Vec3(std::sqrt(d.x() * d.x() + d.y() * d.y() + d.z() * d.z()) - l, 0.0, 0.0);
  }
  k.a2v = rotvec(k.q2);
}

// Full link update (§2.3-2.6) of link i of axis A, any mode: the reference path. Returns true
// if its strain > 100.
template <Axis A>
bool link_scalar(const Model& m, State& st, Scratch& sc, int i) {
  LinkKinematics k;
  orient_link<A>(m, st, i, k);
  const Vec3& pos2 = k.pos2;
  const Vec3& a1 = k.a1v;
  const Vec3& a2 = k.a2v;
  const LinkConst& c = m.link_const[i];

  // §2.4: strain = pos2.x / L (float), sigma = E_L strain (linear material, float)
  const float strain = static_cast<float>(pos2.x() / m.rest_length);
  const bool diverged = strain > kStrainDiverged;
  const float stress = c.e_area * strain;
  const float b1 = c.b1, b2 = c.b2, b3 = c.b3, a2c = c.a2;
  // §2.4 F_N = (sigma A, b1 y - b2 (t1z + t2z), b1 z + b2 (t1y + t2y)), F_P = -F_N
  Vec3 fn(static_cast<double>(stress * c.area), b1 * pos2.y() - b2 * (a1.z() + a2.z()),
          b1 * pos2.z() + b2 * (a1.y() + a2.y()));
  Vec3 fp(-fn.x(), -fn.y(), -fn.z());
  Vec3 mn(a2c * (a2.x() - a1.x()), -b2 * pos2.z() - b3 * (2 * a1.y() + a2.y()),
          b2 * pos2.y() - b3 * (2 * a1.z() + a2.z()));
  Vec3 mp(a2c * (a1.x() - a2.x()), -b2 * pos2.z() - b3 * (a1.y() + 2 * a2.y()),
          b2 * pos2.y() - b3 * (a1.z() + 2 * a2.z()));

  // §2.5 internal damping from the change since the previous link update; skipped (and the
  // flag set) after a mode switch or at the first update
  if (st.link_vel_valid[i] && !k.switched) {
    const Vec3 old_pos2 = st.link_pos2[i];
    const Vec3 old_a1 = st.link_angle1v[i];
    const Vec3 old_a2 = st.link_angle2v[i];
    const double dpx = 0.5 * (pos2.x() - old_pos2.x()), dpy = 0.5 * (pos2.y() - old_pos2.y()),
                 dpz = 0.5 * (pos2.z() - old_pos2.z());
    const double d1x = 0.5 * (a1.x() - old_a1.x()), d1y = 0.5 * (a1.y() - old_a1.y()),
                 d1z = 0.5 * (a1.z() - old_a1.z());
    const double d2x = 0.5 * (a2.x() - old_a2.x()), d2y = 0.5 * (a2.y() - old_a2.y()),
                 d2z = 0.5 * (a2.z() - old_a2.z());
    const float sq_a1 = c.sq_a1, sq_a2 = c.sq_a2xip, sq_b1 = c.sq_b1, sq_b2 = c.sq_b2xfmp,
                sq_b3 = c.sq_b3xip;
    const double vx = sq_a1 * dpx, vy = sq_b1 * dpy - sq_b2 * (d1z + d2z),
                 vz = sq_b1 * dpz + sq_b2 * (d1y + d2y);
    // c_V = 2 sqrt(m_V) zeta_int / previousDt_V (float)
    const double cn = sc.link_damping_neg[i], cp = sc.link_damping_pos[i];  // float values
    fn += Vec3(cn * vx, cn * vy, cn * vz);
    fp -= Vec3(cp * vx, cp * vy, cp * vz);
    const double hn = 0.5 * cn, hp = 0.5 * cp;
    mn -= Vec3(hn * (-sq_a2 * (d2x - d1x)), hn * (sq_b2 * dpz + sq_b3 * (2 * d1y + d2y)),
               hn * (-sq_b2 * dpy + sq_b3 * (2 * d1z + d2z)));
    mp -= Vec3(hp * (sq_a2 * (d2x - d1x)), hp * (sq_b2 * dpz + sq_b3 * (d1y + 2 * d2y)),
               hp * (-sq_b2 * dpy + sq_b3 * (d1z + 2 * d2z)));
  }
  st.link_vel_valid[i] = 1;
  st.link_small_angle[i] = k.small;
  st.link_strain[i] = strain;
  st.link_pos2.set(i, pos2);
  st.link_angle1v.set(i, a1);
  st.link_angle2v.set(i, a2);

  // §2.6 back to the end voxels' local frames
  if (!k.small) {
    fn = rotate_inv(k.q1, fn);
    mn = rotate_inv(k.q1, mn);
  }
  fp = rotate_inv(k.q2, fp);
  mp = rotate_inv(k.q2, mp);
  Scratch::EndLoad* out = &sc.link_end_load[2 * static_cast<std::size_t>(i)];
  out[0].force = from_x<A>(fn);
  out[0].moment = from_x<A>(mn);
  out[1].force = from_x<A>(fp);
  out[1].moment = from_x<A>(mp);
  return diverged;
}

// Mid-step link update of the fork (§2.9 item 6): same kinematics and state update, forces
// discarded (so they are not computed). The local-velocity flag ends up set, as after any update.
template <Axis A>
void link_scalar_state_only(const Model& m, State& st, int i) {
  LinkKinematics k;
  orient_link<A>(m, st, i, k);
  st.link_strain[i] = static_cast<float>(k.pos2.x() / m.rest_length);
  st.link_vel_valid[i] = 1;
  st.link_small_angle[i] = k.small;
  st.link_pos2.set(i, k.pos2);
  st.link_angle1v.set(i, k.a1v);
  st.link_angle2v.set(i, k.a2v);
}

// ---- lanes --------------------------------------------------------------------------------------
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

// Bit k set where the byte flag p[k] is non-zero, for the W consecutive flags at p.
template <class L>
[[gnu::always_inline]] inline int nonzero_flags(const std::uint8_t* p) {
  static_assert(L::W <= 4);
  std::uint32_t word = 0;
  std::memcpy(&word, p, L::W);
  const __m128i zero =
      _mm_cmpeq_epi8(_mm_cvtsi32_si128(static_cast<int>(word)), _mm_setzero_si128());
  return ~_mm_movemask_epi8(zero) & kAllLanes<L>;
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
// L::gather_f12); these are the generic fallbacks. Records: 3 or 4 consecutive doubles, or 12
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

// Lane k of (x, y, z) as the floats (x_k, y_k, z_k, 0) (round to nearest).
template <class L>
[[gnu::always_inline]] inline void float_rows(DV<L> x, DV<L> y, DV<L> z, __m128 (&rows)[L::W]) {
  if constexpr (requires { L::float_rows(x, y, z, rows); }) {
    L::float_rows(x, y, z, rows);
  } else {
    for (int k = 0; k < L::W; ++k)
      rows[k] = _mm_setr_ps(static_cast<float>(x[k]), static_cast<float>(y[k]),
                            static_cast<float>(z[k]), 0.0f);
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

// The reproducible acos / sin / cos (physics/reproducible_math.hpp) on lane vectors.
template <class L>
struct LaneMathOps {
  [[gnu::always_inline]] static DV<L> sqrt(DV<L> x) { return L::sqrt(x); }
  [[gnu::always_inline]] static DV<L> abs(DV<L> x) { return abs_lanes<L>(x); }
  template <class Mask>  // a comparison of DV<L> (long or long long lanes)
  [[gnu::always_inline]] static DV<L> select(Mask mask, DV<L> a, DV<L> b) {
    return physics::select<L>(reinterpret_cast<MV<L>>(mask), a, b);
  }
};
template <class L>
[[gnu::always_inline]] inline DV<L> acos_lanes(DV<L> x) {
  return rmath::acos<LaneMathOps<L>>(x);
}
// rmath::sincos on lanes: lanes beyond the reduction's range (only an exploded voxel) per lane.
template <class L>
[[gnu::always_inline]] inline void sincos_lanes(DV<L> x, DV<L>& sin_x, DV<L>& cos_x) {
  rmath::sincos_reduced<LaneMathOps<L>>(x, sin_x, cos_x);
  const int far = ~L::bits(abs_lanes<L>(x) <= rmath::kSinCosReducedLimit) & kAllLanes<L>;
  if (far) [[unlikely]] {
    for (int k = 0; k < L::W; ++k) {
      if (!(far >> k & 1)) continue;
      double s, c;
      rmath::sincos(x[k], s, c);
      sin_x[k] = s;
      cos_x[k] = c;
    }
  }
}

// quat_from_rotvec (§2.11) on lanes, both branches in SIMD (the sin / cos one only when a lane
// needs it).
template <class L>
inline QL<L> quat_from_rotvec_lanes(const VL<L>& r) {
  const DV<L> hx = r.x / 2.0, hy = r.y / 2.0, hz = r.z / 2.0;
  const DV<L> t = hx * hx + hy * hy + hz * hz;
  DV<L> w = 1.0 - t / 2.0, s = 1.0 - t / 6.0;
  const MV<L> taylor = t * t < kRotvecToQuatTaylorBelow;
  if (L::bits(taylor) != kAllLanes<L>) {
    DV<L> sinc, cos_mag;
    rmath::sinc_cos_of_square(t, sinc, cos_mag);
    const MV<L> small = t <= rmath::kSincCosSquareLimit;
    if (L::bits(small) != kAllLanes<L>) [[unlikely]] {  // a voxel turning > 1.5 rad per step
      const DV<L> mag = L::sqrt(t);
      DV<L> sin_mag, cos_big;
      sincos_lanes<L>(mag, sin_mag, cos_big);
      sinc = select<L>(small, sinc, sin_mag / mag);
      cos_mag = select<L>(small, cos_mag, cos_big);
    }
    w = select<L>(taylor, w, cos_mag);
    s = select<L>(taylor, s, sinc);
  }
  return {w, hx * s, hy * s, hz * s};
}
// §2.2 permutations on lanes (to_x_c / from_x_c, as the scalar to_x / from_x)
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

// rotvec (§2.11) on lanes, every branch in SIMD (the acos one only when a lane needs it).
template <class L>
inline VL<L> rotvec_lanes(const QL<L>& q) {
  using D = DV<L>;
  const D zero = splat<L>(0.0);
  const MV<L> unit = (q.w >= 1.0) | (q.w <= -1.0);
  const D t = 1.0 - q.w * q.w;
  const MV<L> taylor = t < kQuatToRotvecTaylorBelow;
  const D k = L::sqrt((2.0 - 2.0 * q.w) / t);
  VL<L> v{q.x * 2.0 * k, q.y * 2.0 * k, q.z * 2.0 * k};
  if (L::bits(unit | taylor) != kAllLanes<L>) {
    const D a = acos_lanes<L>(q.w), rs = L::sqrt(t);
    const D f = 2.0 * a / rs;  // one division (physics revision 3), as the scalar rotvec
    v.x = select<L>(taylor, v.x, q.x * f);
    v.y = select<L>(taylor, v.y, q.y * f);
    v.z = select<L>(taylor, v.z, q.z * f);
  }
  return {select<L>(unit, zero, v.x), select<L>(unit, zero, v.y), select<L>(unit, zero, v.z)};
}

// frame_to_pos_x (§2.11, quat.hpp) on lanes, every branch in SIMD (the closed-form one only when
// a lane needs it); len = |d| = sqrt(d.x^2 + d.y^2 + d.z^2), which the caller also needs.
template <class L>
inline void frame_to_pos_x_lanes(const VL<L>& d, const DV<L>& len, QL<L>& q1, VL<L>& a1) {
  using D = DV<L>;
  const D zero = splat<L>(0.0), one = splat<L>(1.0);
  const D a = d.y / d.x, b = d.z / d.x;
  const MV<L> taylor = (abs_lanes<L>(a) < kNearPosXBelow) & (abs_lanes<L>(b) < kNearPosXBelow);
  const MV<L> null = (d.x == 0.0) & (d.y == 0.0) & (d.z == 0.0);
  const D y = b / 2.0, z = -a / 2.0;
  QL<L> q{1.0 - 0.5 * (y * y + z * z), zero, y, z};
  MV<L> closed = mask_of<L>(0);  // lanes of the closed-form branch
  VL<L> a_closed;
  if (L::bits(taylor | null) != kAllLanes<L>) {
    const D nx = d.x / len, ny = d.y / len, nz = d.z / len;
    const MV<L> reversed = nx < kReversedBelow;
    const D c = L::sqrt((1.0 + nx) * 0.5), h = 0.5 / c;
    closed = ~(taylor | null | reversed | (1.0 - c * c < kQuatToRotvecTaylorBelow));
    q.w = select<L>(taylor, q.w, select<L>(reversed, zero, c));
    q.y = select<L>(taylor, q.y, select<L>(reversed, one, nz * h));
    q.z = select<L>(taylor, q.z, select<L>(reversed, zero, -ny * h));
    const D f = acos_lanes<L>(nx) / L::sqrt(ny * ny + nz * nz);
    a_closed = {zero, nz * f, -ny * f};
  }
  q1 = {select<L>(null, one, q.w), q.x, select<L>(null, zero, q.y), select<L>(null, zero, q.z)};
  if (L::bits(closed) == kAllLanes<L>) {
    a1 = a_closed;
  } else {
    a1 = rotvec_lanes<L>(q1);  // the reference rotvec of the other branches' q1
    if (L::bits(closed)) {
      a1.x = select<L>(closed, a_closed.x, a1.x);
      a1.y = select<L>(closed, a_closed.y, a1.y);
      a1.z = select<L>(closed, a_closed.z, a1.z);
    }
  }
}

// Links ids[0..W) of axis A, all in the same mode at their last update: small-angle mode
// (kLarge false) or large-angle mode (kLarge true), the caller's choice. With kContig the ids are
// consecutive (ids[k] = ids[0] + k), so the per-link flags and strains are read and written as
// runs. Each lane whose link stays in that mode (§2.3 hysteresis) is updated like link_scalar
// (or link_scalar_state_only without forces), its strain > 100 ORed into `diverged`; returns those
// lanes (bit k = lane k). Lanes that switch mode are left unchanged for the caller's link_scalar.
// A link may fill several lanes (padding of a partial group): all loads precede all stores, so
// its lanes compute and store the same values.
// Invariant used for small-angle links: a link whose last update was in small-angle mode has
// angle1v = (+0, +0, +0) stored (every small-angle update stores rotvec(identity) = 0, and so
// does initial_state), so the old angle1v is the constant zero and the new one need not be
// stored again. The mode flag of a lane that stays in its mode need not be stored either.
template <class L, Axis A, LinkPass K, bool kLarge, bool kContig>
[[gnu::always_inline]] inline int link_group(const Model& m, State& st, Scratch& sc, const int* ids,
                                             bool& diverged) {
  constexpr int W = L::W;
  using D = DV<L>;
  using M = MV<L>;
  int n[W], p[W];
  for (int k = 0; k < W; ++k) {
    n[k] = m.link_neg[ids[k]];
    p[k] = m.link_pos[ids[k]];
  }
  // §2.3 orient link (see orient_link)
  const VL<L> pn = gather<L>(st.pos, n);
  const VL<L> pp = gather<L>(st.pos, p);
  const VL<L> d0 = to_x_lanes<A, L>(pp.x - pn.x, pp.y - pn.y, pp.z - pn.z);
  const QL<L> qn = to_x_lanes<A, L>(gather<L>(st.orient, n));
  const QL<L> r{qn.w, -qn.x, -qn.y, -qn.z};  // conj
  VL<L> d;
  rotate_c(r.w, r.x, r.y, r.z, d0.x, d0.y, d0.z, d.x, d.y, d.z);
  const QL<L> qp = to_x_lanes<A, L>(gather<L>(st.orient, p));
  QL<L> q2;
  mul_c(r.w, r.x, r.y, r.z, qp.w, qp.x, qp.y, qp.z, q2.w, q2.x, q2.y, q2.z);
  const D l = splat<L>(m.rest_length);
  // §2.3 mode test (see orient_link), from products where they decide it (link_mode.hpp)
  const auto mode =
      link_mode::test_without_division<kLarge, LaneMathOps<L>>(d.x, d.y, d.z, m.inv_rest_length);
  int done;  // lanes that stay in their mode
  if (L::bits(reinterpret_cast<M>(mode.decided)) == kAllLanes<L>) [[likely]] {
    done = ~L::bits(reinterpret_cast<M>(mode.switches)) & kAllLanes<L>;
  } else {
    const D turn = L::round_to_float((abs_lanes<L>(d.z) + abs_lanes<L>(d.y)) / d.x);
    const D ext = L::round_to_float(abs_lanes<L>(1.0 - d.x / l));
    if constexpr (kLarge) {
      done = ~L::bits((turn < splat<L>(kSmallBend)) & (ext < splat<L>(kSmallExt))) & kAllLanes<L>;
    } else {
      done = ~L::bits((turn > splat<L>(kHysteresis * kSmallBend)) |
                      (ext > splat<L>(kHysteresis * kSmallExt))) &
             kAllLanes<L>;
    }
  }
  if (!done) return 0;

  const D zero = splat<L>(0.0);
  VL<L> pos2, a1;
  QL<L> q1;  // large-angle mode: rotation of the link frame onto +X
  if constexpr (kLarge) {
    const D len = L::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);  // |d|
    frame_to_pos_x_lanes<L>(d, len, q1, a1);
    QL<L> q12;
    mul_c(q1.w, q1.x, q1.y, q1.z, q2.w, q2.x, q2.y, q2.z, q12.w, q12.x, q12.y, q12.z);
    q2 = q12;
    pos2 = {len - l, zero, zero};
  } else {
    pos2 = {d.x - l, d.y, d.z};
    a1 = {zero, zero, zero};  // rotvec(identity)
  }
  const VL<L> a2 = rotvec_lanes<L>(q2);
  const D strain = L::round_to_float(pos2.x / l);

  int valid = 0;  // lanes whose local velocity was valid (the forces pass reads it)
  if constexpr (computes_forces(K)) {
    if (L::bits(strain > splat<L>(kStrainDiverged)) & done) diverged = true;
    const LinkConstL<L> c = gather_link_const<L, kContig>(m, ids);
    // §2.4 (see link_scalar)
    const D stress = L::round_to_float(c.e_area * strain);
    const D b1 = c.b1;
    const D b2 = c.b2;
    const D b3 = c.b3;
    const D a2c = c.a2;
    VL<L> fn{L::round_to_float(stress * c.area), b1 * pos2.y - b2 * (a1.z + a2.z),
             b1 * pos2.z + b2 * (a1.y + a2.y)};
    VL<L> fp{-fn.x, -fn.y, -fn.z};
    VL<L> mn{a2c * (a2.x - a1.x), -b2 * pos2.z - b3 * (2.0 * a1.y + a2.y),
             b2 * pos2.y - b3 * (2.0 * a1.z + a2.z)};
    VL<L> mp{a2c * (a1.x - a2.x), -b2 * pos2.z - b3 * (a1.y + 2.0 * a2.y),
             b2 * pos2.y - b3 * (a1.z + 2.0 * a2.z)};

    // §2.5 damping in the lanes with a valid local velocity (none switched mode)
    if constexpr (kContig) {
      valid = nonzero_flags<L>(&st.link_vel_valid[ids[0]]);
    } else {
      for (int k = 0; k < W; ++k) valid |= st.link_vel_valid[ids[k]] != 0 ? 1 << k : 0;
    }
    if (valid) {
      const VL<L> old_pos2 = gather<L, kContig>(st.link_pos2, ids);
      VL<L> old_a1{zero, zero, zero};  // small-angle links: see the invariant above
      if constexpr (kLarge) old_a1 = gather<L, kContig>(st.link_angle1v, ids);
      const VL<L> old_a2 = gather<L, kContig>(st.link_angle2v, ids);
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
      D cn, cp;
      if constexpr (kContig) {
        cn = load_lanes<L>(&sc.link_damping_neg[ids[0]]);
        cp = load_lanes<L>(&sc.link_damping_pos[ids[0]]);
      } else {
        cn = make_lanes<L>([&](int k) { return sc.link_damping_neg[ids[k]]; });
        cp = make_lanes<L>([&](int k) { return sc.link_damping_pos[ids[k]]; });
      }
      const D hn = 0.5 * cn, hp = 0.5 * cp;
      const VL<L> fn_d{fn.x + cn * vx, fn.y + cn * vy, fn.z + cn * vz};
      const VL<L> fp_d{fp.x - cp * vx, fp.y - cp * vy, fp.z - cp * vz};
      const VL<L> mn_d{mn.x - hn * (-sq_a2 * (d2x - d1x)),
                       mn.y - hn * (sq_b2 * dpz + sq_b3 * (2.0 * d1y + d2y)),
                       mn.z - hn * (-sq_b2 * dpy + sq_b3 * (2.0 * d1z + d2z))};
      const VL<L> mp_d{mp.x - hp * (sq_a2 * (d2x - d1x)),
                       mp.y - hp * (sq_b2 * dpz + sq_b3 * (d1y + 2.0 * d2y)),
                       mp.z - hp * (-sq_b2 * dpy + sq_b3 * (d1z + 2.0 * d2z))};
      if (valid == kAllLanes<L>) {  // every lane (the usual case)
        fn = fn_d;
        fp = fp_d;
        mn = mn_d;
        mp = mp_d;
      } else {
        const M on = mask_of<L>(valid);
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
    // §2.6: in small-angle mode F_N and M_N are already in N's frame, in large-angle mode they
    // rotate by q1*; F_P, M_P rotate by q2*
    if constexpr (kLarge) {
      VL<L> fnl, mnl;
      rotate_c(q1.w, -q1.x, -q1.y, -q1.z, fn.x, fn.y, fn.z, fnl.x, fnl.y, fnl.z);
      rotate_c(q1.w, -q1.x, -q1.y, -q1.z, mn.x, mn.y, mn.z, mnl.x, mnl.y, mnl.z);
      fn = fnl;
      mn = mnl;
    }
    VL<L> fpl, mpl;
    rotate_c(q2.w, -q2.x, -q2.y, -q2.z, fp.x, fp.y, fp.z, fpl.x, fpl.y, fpl.z);
    rotate_c(q2.w, -q2.x, -q2.y, -q2.z, mp.x, mp.y, mp.z, mpl.x, mpl.y, mpl.z);
    const VL<L> fn_g = from_x_lanes<A, L>(fn), mn_g = from_x_lanes<A, L>(mn);
    const VL<L> fp_g = from_x_lanes<A, L>(fpl), mp_g = from_x_lanes<A, L>(mpl);
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
    if constexpr (stores_link_state(K)) to_floats<L>(strain, &st.link_strain[ids[0]]);
    if (marks_velocity_valid(K) && valid != kAllLanes<L>)
      std::memset(&st.link_vel_valid[ids[0]], 1, W);
  } else {
    if constexpr (stores_link_state(K)) {
      float strain_f[W];
      to_floats<L>(strain, strain_f);
      for (int k = 0; k < W; ++k) {
        if (!(done >> k & 1)) continue;
        st.link_strain[ids[k]] = strain_f[k];
      }
    }
    if (marks_velocity_valid(K) && (valid & done) != done) {
      for (int k = 0; k < W; ++k)
        if (done >> k & 1) st.link_vel_valid[ids[k]] = 1;
    }
  }
  if constexpr (stores_link_state(K)) {
    scatter<L, kContig>(pos2, st.link_pos2, ids, done);
    if constexpr (kLarge) scatter<L, kContig>(a1, st.link_angle1v, ids, done);  // else stays 0
    scatter<L, kContig>(a2, st.link_angle2v, ids, done);
  }
  return done;
}

// The lanes of a group that link_group left undone (they switched mode) through link_scalar (or
// link_scalar_state_only without forces). Out of line: rare.
template <Axis A, LinkPass K>
[[gnu::noinline]] void links_switching_mode(const Model& m, State& st, Scratch& sc,
                                            const int* group, int count, int done, bool& diverged) {
  for (int k = 0; k < count; ++k) {
    if (done >> k & 1) continue;
    if constexpr (computes_forces(K)) {
      if (link_scalar<A>(m, st, sc, group[k])) diverged = true;
    } else {
      link_scalar_state_only<A>(m, st, group[k]);
    }
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
    if (done != kAllLanes<L>) links_switching_mode<A, K>(m, st, sc, list + j, W, done, diverged);
  }
  if (j < count) {
    int group[W];
    for (int k = 0; k < W; ++k) group[k] = list[std::min(j + k, count - 1)];
    const int done = link_group<L, A, K, kLarge, false>(m, st, sc, group, diverged);
    if (done != kAllLanes<L>)
      links_switching_mode<A, K>(m, st, sc, group, count - j, done, diverged);
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
    if (done != kAllLanes<L>) links_switching_mode<A, K>(m, st, sc, group, W, done, diverged);
  }
  return j;
}

// Link pass (§2.3-2.6) over the links of axis A: links go through link_group W at a time, those
// in small-angle mode at their last update and those in large-angle mode in separate groups (a
// lane that switches mode falls back to link_scalar). W consecutive links of the axis (ids are
// contiguous per axis, see Model) that share a mode, the usual case, form a group as they are;
// the others are collected per mode into lists (Scratch) and run after the axis's stretches.
// Links are independent within a pass, so this order gives the same results as list order.
// With forces (computes_forces(K)) the end loads are computed and the return value is true if any
// strain > 100; without, only the link state (LinkPass::state and restore_state).
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

// Sum of the link forces and moments acting on voxel v (local frame), direction order 0..5.
// The six sums in three pairs of doubles (fx fy | fz mx | my mz): element-wise additions in entry
// order from +0.0, so the same roundings as force += load.force; moment += load.moment on Vec3.
struct LinkSums {
  __m128d fxy, fz_mx, myz;
};
inline LinkSums sum_links(const Model& m, const Scratch& sc, int v) {
  static_assert(sizeof(Scratch::EndLoad) == 6 * sizeof(double));
  LinkSums s{_mm_setzero_pd(), _mm_setzero_pd(), _mm_setzero_pd()};
  const Scratch::EndLoad* loads = sc.link_end_load.data();
  for (int slot : m.voxel_load_slots[v]) {  // six slots, missing links read the zero load
    const double* load = loads[slot].force.data();
    s.fxy = _mm_add_pd(s.fxy, _mm_loadu_pd(load));
    s.fz_mx = _mm_add_pd(s.fz_mx, _mm_loadu_pd(load + 2));
    s.myz = _mm_add_pd(s.myz, _mm_loadu_pd(load + 4));
  }
  return s;
}
inline void gather_links(const Model& m, const Scratch& sc, int v, Vec3& force, Vec3& moment) {
  const LinkSums s = sum_links(m, sc, v);
  force = Vec3(s.fxy[0], s.fxy[1], s.fz_mx[0]);
  moment = Vec3(s.fz_mx[1], s.myz[0], s.myz[1]);
}

// §2.8 floorForce(Fsum): normal spring-damper + friction at the start-of-step velocity; may
// clear the static flag. Returns fric (normal + friction).
inline Vec3 floor_force(const VoxelConst& c, const Vec3& pos, const Vec3& vel, const Vec3& fsum,
                        std::uint8_t& static_flag) {
  const float pen = static_cast<float>(0.0 - pos.z());  // s/2 - s/2 - z
  if (!(pen >= 0)) {
    static_flag = 0;
    return Vec3::Zero();
  }
  const float normal = c.k_pen * pen;  // N = 2 E s pen (float)
  Vec3 fric(0.0, 0.0, normal - c.c_col * vel.z());
  if (static_flag) {
    const double sx = fsum.x() + fric.x(), sy = fsum.y() + fric.y();
    const float surface_sq = static_cast<float>(sx * sx + sy * sy);
    const float limit = c.mu_static * normal;
    if (surface_sq > limit * limit) static_flag = 0;  // breaks: no friction on this step
  } else {
    const double hl = std::sqrt(vel.x() * vel.x() + vel.y() * vel.y() + 0.0 * 0.0);
    if (hl > 0) {
      const float f = c.mu_kinetic * normal;
      fric -= Vec3(f * (vel.x() / hl), f * (vel.y() / hl), f * (0.0 / hl));
    }
  }
  return fric;
}

// §2.8 static-friction capture of the fork's part 2 for a voxel in floor contact at its new
// position: whole-step displacement against the friction force of part 1.
inline void fork_static_capture(const VoxelConst& c, const Vec3& fr, const Vec3& op, Vec3& pos,
                                Vec3& mom, std::uint8_t& sf) {
  const float pen = static_cast<float>(0.0 - pos.z());
  if (pen >= 0) {
    const double work = fr.x() * (pos.x() - op.x()) + fr.y() * (pos.y() - op.y());
    const double hke = 0.5 * c.inv_mass * (mom.x() * mom.x() + mom.y() * mom.y());
    if (hke + work <= 0) sf = 1;
    if (sf) {
      mom.x() = 0.0;
      mom.y() = 0.0;
      pos.x() = op.x();
      pos.y() = op.y();
    }
  } else {
    sf = 0;
  }
}

// §2.12 step 5, part 1 of the fork's step for one free voxel: the reference path. Returns the
// voxel's angular momentum about the CoG before (la) and after (lb) the part.
inline void fork_part1_voxel(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                             int v, const Vec3& cog, Vec3& la, Vec3& lb) {
  const float dt = m.dt_f;
  const VoxelConst& c = m.voxel_const[v];
  Vec3& pos = st.pos[v];
  Vec3& mom = st.lin_mom[v];
  Vec3& am = st.ang_mom[v];
  Quat& q = st.orient[v];
  la = cross(pos - cog, mom) + am;
  sc.old_pos[v] = pos;
  Vec3 lsum, msum;
  gather_links(m, sc, v, lsum, msum);
  // §2.7 linkF = q (sum of link forces) - v C_glob
  const Vec3 vel(mom.x() * c.inv_mass, mom.y() * c.inv_mass, mom.z() * c.inv_mass);
  const Vec3 rl = rotate(q, lsum);
  const Vec3 link_f(rl.x() - vel.x() * c.c_glob, rl.y() - vel.y() * c.c_glob,
                    rl.z() - vel.z() * c.c_glob);
  Vec3 ext_f = Vec3::Zero();
  if (!ext.empty())
    ext_f = Vec3(static_cast<float>(ext[v].x()), static_cast<float>(ext[v].y()),
                 static_cast<float>(ext[v].z()));
  const Vec3 grav_f(0.0, 0.0, c.gravity_force);
  const Vec3& col_f = sc.collision_force[v];
  Vec3 fric = Vec3::Zero();
  if (m.floor) {
    const Vec3 fsum = ((link_f + ext_f) + grav_f) + col_f;
    fric = floor_force(c, pos, vel, fsum, st.static_friction[v]);
  }
  // pos += (linkF + extF) dt (dt/m), linMom += (linkF + extF) dt
  const Vec3 fle = link_f + ext_f;
  const float dt_m = dt * c.inv_mass;
  pos += Vec3(fle.x() * dt * dt_m, fle.y() * dt * dt_m, fle.z() * dt * dt_m);
  mom += Vec3(fle.x() * dt, fle.y() * dt, fle.z() * dt);
  // §2.7 curMoment = q (sum of link moments) - omega C_glob,rot
  const Vec3 rm = rotate(q, msum);
  const Vec3 cur_m(rm.x() - am.x() * c.inv_inertia * c.c_glob_rot,
                   rm.y() - am.y() * c.inv_inertia * c.c_glob_rot,
                   rm.z() - am.z() * c.inv_inertia * c.c_glob_rot);
  const float dt_i = dt * c.inv_inertia;
  q = mul(
      quat_from_rotvec(Vec3(cur_m.x() * dt * dt_i, cur_m.y() * dt * dt_i, cur_m.z() * dt * dt_i)),
      q);
  am += Vec3(cur_m.x() * dt, cur_m.y() * dt, cur_m.z() * dt);
  sc.part2_force[v] = (grav_f + col_f) + fric;
  sc.fric[v] = fric;
  lb = cross(pos - cog, mom) + am;
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
// gather_links of W voxels as lanes: sums of link forces (lsum) and moments (msum), local frame.
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

// fork_part1_voxel for W free voxels v[0..W), one per lane (same operations per lane; the floor
// force of §2.8 and the large-rotation branch of quat_from_rotvec per lane in scalar code).
template <class L>
inline void fork_part1_group(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                             const int* v, const Vec3& cog, VL<L>& la, VL<L>& lb) {
  constexpr int W = L::W;
  using D = DV<L>;
  const double dt = m.dt_f;
  const VoxelLanes<L> start = load_voxels<L>(m, st, v);
  VL<L> pos = start.pos, mom = start.mom, am = start.am;
  const QL<L> q = start.q;
  const VoxelConstL<L>& c = start.c;
  const D cgx = splat<L>(cog.x()), cgy = splat<L>(cog.y()), cgz = splat<L>(cog.z());
  {
    const D rx = pos.x - cgx, ry = pos.y - cgy, rz = pos.z - cgz;  // cross(pos - cog, mom) + am
    la = {(ry * mom.z - rz * mom.y) + am.x, (rz * mom.x - rx * mom.z) + am.y,
          (rx * mom.y - ry * mom.x) + am.z};
  }
  store_run<L>(pos, sc.old_pos, v[0]);
  VL<L> lsum, msum;
  gather_links_lanes<L>(m, sc, v, lsum, msum);
  const D inv_mass = c.inv_mass;
  const VL<L> vel{mom.x * inv_mass, mom.y * inv_mass, mom.z * inv_mass};
  VL<L> rl;
  rotate_c(q.w, q.x, q.y, q.z, lsum.x, lsum.y, lsum.z, rl.x, rl.y, rl.z);
  const D c_glob = c.c_glob;
  const VL<L> link_f{rl.x - vel.x * c_glob, rl.y - vel.y * c_glob, rl.z - vel.z * c_glob};
  const D zero = splat<L>(0.0);
  VL<L> ext_f{zero, zero, zero};
  if (!ext.empty()) {  // the reference's External stores float
    ext_f = load_external_force<L>(ext, v[0]);
  }
  const VL<L> grav_f{zero, zero, c.gravity_force};
  const VL<L> col_f = load_run<L>(sc.collision_force, v[0]);
  VL<L> fric{zero, zero, zero};
  if (m.floor) {
    const int contact = L::bits(L::round_to_float(0.0 - pos.z) >= 0.0);
    const VL<L> fsum{((link_f.x + ext_f.x) + grav_f.x) + col_f.x,
                     ((link_f.y + ext_f.y) + grav_f.y) + col_f.y,
                     ((link_f.z + ext_f.z) + grav_f.z) + col_f.z};
    for (int k = 0; k < W; ++k) {
      std::uint8_t& sf = st.static_friction[v[k]];
      if (!(contact >> k & 1)) {
        sf = 0;  // floor_force without contact
        continue;
      }
      const Vec3 fr = floor_force(m.voxel_const[v[k]], Vec3(pos.x[k], pos.y[k], pos.z[k]),
                                  Vec3(vel.x[k], vel.y[k], vel.z[k]),
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
  QL<L> qn;
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
  am = {am.x + cur_m.x * dt, am.y + cur_m.y * dt, am.z + cur_m.z * dt};
  store_voxels<L>(pos, mom, am, qn, st, v);
  store_run<L>(VL<L>{(grav_f.x + col_f.x) + fric.x, (grav_f.y + col_f.y) + fric.y,
                     (grav_f.z + col_f.z) + fric.z},
               sc.part2_force, v[0]);
  store_run<L>(fric, sc.fric, v[0]);
  {
    const D rx = pos.x - cgx, ry = pos.y - cgy, rz = pos.z - cgz;
    lb = {(ry * mom.z - rz * mom.y) + am.x, (rz * mom.x - rx * mom.z) + am.y,
          (rx * mom.y - ry * mom.x) + am.z};
  }
}

// §2.12 step 8, part 2 of the fork's step for one free voxel: the reference path.
inline void fork_part2_voxel(const Model& m, State& st, Scratch& sc, int v, float me_x, float me_y,
                             float me_z, double& check) {
  const float dt = m.dt_f;
  const double dtd = dt;
  const VoxelConst& c = m.voxel_const[v];
  Vec3& pos = st.pos[v];
  Vec3& mom = st.lin_mom[v];
  Vec3& am = st.ang_mom[v];
  Quat& q = st.orient[v];
  const Vec3& f2 = sc.part2_force[v];
  const float dt_m = dt * c.inv_mass;
  pos += Vec3(f2.x() * dt * dt_m, f2.y() * dt * dt_m, f2.z() * dt * dt_m);
  pos += Vec3(mom.x() * dt_m, mom.y() * dt_m, mom.z() * dt_m);
  mom += Vec3(f2.x() * dt, f2.y() * dt, f2.z() * dt);
  if (m.floor) fork_static_capture(c, sc.fric[v], sc.old_pos[v], pos, mom, st.static_friction[v]);
  // angMom += M_ext dt (float moment promoted to double, times the float dt)
  am.x() += static_cast<double>(me_x) * dtd;
  am.y() += static_cast<double>(me_y) * dtd;
  am.z() += static_cast<double>(me_z) * dtd;
  q = mul(quat_from_rotvec(Vec3(am.x() * c.inv_inertia * dt, am.y() * c.inv_inertia * dt,
                                am.z() * c.inv_inertia * dt)),
          q);
  // NaN/inf anywhere makes the running sum non-finite (checked once after the loop; finite
  // values beyond ~1e307 that overflow the sum are reported as non-finite too)
  check +=
      pos.x() + pos.y() + pos.z() + mom.x() + mom.y() + mom.z() + am.x() + am.y() + am.z() + q.w;
}

// fork_part2_voxel for W free voxels v[0..W), one per lane (same operations per lane).
template <class L>
inline void fork_part2_group(const Model& m, State& st, Scratch& sc, const int* v, float me_x,
                             float me_y, float me_z, double& check) {
  constexpr int W = L::W;
  using D = DV<L>;
  const double dt = m.dt_f;
  const VoxelLanes<L> start = load_voxels<L>(m, st, v);
  VL<L> pos = start.pos, mom = start.mom, am = start.am;
  const QL<L> q = start.q;
  const VoxelConstL<L>& c = start.c;
  const VL<L> f2 = load_run<L>(sc.part2_force, v[0]);
  const D inv_mass = c.inv_mass;
  const D dt_m = L::round_to_float(dt * inv_mass);  // float dt * (1/m)
  pos = {pos.x + f2.x * dt * dt_m, pos.y + f2.y * dt * dt_m, pos.z + f2.z * dt * dt_m};
  pos = {pos.x + mom.x * dt_m, pos.y + mom.y * dt_m, pos.z + mom.z * dt_m};
  mom = {mom.x + f2.x * dt, mom.y + f2.y * dt, mom.z + f2.z * dt};
  if (m.floor) {
    const int contact = L::bits(L::round_to_float(0.0 - pos.z) >= 0.0);
    for (int k = 0; k < W; ++k) {
      if (!(contact >> k & 1)) {
        st.static_friction[v[k]] = 0;
        continue;
      }
      Vec3 pk(pos.x[k], pos.y[k], pos.z[k]), mk(mom.x[k], mom.y[k], mom.z[k]);
      fork_static_capture(m.voxel_const[v[k]], sc.fric[v[k]], sc.old_pos[v[k]], pk, mk,
                          st.static_friction[v[k]]);
      pos.x[k] = pk.x();
      pos.y[k] = pk.y();
      mom.x[k] = mk.x();
      mom.y[k] = mk.y();
    }
  }
  am = {am.x + splat<L>(static_cast<double>(me_x) * dt),
        am.y + splat<L>(static_cast<double>(me_y) * dt),
        am.z + splat<L>(static_cast<double>(me_z) * dt)};
  const D inv_i = c.inv_inertia;
  const QL<L> dq =
      quat_from_rotvec_lanes<L>({am.x * inv_i * dt, am.y * inv_i * dt, am.z * inv_i * dt});
  QL<L> qn;
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
  store_voxels<L>(pos, mom, am, qn, st, v);
  const D sum = pos.x + pos.y + pos.z + mom.x + mom.y + mom.z + am.x + am.y + am.z + qn.w;
  for (int k = 0; k < W; ++k) check += sum[k];
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

// §2.9 upstream single-pass symplectic Euler with the same forces, one voxel: the reference path.
inline void symplectic_voxel(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                             int v, double& check) {
  const float dt = m.dt_f;
  const VoxelConst& c = m.voxel_const[v];
  Vec3& pos = st.pos[v];
  Vec3& mom = st.lin_mom[v];
  Vec3& am = st.ang_mom[v];
  Quat& q = st.orient[v];
  Vec3 lsum, msum;
  gather_links(m, sc, v, lsum, msum);
  const Vec3 vel(mom.x() * c.inv_mass, mom.y() * c.inv_mass, mom.z() * c.inv_mass);
  // force(): links (rotated to global) + external - global damping + gravity + collisions
  Vec3 f = rotate(q, lsum);
  if (!ext.empty())
    f += Vec3(static_cast<float>(ext[v].x()), static_cast<float>(ext[v].y()),
              static_cast<float>(ext[v].z()));
  f -= Vec3(vel.x() * c.c_glob, vel.y() * c.c_glob, vel.z() * c.c_glob);
  f.z() += c.gravity_force;
  f += sc.collision_force[v];
  const float pen = static_cast<float>(0.0 - pos.z());  // at the old position (upstream)
  const bool contact = m.floor && pen >= 0;
  if (m.floor) f += floor_force(c, pos, vel, f, st.static_friction[v]);
  mom += Vec3(f.x() * dt, f.y() * dt, f.z() * dt);
  const float dt_m = dt * c.inv_mass;
  Vec3 tr(mom.x() * dt_m, mom.y() * dt_m, mom.z() * dt_m);
  if (m.floor) {
    std::uint8_t& sf = st.static_friction[v];
    if (contact) {
      const double work = f.x() * tr.x() + f.y() * tr.y();
      const double hke = 0.5 * c.inv_mass * (mom.x() * mom.x() + mom.y() * mom.y());
      if (hke + work <= 0) sf = 1;
      if (sf) {
        mom.x() = mom.y() = 0.0;
        tr.x() = tr.y() = 0.0;
      }
    } else {
      sf = 0;
    }
  }
  pos += tr;
  const Vec3 rm = rotate(q, msum);
  const Vec3 cur_m(rm.x() - am.x() * c.inv_inertia * c.c_glob_rot,
                   rm.y() - am.y() * c.inv_inertia * c.c_glob_rot,
                   rm.z() - am.z() * c.inv_inertia * c.c_glob_rot);
  am += Vec3(cur_m.x() * dt, cur_m.y() * dt, cur_m.z() * dt);
  q = mul(quat_from_rotvec(Vec3(am.x() * c.inv_inertia * dt, am.y() * c.inv_inertia * dt,
                                am.z() * c.inv_inertia * dt)),
          q);
  // NaN/inf anywhere makes the running sum non-finite (checked once after the loop; finite
  // values beyond ~1e307 that overflow the sum are reported as non-finite too)
  check +=
      pos.x() + pos.y() + pos.z() + mom.x() + mom.y() + mom.z() + am.x() + am.y() + am.z() + q.w;
}

// symplectic_voxel for W free voxels v[0..W), one per lane (same operations per lane as the
// scalar path; the floor contact of §2.8 and the large-rotation branch of quat_from_rotvec are
// done per lane in scalar code).
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
  if (m.floor) {
    contact = L::bits(L::round_to_float(0.0 - pos.z) >= 0.0);
    const D zero = splat<L>(0.0);
    VL<L> fric{zero, zero, zero};
    for (int k = 0; k < W; ++k) {
      std::uint8_t& sf = st.static_friction[v[k]];
      if (!(contact >> k & 1)) {
        sf = 0;  // floor_force without contact
        continue;
      }
      const Vec3 fr =
          floor_force(vc[v[k]], Vec3(pos.x[k], pos.y[k], pos.z[k]),
                      Vec3(vel.x[k], vel.y[k], vel.z[k]), Vec3(f.x[k], f.y[k], f.z[k]), sf);
      set_lane<L>(fric, k, fr);
    }
    f = {f.x + fric.x, f.y + fric.y, f.z + fric.z};
  }
  mom = {mom.x + f.x * dt, mom.y + f.y * dt, mom.z + f.z * dt};
  const D dt_m = L::round_to_float(dt * inv_mass);  // float dt * (1/m)
  VL<L> tr{mom.x * dt_m, mom.y * dt_m, mom.z * dt_m};
  for (int k = 0; k < W; ++k) {
    if (!(contact >> k & 1)) continue;
    std::uint8_t& sf = st.static_friction[v[k]];
    const double work = f.x[k] * tr.x[k] + f.y[k] * tr.y[k];
    const double hke = 0.5 * vc[v[k]].inv_mass * (mom.x[k] * mom.x[k] + mom.y[k] * mom.y[k]);
    if (hke + work <= 0) sf = 1;
    if (sf) {
      mom.x[k] = mom.y[k] = 0.0;
      tr.x[k] = tr.y[k] = 0.0;
    }
  }
  pos = {pos.x + tr.x, pos.y + tr.y, pos.z + tr.z};
  VL<L> rm;
  rotate_c(q.w, q.x, q.y, q.z, msum.x, msum.y, msum.z, rm.x, rm.y, rm.z);
  const D inv_i = c.inv_inertia;
  const D c_rot = c.c_glob_rot;
  const VL<L> cur_m{rm.x - am.x * inv_i * c_rot, rm.y - am.y * inv_i * c_rot,
                    rm.z - am.z * inv_i * c_rot};
  am = {am.x + cur_m.x * dt, am.y + cur_m.y * dt, am.z + cur_m.z * dt};
  const QL<L> dq =
      quat_from_rotvec_lanes<L>({am.x * inv_i * dt, am.y * inv_i * dt, am.z * inv_i * dt});
  QL<L> qn;
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
  store_voxels<L>(pos, mom, am, qn, st, v);
  const D sum = pos.x + pos.y + pos.z + mom.x + mom.y + mom.z + am.x + am.y + am.z + qn.w;
  for (int k = 0; k < W; ++k) check += sum[k];
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

// ---- chamber meshes (§3.2, §3.4): W triangles at a time ----------------------------------------
// The triangle formulas of pneumatics_triangle.hpp on lanes; the sums over triangles (float
// volume, float forces per wall slot) stay in triangle order, lane by lane.
template <class L>
struct TriangleLaneOps {
  static DV<L> round_to_float(DV<L> x) { return L::round_to_float(x); }
  static DV<L> sqrt(DV<L> x) { return L::sqrt(x); }
  static DV<L> positive_or_one(DV<L> x) { return select<L>(x > 0.0, x, splat<L>(1.0)); }
};

// Vertex `corner` of triangles t .. t + W - 1 as lanes.
template <class L>
[[gnu::always_inline]] inline Point3<DV<L>> triangle_corner(const PneumaticsModel& pm,
                                                            std::span<const Vec3> positions, int t,
                                                            int corner) {
  const double* p[L::W];
  for (int k = 0; k < L::W; ++k) p[k] = positions[pm.triangle_voxels[t + k][corner]].data();
  Point3<DV<L>> r;
  gather3<L>(p, r.x, r.y, r.z);
  return r;
}

// chamber_volume (pneumatics.cpp) with the tetrahedra W at a time.
template <class L>
float chamber_volume_lanes(const PneumaticsModel& pm, int chamber,
                           std::span<const Vec3> positions) {
  constexpr int W = L::W;
  const int begin = pm.chamber_triangle_begin[chamber];
  const int end = pm.chamber_triangle_begin[chamber + 1];
  float volume = 0.0f;  // [m^3], accumulated in float as the reference
  if (begin < end) {
    const Point3<double> p0 = to_point3(positions[pm.triangle_voxels[begin][0]]);
    const Point3<DV<L>> p0_lanes{splat<L>(p0.x), splat<L>(p0.y), splat<L>(p0.z)};
    int t = begin;
    for (; t + W <= end; t += W) {
      const DV<L> tet = triangle_tet_volume(triangle_corner<L>(pm, positions, t, 0),
                                            triangle_corner<L>(pm, positions, t, 1),
                                            triangle_corner<L>(pm, positions, t, 2), p0_lanes);
      for (int k = 0; k < W; ++k) volume = static_cast<float>(volume + tet[k]);
    }
    for (; t < end; ++t) {
      const auto& tri = pm.triangle_voxels[t];
      const double tet =
          triangle_tet_volume(to_point3(positions[tri[0]]), to_point3(positions[tri[1]]),
                              to_point3(positions[tri[2]]), p0);
      volume = static_cast<float>(volume + tet);
    }
  }
  return volume < 1e-12f ? 1e-12f : volume;  // §3.2: V = max(V, 1e-12), as std::max (NaN kept)
}

// §3.4 pressure forces of one chamber, W triangles at a time: each triangle's share F/3 as the
// floats (x, y, z, 0) in PneumaticsScratch::triangle_force.
template <class L>
void pressure_forces_lanes(const PneumaticsModel& pm, int chamber, float gauge,
                           std::span<const Vec3> positions, PneumaticsScratch& scratch) {
  constexpr int W = L::W;
  const int end = pm.chamber_triangle_begin[chamber + 1];
  int t = pm.chamber_triangle_begin[chamber];
  for (; t + W <= end; t += W) {
    const Point3<DV<L>> f3 = triangle_force_third<TriangleLaneOps<L>>(
        triangle_corner<L>(pm, positions, t, 0), triangle_corner<L>(pm, positions, t, 1),
        triangle_corner<L>(pm, positions, t, 2), splat<L>(gauge));
    __m128 rows[W];  // (fx, fy, fz, 0) of each triangle
    float_rows<L>(f3.x, f3.y, f3.z, rows);
    for (int k = 0; k < W; ++k) _mm_storeu_ps(scratch.triangle_force[t + k].data(), rows[k]);
  }
  for (; t < end; ++t) {
    const auto& tri = pm.triangle_voxels[t];
    const Point3<double> f3 = triangle_force_third<ScalarTriangleOps>(
        to_point3(positions[tri[0]]), to_point3(positions[tri[1]]), to_point3(positions[tri[2]]),
        static_cast<double>(gauge));
    scratch.triangle_force[t] = {static_cast<float>(f3.x), static_cast<float>(f3.y),
                                 static_cast<float>(f3.z), 0.0f};
  }
}

// The exported table of this translation unit's passes.
template <class L>
constexpr StepKernels make_step_kernels(Simd simd) {
  return StepKernels{simd,
                     L::W,
                     &link_pass_forces<L, LinkPass::forces_and_state>,
                     &link_pass_forces<L, LinkPass::forces>,
                     &link_pass_state<L, LinkPass::restore_state>,
                     &fork_voxel_passes<L>,
                     &symplectic_voxel_pass<L>,
                     &chamber_volume_lanes<L>,
                     &pressure_forces_lanes<L>};
}

}  // namespace
}  // namespace softevo::physics
