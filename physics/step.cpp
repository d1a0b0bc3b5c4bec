// The time step of pneuvox-model.md §2.12 (fork, "pneuvox") and §2.9 (upstream, "symplectic").
//
// Precision: state is double; constants are float (Model); products the reference forms in float
// (dt * (1/m), k_pen * pen, mu * N, strain, stress * A, collision forces) are formed in float
// here too, and a float times a double is promoted exactly as in the reference. The build uses
// -ffp-contract=off, so the written operation order is the executed one.
#include "physics/step.hpp"

// The paired link and voxel passes use SSE2 (part of every x86-64 CPU). Other architectures
// would need a scalar build of those passes (the scalar per-lane code is already there).
#if !defined(__SSE2__)
#error "softevo physics needs an x86-64 (SSE2) target; see the note at the top of step.cpp"
#endif
#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace softevo::physics {

const char* to_string(StepStatus status) {
  switch (status) {
    case StepStatus::ok:
      return "ok";
    case StepStatus::diverged:
      return "diverged";
    case StepStatus::non_finite:
      return "non_finite";
  }
  return "unknown";
}

Scratch make_scratch(const Model& model) {
  Scratch sc;
  const std::size_t nl = model.link_count, nv = model.voxel_count;
  sc.link_end_load.assign(2 * nl, Scratch::EndLoad{Vec3::Zero(), Vec3::Zero()});
  sc.link_damping.assign(nv, 0.0f);
  sc.collision_force.assign(nv, Vec3::Zero());
  sc.part2_force.assign(nv, Vec3::Zero());
  sc.fric.assign(nv, Vec3::Zero());
  sc.old_pos.assign(nv, Vec3::Zero());
  sc.ext_moment.assign(nv, {0.0f, 0.0f, 0.0f});
  const std::size_t ns = model.surface_voxels.size();
  std::size_t cap = ns * 128;
  if (ns > 1 && cap > ns * (ns - 1) / 2) cap = ns * (ns - 1) / 2;
  sc.pair_force.assign(cap, {0.0f, 0.0f, 0.0f});
  std::size_t buckets = 1;
  while (buckets < 2 * ns + 2) buckets <<= 1;
  sc.grid_head.assign(buckets, -1);
  sc.grid_next.assign(ns, -1);
  sc.grid_cell.assign(ns * 3, 0);
  sc.candidates.reserve(ns);
  return sc;
}

namespace {

// ---- §2.2 axis permutation ("as if the link pointed along +X") --------------------------------
// The axis is a template parameter: the link pass runs one axis at a time (Model::links_by_axis),
// so the permutations are free register moves instead of a data-dependent switch per link end.
template <Axis A>
inline Vec3 to_x(double x, double y, double z) {
  if constexpr (A == Axis::x) return {x, y, z};
  if constexpr (A == Axis::y) return {y, -x, z};
  if constexpr (A == Axis::z) return {z, y, -x};
}
template <Axis A>
inline Quat to_x(const Quat& q) {
  if constexpr (A == Axis::x) return q;
  if constexpr (A == Axis::y) return {q.w, q.y, -q.x, q.z};
  if constexpr (A == Axis::z) return {q.w, q.z, q.y, -q.x};
}
template <Axis A>
inline Vec3 from_x(const Vec3& v) {
  if constexpr (A == Axis::x) return v;
  if constexpr (A == Axis::y) return {-v.y(), v.x(), v.z()};
  if constexpr (A == Axis::z) return {-v.z(), v.y(), v.x()};
}

// §2.3 small-angle hysteresis thresholds (float, as the reference's static float constants).
constexpr float kSmallBend = 0.05f;        // turn below this -> small angle
constexpr float kSmallExt = 0.5f;          // extension below this -> small angle
constexpr float kHysteresis = 1.2f;        // leave small angle above 1.2x the thresholds
constexpr float kStrainDiverged = 100.0f;  // §2.12 item 1

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
    k.q1 = quat_to_pos_x(d);
    k.q2 = mul(k.q1, k.q2);
    k.pos2 = Vec3(std::sqrt(d.x() * d.x() + d.y() * d.y() + d.z() * d.z()) - l, 0.0, 0.0);
    k.a1v = rotvec(k.q1);
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
    const Vec3& old_pos2 = st.link_pos2[i];
    const Vec3& old_a1 = st.link_angle1v[i];
    const Vec3& old_a2 = st.link_angle2v[i];
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
    const float cn = sc.link_damping[m.link_neg[i]];
    const float cp = sc.link_damping[m.link_pos[i]];
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
  st.link_pos2[i] = pos2;
  st.link_angle1v[i] = a1;
  st.link_angle2v[i] = a2;

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
  st.link_pos2[i] = k.pos2;
  st.link_angle1v[i] = k.a1v;
  st.link_angle2v[i] = k.a2v;
}

// ---- two links at a time (SSE2) ----------------------------------------------------------------
// Links in small-angle mode (the common case) go through the link pass in pairs, one link per
// lane of a 2 x double SSE2 vector. Every lane performs exactly the scalar path's IEEE
// operations in the same order (the quaternion formulas are the shared templates of quat.hpp;
// float roundings are a float conversion of the same double; float x float products and
// float / float quotients are formed in double and rounded to float, which gives the float
// result exactly since 53 >= 2 x 24 + 2), so results are bit-identical to link_scalar. Lanes that
// need the large-angle path (§2.3) go through link_scalar alone.
using D2 = double __attribute__((vector_size(16)));
using M2 = long long __attribute__((vector_size(16)));  // comparison result: all ones = true

inline D2 splat(double x) {
  return D2{x, x};
}
inline D2 round_to_float(D2 x) {
  return _mm_cvtps_pd(_mm_cvtpd_ps(x));
}
inline D2 abs2(D2 x) {
  return _mm_andnot_pd(_mm_set1_pd(-0.0), x);
}
inline D2 select(M2 mask, D2 a, D2 b) {  // mask ? a : b, bitwise
  const __m128d mk = reinterpret_cast<__m128d>(mask);
  return _mm_or_pd(_mm_and_pd(mk, a), _mm_andnot_pd(mk, b));
}
inline int lanes(M2 mask) {  // bit k = lane k true
  return _mm_movemask_pd(reinterpret_cast<__m128d>(mask));
}

