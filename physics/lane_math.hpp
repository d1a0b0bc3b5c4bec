// The reproducible acos / sin / cos of physics/reproducible_math.hpp and the quaternion functions
// of §2.11 that use them (rotvec, quat_from_rotvec, frame_to_pos_x), on lane vectors: every
// branch in SIMD, the rare ones only when a lane needs them. Same bits as the scalar functions of
// quat.hpp. Internal to physics/ (see physics/lanes.hpp).
#pragma once

#include "physics/lanes.hpp"
#include "physics/quat.hpp"
#include "physics/reproducible_math.hpp"

namespace softevo::physics {
namespace {

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

// §2.11 "angle to +X" on lanes: q1, the rotation taking direction d onto +X (identity for d = 0),
// and its rotation vector a1 = rotvec(q1), together (the large-angle link frame, §2.3). Every
// branch in SIMD, the closed-form one only when a lane needs it; len = |d| = sqrt(d.x^2 + d.y^2 +
// d.z^2), which the caller also needs. The branches, first match wins, per lane:
//   d = 0:                                  q1 = identity, a1 = 0
//   |d_y / d_x|, |d_z / d_x| < kNearPosXBelow:  the reference's Taylor q1 = (1 - (y^2 + z^2) / 2,
//                                           0, y, z), y = d_z / (2 d_x), z = -d_y / (2 d_x);
//                                           a1 = rotvec(q1)
//   n_x < kReversedBelow (n = d / |d|):     q1 = (0, 0, 1, 0), a1 = rotvec(q1)
//   otherwise:                              the closed form below
//
// Physics revision 2 (physics/revision.hpp) evaluates the general branch in closed form. With
// theta = acos(n_x) and s = sqrt(n_y^2 + n_z^2) = sin(theta):
//   q1 = (cos(theta/2), 0, n_z k sin(theta/2), -n_y k sin(theta/2)),  k = 1 / s      (reference)
//      = (c, 0, n_z h, -n_y h),  c = cos(theta/2) = sqrt((1 + n_x) / 2),  h = 1 / (2c)
//        (half-angle identities: k sin(theta/2) = sin(theta/2) / sin(theta) = 1 / (2 cos(theta/2)))
//   a1 = 2 acos(c) / sqrt(1 - c^2) (q1.x, q1.y, q1.z)                          (reference rotvec)
//      = (0, theta n_z / s, -theta n_y / s)        (acos(c) = theta/2, sqrt(1 - c^2) = s / (2c))
// The same numbers up to rounding, without sin, cos, a second acos and three divisions. Bends
// small enough for rotvec's Taylor branch (1 - c^2 < 2.4e-3: that branch is only good to ~1e-5
// relative, and the gaits should see the reference's a1 there) keep a1 = rotvec(q1).
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

}  // namespace
}  // namespace softevo::physics
