// The link update of §2.2-2.6 for one link: the reference path, which the grouped passes
// (physics/link_lanes.hpp) reproduce lane by lane and fall back to for a link that switches
// between small- and large-angle mode. Internal to physics/ (see physics/lanes.hpp).
#pragma once

#include <cmath>
#include <cstddef>

#include "physics/link_mode.hpp"
#include "physics/model.hpp"
#include "physics/quat.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"

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

}  // namespace
}  // namespace softevo::physics