struct V2 {  // two Vec3
  D2 x, y, z;
};
struct Q2 {  // two Quat
  D2 w, x, y, z;
};
inline V2 load2(const Vec3& a, const Vec3& b) {
  return {D2{a.x(), b.x()}, D2{a.y(), b.y()}, D2{a.z(), b.z()}};
}
inline void store2(const V2& v, Vec3& a, Vec3& b) {  // lane 0 -> a, lane 1 -> b
  a = Vec3(v.x[0], v.y[0], v.z[0]);
  b = Vec3(v.x[1], v.y[1], v.z[1]);
}
inline Q2 load2(const Quat& a, const Quat& b) {
  return {D2{a.w, b.w}, D2{a.x, b.x}, D2{a.y, b.y}, D2{a.z, b.z}};
}
// store2 of the lanes in `mask` only (bit k = lane k)
inline void store2(const V2& v, Vec3& a, Vec3& b, int mask) {
  if (mask == 3) {
    store2(v, a, b);
    return;
  }
  if (mask & 1) a = Vec3(v.x[0], v.y[0], v.z[0]);
  if (mask & 2) b = Vec3(v.x[1], v.y[1], v.z[1]);
}
inline void store2(const Q2& q, Quat& a, Quat& b) {
  a = Quat{q.w[0], q.x[0], q.y[0], q.z[0]};
  b = Quat{q.w[1], q.x[1], q.y[1], q.z[1]};
}
// quat_from_rotvec (§2.11) per lane: the Taylor branch in SIMD, the cos/sin branch per lane.
inline Q2 quat_from_rotvec2(const V2& r) {
  const D2 hx = r.x / 2.0, hy = r.y / 2.0, hz = r.z / 2.0;
  const D2 t = hx * hx + hy * hy + hz * hz;
  const D2 w = 1.0 - t / 2.0, s = 1.0 - t / 6.0;
  Q2 q{w, hx * s, hy * s, hz * s};
  const int wide = ~lanes(t * t < 5.328e-15) & 3;
  for (int k = 0; k < 2; ++k) {
    if (!(wide >> k & 1)) continue;
    const Quat qk = quat_from_rotvec(Vec3(r.x[k], r.y[k], r.z[k]));
    q.w[k] = qk.w;
    q.x[k] = qk.x;
    q.y[k] = qk.y;
    q.z[k] = qk.z;
  }
  return q;
}
// §2.2 permutations on lane pairs (same signs and order as the scalar to_x / from_x)
template <Axis A>
inline V2 to_x2(D2 x, D2 y, D2 z) {
  if constexpr (A == Axis::x) return {x, y, z};
  if constexpr (A == Axis::y) return {y, -x, z};
  if constexpr (A == Axis::z) return {z, y, -x};
}
template <Axis A>
inline Q2 to_x2(const Q2& q) {
  if constexpr (A == Axis::x) return q;
  if constexpr (A == Axis::y) return {q.w, q.y, -q.x, q.z};
  if constexpr (A == Axis::z) return {q.w, q.z, q.y, -q.x};
}
template <Axis A>
inline V2 from_x2(const V2& v) {
  if constexpr (A == Axis::x) return v;
  if constexpr (A == Axis::y) return {-v.y, v.x, v.z};
  if constexpr (A == Axis::z) return {-v.z, v.y, v.x};
}
inline D2 float_pair(float a, float b) {
  return D2{static_cast<double>(a), static_cast<double>(b)};
}

// The members of two LinkConst as lane pairs (float -> double, exact): four members at a time,
// interleaved with unpack, instead of one scalar conversion per member and lane.
struct LinkConst2 {
  D2 e_area, area, a2, b1, b2, b3, sq_a1, sq_a2xip, sq_b1, sq_b2xfmp, sq_b3xip;
};
inline LinkConst2 load2(const LinkConst& a, const LinkConst& b) {
  static_assert(sizeof(LinkConst) == 12 * sizeof(float) && offsetof(LinkConst, e_area) == 0 &&
                offsetof(LinkConst, sq_b3xip) == 10 * sizeof(float));
  const float* pa = &a.e_area;
  const float* pb = &b.e_area;
  D2 d[12];
  for (int k = 0; k < 3; ++k) {
    const __m128 va = _mm_loadu_ps(pa + 4 * k), vb = _mm_loadu_ps(pb + 4 * k);
    const __m128 lo = _mm_unpacklo_ps(va, vb), hi = _mm_unpackhi_ps(va, vb);
    d[4 * k] = _mm_cvtps_pd(lo);
    d[4 * k + 1] = _mm_cvtps_pd(_mm_movehl_ps(lo, lo));
    d[4 * k + 2] = _mm_cvtps_pd(hi);
    d[4 * k + 3] = _mm_cvtps_pd(_mm_movehl_ps(hi, hi));
  }
  return {d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7], d[8], d[9], d[10]};
}

