// Vector and quaternion helpers of the voxel physics, written to the exact formulas of
// docs/model.md §2.11 (the reference never renormalises a quaternion, and its Taylor branches
// leave orientations slightly non-unit; the gaits depend on that, so we reproduce it).
//
// Vec3 is Eigen::Vector3d (three packed doubles, no alignment requirement). The hot loops use
// .x()/.y()/.z() and spell every product out so that the operation order (and thus the rounding,
// with -ffp-contract=off) is the one written in the comment. acos, sin and cos are
// physics/reproducible_math.hpp's (physics revision 2), not the C library's, so the SIMD passes
// compute the same bits on their lanes.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "physics/reproducible_math.hpp"

namespace softevo::physics {

using Vec3 = Eigen::Vector3d;  // double 3-vector; the role of Voxelyze's Vec3D<double>

// Quaternion stored as (w, x, y, z) doubles; identity = (1, 0, 0, 0).
struct Quat {
  double w = 1.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};

// a x b, component order as Voxelyze's Vec3D::Cross.
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(),
          a.x() * b.y() - a.y() * b.x()};
}

inline Quat conj(const Quat& q) {
  return {q.w, -q.x, -q.y, -q.z};
}

// The helpers below are always_inline: the step passes are also compiled for AVX2
// (physics/step_avx2.cpp), and an out-of-line copy emitted there could be linked into the SSE2
// code as well (checked by the PhysicsIsa test).
//
// The formulas below are written once, generic over the scalar type T (double, or a pair of
// doubles for the two-link SIMD link pass of step.cpp), so every caller performs exactly the
// same operations in the same order (bit-identical results, -ffp-contract=off).

// §2.11: Hamilton product a ⊗ b. "Rotate by A then by B" = B ⊗ A.
template <class T>
[[gnu::always_inline]] inline void mul_c(T aw, T ax, T ay, T az, T bw, T bx, T by, T bz, T& w, T& x,
                                         T& y, T& z) {
  w = aw * bw - ax * bx - ay * by - az * bz;
  x = aw * bx + ax * bw + ay * bz - az * by;
  y = aw * by - ax * bz + ay * bw + az * bx;
  z = aw * bz + ax * by - ay * bx + az * bw;
}
inline Quat mul(const Quat& a, const Quat& b) {
  Quat r;
  mul_c(a.w, a.x, a.y, a.z, b.w, b.x, b.y, b.z, r.w, r.x, r.y, r.z);
  return r;
}

// §2.11: v' = q v q*, expanded: t = (0,v) ⊗ q*, then v' = vector part of q ⊗ t.
template <class T>
[[gnu::always_inline]] inline void rotate_c(T qw, T qx, T qy, T qz, T fx, T fy, T fz, T& ox, T& oy,
                                            T& oz) {
  const T tw = fx * qx + fy * qy + fz * qz;
  const T tx = fx * qw - fy * qz + fz * qy;
  const T ty = fx * qz + fy * qw - fz * qx;
  const T tz = -fx * qy + fy * qx + fz * qw;
  ox = qw * tx + qx * tw + qy * tz - qz * ty;
  oy = qw * ty - qx * tz + qy * tw + qz * tx;
  oz = qw * tz + qx * ty - qy * tx + qz * tw;
}
inline Vec3 rotate(const Quat& q, const Vec3& f) {
  Vec3 r;
  rotate_c(q.w, q.x, q.y, q.z, f.x(), f.y(), f.z(), r.x(), r.y(), r.z());
  return r;
}

// §2.11: inverse rotation = rotation by the conjugate.
inline Vec3 rotate_inv(const Quat& q, const Vec3& f) {
  return rotate(conj(q), f);
}

// Branch thresholds of §2.11, shared by the scalar functions below and their lane versions in
// physics/lane_math.hpp, which must branch exactly alike:
constexpr double kRotvecToQuatTaylorBelow =
    5.328e-15;                                       // quat_from_rotvec: Taylor if |r/2|^4 < this
constexpr double kQuatToRotvecTaylorBelow = 2.4e-3;  // rotvec: Taylor if 1 - w^2 < this
constexpr double kNearPosXBelow =
    1.732e-2;  // frame_to_pos_x: Taylor if |d_y/d_x|, |d_z/d_x| < this

// §2.11: quaternion from rotation vector r (Taylor branch for half-angles below ~2.7e-4 rad).
[[gnu::always_inline]] inline Quat quat_from_rotvec(const Vec3& r) {
  const double hx = r.x() / 2, hy = r.y() / 2, hz = r.z() / 2;  // theta = r/2
  const double t = hx * hx + hy * hy + hz * hz;                 // |theta|^2
  double w, s;
  if (t * t < kRotvecToQuatTaylorBelow) {
    w = 1.0 - t / 2;
    s = 1.0 - t / 6;
  } else if (t <= rmath::kSincCosSquareLimit) {
    // physics revision 3: w = cos|theta| and s = sin|theta| / |theta| straight from t (every
    // turn below 1.5 rad per step, that is every voxel that has not exploded)
    rmath::sinc_cos_of_square(t, s, w);
  } else {
    const double mag = std::sqrt(t);
    double sin_mag;
    rmath::sincos(mag, sin_mag, w);
    s = sin_mag / mag;
  }
  return {w, hx * s, hy * s, hz * s};
}

// §2.11: rotation vector of q (no renormalisation; w outside (-1,1) gives 0).
[[gnu::always_inline]] inline Vec3 rotvec(const Quat& q) {
  if (q.w >= 1.0 || q.w <= -1.0) return Vec3::Zero();
  const double t = 1.0 - q.w * q.w;
  if (t < kQuatToRotvecTaylorBelow) {
    const double k = std::sqrt((2 - 2 * q.w) / t);
    return {q.x * 2.0 * k, q.y * 2.0 * k, q.z * 2.0 * k};
  }
  // the reference divides each component (q.x * 2 * a / rs); physics revision 3 divides once
  const double a = rmath::acos(q.w), rs = std::sqrt(t);
  const double f = 2.0 * a / rs;
  return {q.x * f, q.y * f, q.z * f};
}

// §2.11 "angle to +X" (the large-angle link frame, §2.3) is computed on lanes only
// (physics/lane_math.hpp frame_to_pos_x_lanes): every link runs it there, one lane wide when it
// switches mode. Its reversed-direction threshold: cos(3.14159265358979 - 1e-7).
constexpr double kReversedBelow = -0x1.fffffffffffd3p-1;

}  // namespace softevo::physics