// Links i0, i1 of axis A. Each lane whose link ends in small-angle mode is updated like
// link_scalar (or link_scalar_state_only if !kForces), its strain > 100 ORed into `diverged`;
// returns those lanes (bit k = lane k). Lanes that need the large-angle path are left unchanged
// for the caller's link_scalar.
template <Axis A, bool kForces>
[[gnu::always_inline]] inline int link_pair(const Model& m, State& st, Scratch& sc, int i0, int i1,
                                            bool& diverged) {
  const int n0 = m.link_neg[i0], p0 = m.link_pos[i0], n1 = m.link_neg[i1], p1 = m.link_pos[i1];
  // §2.3 orient link (see orient_link)
  const V2 pn = load2(st.pos[n0], st.pos[n1]);
  const V2 pp = load2(st.pos[p0], st.pos[p1]);
  const V2 d0 = to_x2<A>(pp.x - pn.x, pp.y - pn.y, pp.z - pn.z);
  const Q2 qn = to_x2<A>(load2(st.orient[n0], st.orient[n1]));
  const Q2 r{qn.w, -qn.x, -qn.y, -qn.z};  // conj
  V2 d;
  rotate_c(r.w, r.x, r.y, r.z, d0.x, d0.y, d0.z, d.x, d.y, d.z);
  const Q2 qp = to_x2<A>(load2(st.orient[p0], st.orient[p1]));
  Q2 q2;
  mul_c(r.w, r.x, r.y, r.z, qp.w, qp.x, qp.y, qp.z, q2.w, q2.x, q2.y, q2.z);
  const D2 l = splat(m.rest_length);
  const D2 turn = round_to_float((abs2(d.z) + abs2(d.y)) / d.x);
  const D2 ext = round_to_float(abs2(1.0 - d.x / l));
  const int enter = lanes((turn < splat(kSmallBend)) & (ext < splat(kSmallExt)));
  const int leave =
      lanes((turn > splat(kHysteresis * kSmallBend)) | (ext > splat(kHysteresis * kSmallExt)));
  const int was = (st.link_small_angle[i0] != 0 ? 1 : 0) | (st.link_small_angle[i1] != 0 ? 2 : 0);
  const int small = (was & ~leave) | (~was & enter);
  const int done = small & 3;
  if (!done) return 0;
  const int switched = ~was & 3;  // entered small-angle mode on this update

  const V2 pos2{d.x - l, d.y, d.z};
  const D2 zero = splat(0.0);
  const V2 a1{zero, zero, zero};  // rotvec(identity)
  // a2 = rotvec(q2) (§2.11), branches as lane masks; the acos branch is done per lane
  V2 a2;
  {
    const M2 unit = (q2.w >= 1.0) | (q2.w <= -1.0);
    const D2 t = 1.0 - q2.w * q2.w;
    const D2 k = _mm_sqrt_pd((2.0 - 2.0 * q2.w) / t);
    a2 = {select(unit, zero, q2.x * 2.0 * k), select(unit, zero, q2.y * 2.0 * k),
          select(unit, zero, q2.z * 2.0 * k)};
    const int wide = ~lanes(unit) & ~lanes(t < 2.4e-3) & 3;
    for (int lane = 0; lane < 2; ++lane) {
      if (!(wide >> lane & 1)) continue;
      const Vec3 v = rotvec(Quat{q2.w[lane], q2.x[lane], q2.y[lane], q2.z[lane]});
      a2.x[lane] = v.x();
      a2.y[lane] = v.y();
      a2.z[lane] = v.z();
    }
  }
  const D2 strain = round_to_float(pos2.x / l);

  if constexpr (kForces) {
    const LinkConst2 c = load2(m.link_const[i0], m.link_const[i1]);
    if (lanes(strain > splat(kStrainDiverged)) & done) diverged = true;
    // §2.4 (see link_scalar)
    const D2 stress = round_to_float(c.e_area * strain);
    const D2 b1 = c.b1, b2 = c.b2, b3 = c.b3, a2c = c.a2;
    V2 fn{round_to_float(stress * c.area), b1 * pos2.y - b2 * (a1.z + a2.z),
          b1 * pos2.z + b2 * (a1.y + a2.y)};
    V2 fp{-fn.x, -fn.y, -fn.z};
    V2 mn{a2c * (a2.x - a1.x), -b2 * pos2.z - b3 * (2.0 * a1.y + a2.y),
          b2 * pos2.y - b3 * (2.0 * a1.z + a2.z)};
    V2 mp{a2c * (a1.x - a2.x), -b2 * pos2.z - b3 * (a1.y + 2.0 * a2.y),
          b2 * pos2.y - b3 * (a1.z + 2.0 * a2.z)};

    // §2.5 damping in the lanes with a valid local velocity that did not switch mode
    const int damp =
        ((st.link_vel_valid[i0] != 0 ? 1 : 0) | (st.link_vel_valid[i1] != 0 ? 2 : 0)) & ~switched;
    if (damp) {
      const V2 old_pos2 = load2(st.link_pos2[i0], st.link_pos2[i1]);
      const V2 old_a1 = load2(st.link_angle1v[i0], st.link_angle1v[i1]);
      const V2 old_a2 = load2(st.link_angle2v[i0], st.link_angle2v[i1]);
      const D2 dpx = 0.5 * (pos2.x - old_pos2.x), dpy = 0.5 * (pos2.y - old_pos2.y),
               dpz = 0.5 * (pos2.z - old_pos2.z);
      const D2 d1x = 0.5 * (a1.x - old_a1.x), d1y = 0.5 * (a1.y - old_a1.y),
               d1z = 0.5 * (a1.z - old_a1.z);
      const D2 d2x = 0.5 * (a2.x - old_a2.x), d2y = 0.5 * (a2.y - old_a2.y),
               d2z = 0.5 * (a2.z - old_a2.z);
      const D2 sq_a1 = c.sq_a1, sq_a2 = c.sq_a2xip, sq_b1 = c.sq_b1, sq_b2 = c.sq_b2xfmp,
               sq_b3 = c.sq_b3xip;
      const D2 vx = sq_a1 * dpx, vy = sq_b1 * dpy - sq_b2 * (d1z + d2z),
               vz = sq_b1 * dpz + sq_b2 * (d1y + d2y);
      const D2 cn = float_pair(sc.link_damping[n0], sc.link_damping[n1]);
      const D2 cp = float_pair(sc.link_damping[p0], sc.link_damping[p1]);
      const D2 hn = 0.5 * cn, hp = 0.5 * cp;
      const V2 fn_d{fn.x + cn * vx, fn.y + cn * vy, fn.z + cn * vz};
      const V2 fp_d{fp.x - cp * vx, fp.y - cp * vy, fp.z - cp * vz};
      const V2 mn_d{mn.x - hn * (-sq_a2 * (d2x - d1x)),
                    mn.y - hn * (sq_b2 * dpz + sq_b3 * (2.0 * d1y + d2y)),
                    mn.z - hn * (-sq_b2 * dpy + sq_b3 * (2.0 * d1z + d2z))};
      const V2 mp_d{mp.x - hp * (sq_a2 * (d2x - d1x)),
                    mp.y - hp * (sq_b2 * dpz + sq_b3 * (d1y + 2.0 * d2y)),
                    mp.z - hp * (-sq_b2 * dpy + sq_b3 * (d1z + 2.0 * d2z))};
      if (damp == 3) {  // both lanes (the usual case)
        fn = fn_d;
        fp = fp_d;
        mn = mn_d;
        mp = mp_d;
      } else {
        const M2 on = M2{(damp & 1) ? -1LL : 0LL, (damp & 2) ? -1LL : 0LL};
        fn = {select(on, fn_d.x, fn.x), select(on, fn_d.y, fn.y), select(on, fn_d.z, fn.z)};
        fp = {select(on, fp_d.x, fp.x), select(on, fp_d.y, fp.y), select(on, fp_d.z, fp.z)};
        mn = {select(on, mn_d.x, mn.x), select(on, mn_d.y, mn.y), select(on, mn_d.z, mn.z)};
        mp = {select(on, mp_d.x, mp.x), select(on, mp_d.y, mp.y), select(on, mp_d.z, mp.z)};
      }
    }
    // §2.6: small-angle mode, so F_N and M_N are already in N's frame; F_P, M_P rotate by q2*
    V2 fpl, mpl;
    rotate_c(q2.w, -q2.x, -q2.y, -q2.z, fp.x, fp.y, fp.z, fpl.x, fpl.y, fpl.z);
    rotate_c(q2.w, -q2.x, -q2.y, -q2.z, mp.x, mp.y, mp.z, mpl.x, mpl.y, mpl.z);
    Scratch::EndLoad* out0 = &sc.link_end_load[2 * static_cast<std::size_t>(i0)];
    Scratch::EndLoad* out1 = &sc.link_end_load[2 * static_cast<std::size_t>(i1)];
    store2(from_x2<A>(fn), out0[0].force, out1[0].force, done);
    store2(from_x2<A>(mn), out0[0].moment, out1[0].moment, done);
    store2(from_x2<A>(fpl), out0[1].force, out1[1].force, done);
    store2(from_x2<A>(mpl), out0[1].moment, out1[1].moment, done);
  }
  const float strain0 = static_cast<float>(strain[0]), strain1 = static_cast<float>(strain[1]);
  if (done & 1) {
    st.link_vel_valid[i0] = st.link_small_angle[i0] = 1;
    st.link_strain[i0] = strain0;
  }
  if (done & 2) {
    st.link_vel_valid[i1] = st.link_small_angle[i1] = 1;
    st.link_strain[i1] = strain1;
  }
  store2(pos2, st.link_pos2[i0], st.link_pos2[i1], done);
  store2(a1, st.link_angle1v[i0], st.link_angle1v[i1], done);
  store2(a2, st.link_angle2v[i0], st.link_angle2v[i1], done);
  return done;
}

// Link pass (§2.3-2.6) over the links of axis A. Links that were in small-angle mode at their
// last update go through link_pair two at a time (a lane that leaves small-angle mode falls back
// to link_scalar); the others, in large-angle mode, through link_scalar directly. Links are
// independent within a pass, so this order gives the same results as list order. With kForces
// the end loads are computed and the return value is true if any strain > 100; without, the
// state-only mid-step pass of the fork (§2.9 item 6).
template <Axis A, bool kForces>
bool link_pass_axis(const Model& m, State& st, Scratch& sc) {
  bool diverged = false;
  const int* ids = m.links_by_axis.data();
  const int begin = m.axis_link_begin[static_cast<int>(A)];
  const int end = m.axis_link_begin[static_cast<int>(A) + 1];
  auto one = [&](int i) {
    if constexpr (kForces) {
      if (link_scalar<A>(m, st, sc, i)) diverged = true;
    } else {
      link_scalar_state_only<A>(m, st, i);
    }
  };
  int pending = -1;  // a small-angle link waiting for a partner
  for (int j = begin; j < end; ++j) {
    const int i = ids[j];
    if (!st.link_small_angle[i]) {
      one(i);
    } else if (pending < 0) {
      pending = i;
    } else {
      const int done = link_pair<A, kForces>(m, st, sc, pending, i, diverged);
      if (!(done & 1)) one(pending);
      if (!(done & 2)) one(i);
      pending = -1;
    }
  }
  if (pending >= 0) one(pending);
  return diverged;
}

// Full link pass (§2.3-2.6) over all links. Returns true if any strain > 100. (The passes are
// kept out of line, once per step, so that profiles attribute their cost.)
[[gnu::noinline]] bool link_pass_forces(const Model& m, State& st, Scratch& sc) {
  // c_V = 2 sqrt(m_V) zeta_int / previousDt_V (float, §2.5); only read by links with a valid
  // local velocity, i.e. after a step has set previous_dt
  const float prev_dt = st.previous_dt;
  for (int v = 0; v < m.voxel_count; ++v) sc.link_damping[v] = m.voxel_const[v].damp_base / prev_dt;
  const bool dx = link_pass_axis<Axis::x, true>(m, st, sc);
  const bool dy = link_pass_axis<Axis::y, true>(m, st, sc);
  const bool dz = link_pass_axis<Axis::z, true>(m, st, sc);
  return dx || dy || dz;
}

// Mid-step link pass of the fork (§2.9 item 6), state only.
[[gnu::noinline]] void link_pass_state_only(const Model& m, State& st, Scratch& sc) {
  link_pass_axis<Axis::x, false>(m, st, sc);
  link_pass_axis<Axis::y, false>(m, st, sc);
  link_pass_axis<Axis::z, false>(m, st, sc);
}

// Sum of the link forces and moments acting on voxel v (local frame), direction order 0..5.
inline void gather_links(const Model& m, const Scratch& sc, int v, Vec3& force, Vec3& moment) {
  force = Vec3::Zero();
  moment = Vec3::Zero();
  const int end = m.voxel_link_begin[v + 1];
  for (int e = m.voxel_link_begin[v]; e < end; ++e) {
    const Scratch::EndLoad& load = sc.link_end_load[m.voxel_link_entry[e]];
    force += load.force;
    moment += load.moment;
  }
}

inline int cell_coord(double x, double inv_h) {
  const double c = std::floor(x * inv_h);
  if (!(c > -1.0e9)) return -1000000000;  // also catches NaN
  if (c > 1.0e9) return 1000000000;
  return static_cast<int>(c);
}

inline std::size_t bucket_of(int cx, int cy, int cz, std::size_t mask) {
  const std::uint64_t h = static_cast<std::uint64_t>(static_cast<std::uint32_t>(cx)) * 73856093u ^
                          static_cast<std::uint64_t>(static_cast<std::uint32_t>(cy)) * 19349663u ^
                          static_cast<std::uint64_t>(static_cast<std::uint32_t>(cz)) * 83492791u;
  return static_cast<std::size_t>(h) & mask;
}

// §2.10 pair rebuild. Same pairs, in the same order, as the reference's O(N^2) scan: for each
// surface voxel a in list order, every later surface voxel b with |pos_a - pos_b|^2 <= (2.5 s)^2
// that is not within 5 link hops; found here through a uniform grid of cell size 2.5 s.
void rebuild_pairs(const Model& m, State& st, Scratch& sc) {
  const auto& surf = m.surface_voxels;
  const int ns = static_cast<int>(surf.size());
  const float radius = static_cast<float>(m.collision_watch_radius);
  const float thresh_sq = radius * radius;  // float, as Voxelyze's threshRadiusSq
  const double inv_h = 1.0 / static_cast<double>(radius);
  const std::size_t mask = sc.grid_head.size() - 1;
  std::fill(sc.grid_head.begin(), sc.grid_head.end(), -1);
  // insert in reverse so that each bucket lists its voxels in ascending slot order
  for (int si = ns - 1; si >= 0; --si) {
    const Vec3& p = st.pos[surf[si]];
    const int cx = cell_coord(p.x(), inv_h), cy = cell_coord(p.y(), inv_h),
              cz = cell_coord(p.z(), inv_h);
    sc.grid_cell[3 * si] = cx;
    sc.grid_cell[3 * si + 1] = cy;
    sc.grid_cell[3 * si + 2] = cz;
    const std::size_t b = bucket_of(cx, cy, cz, mask);
    sc.grid_next[si] = sc.grid_head[b];
    sc.grid_head[b] = si;
  }
  int count = 0;
  for (int si = 0; si < ns; ++si) {
    const int a = surf[si];
    const Vec3& pa = st.pos[a];
    // Voxelyze: lastColWatchPosition = (Vec3D<float>)pos for every non-interior voxel
    st.col_watch_pos[a] = {static_cast<float>(pa.x()), static_cast<float>(pa.y()),
                           static_cast<float>(pa.z())};
    sc.candidates.clear();
    const int cx = sc.grid_cell[3 * si], cy = sc.grid_cell[3 * si + 1],
              cz = sc.grid_cell[3 * si + 2];
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const int qx = cx + dx, qy = cy + dy, qz = cz + dz;
          for (int sj = sc.grid_head[bucket_of(qx, qy, qz, mask)]; sj >= 0; sj = sc.grid_next[sj]) {
            if (sj <= si) continue;  // slots ascend with voxel id: keep b > a only
            if (sc.grid_cell[3 * sj] != qx || sc.grid_cell[3 * sj + 1] != qy ||
                sc.grid_cell[3 * sj + 2] != qz)
              continue;  // another cell hashed to this bucket
            const int b = surf[sj];
            const Vec3& pb = st.pos[b];
            const double ex = pa.x() - pb.x(), ey = pa.y() - pb.y(), ez = pa.z() - pb.z();
            if (ex * ex + ey * ey + ez * ez > thresh_sq) continue;
            if (is_nearby(m, a, b)) continue;
            sc.candidates.push_back(sj);
          }
        }
    // creation order is ascending partner id (insertion sort; lists are short)
    auto& cand = sc.candidates;
    for (std::size_t x = 1; x < cand.size(); ++x) {
      const int key = cand[x];
      std::size_t y = x;
      for (; y > 0 && cand[y - 1] > key; --y) cand[y] = cand[y - 1];
      cand[y] = key;
    }
    for (int sj : cand) {
      if (count == static_cast<int>(st.col_pairs.size())) {
        // pathological pile-up beyond the reserved slots: grow (the only allocation in a step)
        st.col_pairs.resize(st.col_pairs.size() * 2 + 64);
        ++st.counters.collision_pair_growths;
      }
      st.col_pairs[count++] = CollisionPair{a, surf[sj]};
    }
  }
  st.col_pair_count = count;
  if (sc.pair_force.size() < st.col_pairs.size())
    sc.pair_force.resize(st.col_pairs.size(), {0.0f, 0.0f, 0.0f});
  st.collisions_stale = false;
  ++st.counters.collision_rebuilds;
}

// §2.10: staleness check, rebuild if stale, pair forces -> collision_force (collisionF of §2.7).
[[gnu::noinline]] void update_collisions(const Model& m, State& st, Scratch& sc) {
  if (!st.collisions_stale) {
    const float rd = static_cast<float>(m.collision_recalc_distance);
    const float rd_sq = rd * rd;
    for (int v : m.surface_voxels) {
      const Vec3& p = st.pos[v];
      const auto& w = st.col_watch_pos[v];
      const double ex = p.x() - w[0], ey = p.y() - w[1], ez = p.z() - w[2];
      if (ex * ex + ey * ey + ez * ez > rd_sq) {
        st.collisions_stale = true;
        break;
      }
    }
  }
  if (st.collisions_stale) rebuild_pairs(m, st, sc);

  std::fill(sc.collision_force.begin(), sc.collision_force.end(), Vec3::Zero());
  // D0 = (s + s) * 0.625 (sum of the two base sizes x envelope radius), float
  const float nom_dist = static_cast<float>((m.voxel_size + m.voxel_size) * 0.625f);
  for (int k = 0; k < st.col_pair_count; ++k) {
    const int a = st.col_pairs[k].a, b = st.col_pairs[k].b;
    const Vec3& p1 = st.pos[a];
    const Vec3& p2 = st.pos[b];
    const float ox = static_cast<float>(p2.x() - p1.x()), oy = static_cast<float>(p2.y() - p1.y()),
                oz = static_cast<float>(p2.z() - p1.z());
    const float len = std::sqrt(ox * ox + oy * oy + oz * oz);
    const float rel_dist = nom_dist - len;  // overlap, > 0 when touching
    if (!(rel_dist > 0)) continue;          // F = 0
    const float ux = ox / len, uy = oy / len, uz = oz / len;
    const VoxelConst& c1 = m.voxel_const[a];
    const VoxelConst& c2 = m.voxel_const[b];
    // k_c = harmonic mean of the k_pen, c_c = mean of C_col (float)
    const float kc = 2.0f / (1.0f / c1.k_pen + 1.0f / c2.k_pen);
    const float cc = 0.5f * (c1.c_col + c2.c_col);
    const Vec3& m1 = st.lin_mom[a];
    const Vec3& m2 = st.lin_mom[b];
    const double v1x = m1.x() * c1.inv_mass, v1y = m1.y() * c1.inv_mass, v1z = m1.z() * c1.inv_mass;
    const double v2x = m2.x() * c2.inv_mass, v2y = m2.y() * c2.inv_mass, v2z = m2.z() * c2.inv_mass;
    const double dux = ux, duy = uy, duz = uz;
    // v_rel = v1.n - v2.n (positive = approaching), float
    const float rel_vel = static_cast<float>((v1x * dux + v1y * duy + v1z * duz) -
                                             (v2x * dux + v2y * duy + v2z * duz));
    const float mag = kc * rel_dist + cc * rel_vel;
    const float fx = ux * mag, fy = uy * mag, fz = uz * mag;
    // voxel 1 receives -F, voxel 2 receives +F (collisionF = -sum of contactForce)
    sc.collision_force[a] -= Vec3(fx, fy, fz);
    sc.collision_force[b] -= Vec3(-fx, -fy, -fz);
  }
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

// fork_part1_voxel for two free voxels, one per SSE2 lane (same operations per lane; the floor
// force of §2.8 and the large-rotation branch of quat_from_rotvec per lane in scalar code).
inline void fork_part1_pair(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                            int v0, int v1, const Vec3& cog, V2& la, V2& lb) {
  const double dt = m.dt_f;
  const VoxelConst& c0 = m.voxel_const[v0];
  const VoxelConst& c1 = m.voxel_const[v1];
  V2 pos = load2(st.pos[v0], st.pos[v1]);
  V2 mom = load2(st.lin_mom[v0], st.lin_mom[v1]);
  V2 am = load2(st.ang_mom[v0], st.ang_mom[v1]);
  const Q2 q = load2(st.orient[v0], st.orient[v1]);
  const D2 cgx = splat(cog.x()), cgy = splat(cog.y()), cgz = splat(cog.z());
  {
    const D2 rx = pos.x - cgx, ry = pos.y - cgy, rz = pos.z - cgz;  // cross(pos - cog, mom) + am
    la = {(ry * mom.z - rz * mom.y) + am.x, (rz * mom.x - rx * mom.z) + am.y,
          (rx * mom.y - ry * mom.x) + am.z};
  }
  sc.old_pos[v0] = st.pos[v0];
  sc.old_pos[v1] = st.pos[v1];
  Vec3 ls0, ms0, ls1, ms1;
  gather_links(m, sc, v0, ls0, ms0);
  gather_links(m, sc, v1, ls1, ms1);
  const V2 lsum = load2(ls0, ls1), msum = load2(ms0, ms1);
  const D2 inv_mass = float_pair(c0.inv_mass, c1.inv_mass);
  const V2 vel{mom.x * inv_mass, mom.y * inv_mass, mom.z * inv_mass};
  V2 rl;
  rotate_c(q.w, q.x, q.y, q.z, lsum.x, lsum.y, lsum.z, rl.x, rl.y, rl.z);
  const D2 c_glob = float_pair(c0.c_glob, c1.c_glob);
  const V2 link_f{rl.x - vel.x * c_glob, rl.y - vel.y * c_glob, rl.z - vel.z * c_glob};
  V2 ext_f{splat(0.0), splat(0.0), splat(0.0)};
  if (!ext.empty()) {
    const Vec3& e0 = ext[v0];
    const Vec3& e1 = ext[v1];
    ext_f = {float_pair(static_cast<float>(e0.x()), static_cast<float>(e1.x())),
             float_pair(static_cast<float>(e0.y()), static_cast<float>(e1.y())),
             float_pair(static_cast<float>(e0.z()), static_cast<float>(e1.z()))};
  }
  const D2 zero = splat(0.0);
  const V2 grav_f{zero, zero, float_pair(c0.gravity_force, c1.gravity_force)};
  const V2 col_f = load2(sc.collision_force[v0], sc.collision_force[v1]);
  V2 fric{zero, zero, zero};
  if (m.floor) {
    const int contact = lanes(round_to_float(0.0 - pos.z) >= 0.0);
    const V2 fsum{((link_f.x + ext_f.x) + grav_f.x) + col_f.x,
                  ((link_f.y + ext_f.y) + grav_f.y) + col_f.y,
                  ((link_f.z + ext_f.z) + grav_f.z) + col_f.z};
    for (int k = 0; k < 2; ++k) {
      std::uint8_t& sf = st.static_friction[k ? v1 : v0];
      if (!(contact >> k & 1)) {
        sf = 0;  // floor_force without contact
        continue;
      }
      const Vec3 fr = floor_force(k ? c1 : c0, Vec3(pos.x[k], pos.y[k], pos.z[k]),
                                  Vec3(vel.x[k], vel.y[k], vel.z[k]),
                                  Vec3(fsum.x[k], fsum.y[k], fsum.z[k]), sf);
      fric.x[k] = fr.x();
      fric.y[k] = fr.y();
      fric.z[k] = fr.z();
    }
  }
  const V2 fle{link_f.x + ext_f.x, link_f.y + ext_f.y, link_f.z + ext_f.z};
  const D2 dt_m = round_to_float(dt * inv_mass);  // float dt * (1/m)
  pos = {pos.x + fle.x * dt * dt_m, pos.y + fle.y * dt * dt_m, pos.z + fle.z * dt * dt_m};
  mom = {mom.x + fle.x * dt, mom.y + fle.y * dt, mom.z + fle.z * dt};
  V2 rm;
  rotate_c(q.w, q.x, q.y, q.z, msum.x, msum.y, msum.z, rm.x, rm.y, rm.z);
  const D2 inv_i = float_pair(c0.inv_inertia, c1.inv_inertia);
  const D2 c_rot = float_pair(c0.c_glob_rot, c1.c_glob_rot);
  const V2 cur_m{rm.x - am.x * inv_i * c_rot, rm.y - am.y * inv_i * c_rot,
                 rm.z - am.z * inv_i * c_rot};
  const D2 dt_i = round_to_float(dt * inv_i);  // float dt * (1/I)
  const Q2 dq = quat_from_rotvec2({cur_m.x * dt * dt_i, cur_m.y * dt * dt_i, cur_m.z * dt * dt_i});
  Q2 qn;
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
  am = {am.x + cur_m.x * dt, am.y + cur_m.y * dt, am.z + cur_m.z * dt};
  store2(pos, st.pos[v0], st.pos[v1]);
  store2(mom, st.lin_mom[v0], st.lin_mom[v1]);
  store2(am, st.ang_mom[v0], st.ang_mom[v1]);
  store2(qn, st.orient[v0], st.orient[v1]);
  store2(V2{(grav_f.x + col_f.x) + fric.x, (grav_f.y + col_f.y) + fric.y,
            (grav_f.z + col_f.z) + fric.z},
         sc.part2_force[v0], sc.part2_force[v1]);
  store2(fric, sc.fric[v0], sc.fric[v1]);
  {
    const D2 rx = pos.x - cgx, ry = pos.y - cgy, rz = pos.z - cgz;
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
  sc.ext_moment[v] = {me_x, me_y, me_z};
  // NaN/inf anywhere makes the running sum non-finite (checked once after the loop; finite
  // values beyond ~1e307 that overflow the sum are reported as non-finite too)
  check +=
      pos.x() + pos.y() + pos.z() + mom.x() + mom.y() + mom.z() + am.x() + am.y() + am.z() + q.w;
}

// fork_part2_voxel for two free voxels, one per SSE2 lane (same operations per lane).
inline void fork_part2_pair(const Model& m, State& st, Scratch& sc, int v0, int v1, float me_x,
                            float me_y, float me_z, double& check) {
  const double dt = m.dt_f;
  const VoxelConst& c0 = m.voxel_const[v0];
  const VoxelConst& c1 = m.voxel_const[v1];
  V2 pos = load2(st.pos[v0], st.pos[v1]);
  V2 mom = load2(st.lin_mom[v0], st.lin_mom[v1]);
  V2 am = load2(st.ang_mom[v0], st.ang_mom[v1]);
  const Q2 q = load2(st.orient[v0], st.orient[v1]);
  const V2 f2 = load2(sc.part2_force[v0], sc.part2_force[v1]);
  const D2 inv_mass = float_pair(c0.inv_mass, c1.inv_mass);
  const D2 dt_m = round_to_float(dt * inv_mass);  // float dt * (1/m)
  pos = {pos.x + f2.x * dt * dt_m, pos.y + f2.y * dt * dt_m, pos.z + f2.z * dt * dt_m};
  pos = {pos.x + mom.x * dt_m, pos.y + mom.y * dt_m, pos.z + mom.z * dt_m};
  mom = {mom.x + f2.x * dt, mom.y + f2.y * dt, mom.z + f2.z * dt};
  if (m.floor) {
    const int contact = lanes(round_to_float(0.0 - pos.z) >= 0.0);
    for (int k = 0; k < 2; ++k) {
      const int v = k ? v1 : v0;
      if (!(contact >> k & 1)) {
        st.static_friction[v] = 0;
        continue;
      }
      Vec3 pk(pos.x[k], pos.y[k], pos.z[k]), mk(mom.x[k], mom.y[k], mom.z[k]);
      fork_static_capture(k ? c1 : c0, sc.fric[v], sc.old_pos[v], pk, mk, st.static_friction[v]);
      pos.x[k] = pk.x();
      pos.y[k] = pk.y();
      mom.x[k] = mk.x();
      mom.y[k] = mk.y();
    }
  }
  am = {am.x + splat(static_cast<double>(me_x) * dt), am.y + splat(static_cast<double>(me_y) * dt),
        am.z + splat(static_cast<double>(me_z) * dt)};
  const D2 inv_i = float_pair(c0.inv_inertia, c1.inv_inertia);
  const Q2 dq = quat_from_rotvec2({am.x * inv_i * dt, am.y * inv_i * dt, am.z * inv_i * dt});
  Q2 qn;
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
  store2(pos, st.pos[v0], st.pos[v1]);
  store2(mom, st.lin_mom[v0], st.lin_mom[v1]);
  store2(am, st.ang_mom[v0], st.ang_mom[v1]);
  store2(qn, st.orient[v0], st.orient[v1]);
  sc.ext_moment[v0] = sc.ext_moment[v1] = {me_x, me_y, me_z};
  const D2 sum = pos.x + pos.y + pos.z + mom.x + mom.y + mom.z + am.x + am.y + am.z + qn.w;
  check += sum[0];
  check += sum[1];
}

// §2.12 steps 3-9 (after the link pass and the collisions): the fork's two-part step. Free
// voxels go through the parts in pairs (SSE2 lanes); sums over voxels keep list order.
[[gnu::noinline]] bool fork_voxel_passes(const Model& m, State& st, Scratch& sc,
                                         std::span<const Vec3> ext) {
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
  int v = 0;
  for (; v + 1 < nv; v += 2) {
    if (!m.voxel_fixed[v] && !m.voxel_fixed[v + 1]) {
      V2 a, b;
      fork_part1_pair(m, st, sc, ext, v, v + 1, cog, a, b);
      la += Vec3(a.x[0], a.y[0], a.z[0]);
      la += Vec3(a.x[1], a.y[1], a.z[1]);
      lb += Vec3(b.x[0], b.y[0], b.z[0]);
      lb += Vec3(b.x[1], b.y[1], b.z[1]);
    } else {
      if (!m.voxel_fixed[v]) part1(v);
      if (!m.voxel_fixed[v + 1]) part1(v + 1);
    }
  }
  if (v < nv && !m.voxel_fixed[v]) part1(v);

  // 6. mid-step link update (state only)
  link_pass_state_only(m, st, sc);

  // 7. correction moment -dL / dt / N_all (float), same for every non-fixed voxel
  const Vec3 dl = lb - la;
  const double n_all = static_cast<double>(nv);
  const double dtd = dt;
  const float me_x = static_cast<float>(-dl.x() / dtd / n_all);
  const float me_y = static_cast<float>(-dl.y() / dtd / n_all);
  const float me_z = static_cast<float>(-dl.z() / dtd / n_all);

  // 8. part 2
  double check = 0.0;
  for (v = 0; v + 1 < nv; v += 2) {
    if (!m.voxel_fixed[v] && !m.voxel_fixed[v + 1]) {
      fork_part2_pair(m, st, sc, v, v + 1, me_x, me_y, me_z, check);
    } else {
      if (!m.voxel_fixed[v]) fork_part2_voxel(m, st, sc, v, me_x, me_y, me_z, check);
      if (!m.voxel_fixed[v + 1]) fork_part2_voxel(m, st, sc, v + 1, me_x, me_y, me_z, check);
    }
  }
  if (v < nv && !m.voxel_fixed[v]) fork_part2_voxel(m, st, sc, v, me_x, me_y, me_z, check);
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

// symplectic_voxel for two free voxels v0, v1, one per SSE2 lane (same operations per lane as
// the scalar path; the floor contact of §2.8 and the large-rotation branch of quat_from_rotvec
// are done per lane in scalar code).
inline void symplectic_pair(const Model& m, State& st, Scratch& sc, std::span<const Vec3> ext,
                            int v0, int v1, double& check) {
  const double dt = m.dt_f;
  const VoxelConst& c0 = m.voxel_const[v0];
  const VoxelConst& c1 = m.voxel_const[v1];
  Vec3 ls0, ms0, ls1, ms1;
  gather_links(m, sc, v0, ls0, ms0);
  gather_links(m, sc, v1, ls1, ms1);
  const V2 lsum = load2(ls0, ls1), msum = load2(ms0, ms1);
  V2 pos = load2(st.pos[v0], st.pos[v1]);
  V2 mom = load2(st.lin_mom[v0], st.lin_mom[v1]);
  V2 am = load2(st.ang_mom[v0], st.ang_mom[v1]);
  const Q2 q = load2(st.orient[v0], st.orient[v1]);
  const D2 inv_mass = float_pair(c0.inv_mass, c1.inv_mass);
  const V2 vel{mom.x * inv_mass, mom.y * inv_mass, mom.z * inv_mass};
  V2 f;
  rotate_c(q.w, q.x, q.y, q.z, lsum.x, lsum.y, lsum.z, f.x, f.y, f.z);
  if (!ext.empty()) {
    const Vec3& e0 = ext[v0];
    const Vec3& e1 = ext[v1];
    f.x = f.x + float_pair(static_cast<float>(e0.x()), static_cast<float>(e1.x()));
    f.y = f.y + float_pair(static_cast<float>(e0.y()), static_cast<float>(e1.y()));
    f.z = f.z + float_pair(static_cast<float>(e0.z()), static_cast<float>(e1.z()));
  }
  const D2 c_glob = float_pair(c0.c_glob, c1.c_glob);
  f = {f.x - vel.x * c_glob, f.y - vel.y * c_glob, f.z - vel.z * c_glob};
  f.z = f.z + float_pair(c0.gravity_force, c1.gravity_force);
  const V2 col = load2(sc.collision_force[v0], sc.collision_force[v1]);
  f = {f.x + col.x, f.y + col.y, f.z + col.z};
  int contact = 0;  // lane bits
  if (m.floor) {
    contact = lanes(round_to_float(0.0 - pos.z) >= 0.0);
    V2 fric{splat(0.0), splat(0.0), splat(0.0)};
    for (int k = 0; k < 2; ++k) {
      std::uint8_t& sf = st.static_friction[k ? v1 : v0];
      if (!(contact >> k & 1)) {
        sf = 0;  // floor_force without contact
        continue;
      }
      const Vec3 fr =
          floor_force(k ? c1 : c0, Vec3(pos.x[k], pos.y[k], pos.z[k]),
                      Vec3(vel.x[k], vel.y[k], vel.z[k]), Vec3(f.x[k], f.y[k], f.z[k]), sf);
      fric.x[k] = fr.x();
      fric.y[k] = fr.y();
      fric.z[k] = fr.z();
    }
    f = {f.x + fric.x, f.y + fric.y, f.z + fric.z};
  }
  mom = {mom.x + f.x * dt, mom.y + f.y * dt, mom.z + f.z * dt};
  const D2 dt_m = round_to_float(dt * inv_mass);  // float dt * (1/m)
  V2 tr{mom.x * dt_m, mom.y * dt_m, mom.z * dt_m};
  for (int k = 0; k < 2; ++k) {
    if (!(contact >> k & 1)) continue;
    std::uint8_t& sf = st.static_friction[k ? v1 : v0];
    const double work = f.x[k] * tr.x[k] + f.y[k] * tr.y[k];
    const double hke = 0.5 * (k ? c1 : c0).inv_mass * (mom.x[k] * mom.x[k] + mom.y[k] * mom.y[k]);
    if (hke + work <= 0) sf = 1;
    if (sf) {
      mom.x[k] = mom.y[k] = 0.0;
      tr.x[k] = tr.y[k] = 0.0;
    }
  }
  pos = {pos.x + tr.x, pos.y + tr.y, pos.z + tr.z};
  V2 rm;
  rotate_c(q.w, q.x, q.y, q.z, msum.x, msum.y, msum.z, rm.x, rm.y, rm.z);
  const D2 inv_i = float_pair(c0.inv_inertia, c1.inv_inertia);
  const D2 c_rot = float_pair(c0.c_glob_rot, c1.c_glob_rot);
  const V2 cur_m{rm.x - am.x * inv_i * c_rot, rm.y - am.y * inv_i * c_rot,
                 rm.z - am.z * inv_i * c_rot};
  am = {am.x + cur_m.x * dt, am.y + cur_m.y * dt, am.z + cur_m.z * dt};
  const Q2 dq = quat_from_rotvec2({am.x * inv_i * dt, am.y * inv_i * dt, am.z * inv_i * dt});
  Q2 qn;
  mul_c(dq.w, dq.x, dq.y, dq.z, q.w, q.x, q.y, q.z, qn.w, qn.x, qn.y, qn.z);
  store2(pos, st.pos[v0], st.pos[v1]);
  store2(mom, st.lin_mom[v0], st.lin_mom[v1]);
  store2(am, st.ang_mom[v0], st.ang_mom[v1]);
  store2(qn, st.orient[v0], st.orient[v1]);
  const D2 sum = pos.x + pos.y + pos.z + mom.x + mom.y + mom.z + am.x + am.y + am.z + qn.w;
  check += sum[0];
  check += sum[1];
}

// §2.9 upstream single-pass symplectic Euler with the same forces; free voxels in pairs.
[[gnu::noinline]] bool symplectic_voxel_pass(const Model& m, State& st, Scratch& sc,
                                             std::span<const Vec3> ext) {
  const int nv = m.voxel_count;
  st.previous_dt = m.dt_f;
  double check = 0.0;
  int v = 0;
  for (; v + 1 < nv; v += 2) {
    if (!m.voxel_fixed[v] && !m.voxel_fixed[v + 1]) {
      symplectic_pair(m, st, sc, ext, v, v + 1, check);
    } else {
      if (!m.voxel_fixed[v]) symplectic_voxel(m, st, sc, ext, v, check);
      if (!m.voxel_fixed[v + 1]) symplectic_voxel(m, st, sc, ext, v + 1, check);
    }
  }
  if (v < nv && !m.voxel_fixed[v]) symplectic_voxel(m, st, sc, ext, v, check);
  return std::isfinite(check);
}

}  // namespace

StepStatus step(const Model& model, State& state, Scratch& scratch,
                std::span<const Vec3> external_force) {
  if (!external_force.empty() &&
      external_force.size() != static_cast<std::size_t>(model.voxel_count))
    throw std::invalid_argument("physics::step: external_force has " +
                                std::to_string(external_force.size()) + " entries, model has " +
                                std::to_string(model.voxel_count) + " voxels");
  // 1. link pass; strain > 100 -> nothing else advances
  if (link_pass_forces(model, state, scratch)) {
    ++state.counters.diverged_steps;
    return StepStatus::diverged;
  }
  // 2. collisions
  if (model.self_collision) update_collisions(model, state, scratch);
  const bool finite = model.integrator == Integrator::pneuvox
                          ? fork_voxel_passes(model, state, scratch, external_force)
                          : symplectic_voxel_pass(model, state, scratch, external_force);
  state.time += model.dt_f;  // 9.
  if (!finite) {
    ++state.counters.non_finite_steps;
    return StepStatus::non_finite;
  }
  ++state.counters.steps;
  return StepStatus::ok;
}

}  // namespace softevo::physics
