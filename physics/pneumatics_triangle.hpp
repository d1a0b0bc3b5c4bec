// The per-triangle formulas of the chamber meshes (docs/model.md §3.2, §3.4), written once,
// generic over the number type T: double in the scalar path (pneumatics.cpp), a vector of W
// doubles in the lane passes (step_kernels.hpp). Both perform the same IEEE operations in the
// same order (-ffp-contract=off), so every SIMD width gives the same bits. Internal to physics/.
//
// Ops supplies, for T: round_to_float(x) (x rounded to float, as T), sqrt(x) (IEEE, correctly
// rounded) and positive_or_one(x) (x if x > 0, else 1).
#pragma once

#include <cmath>

#include "physics/pneumatics.hpp"

namespace softevo::physics {

template <class T>
struct Point3 {
  T x, y, z;
};

// (always_inline, as every helper here: the lane passes are also compiled for AVX2 and AVX-512,
// and an out-of-line copy emitted there could be linked into the SSE2 code; see quat.hpp.)
[[gnu::always_inline]] inline Point3<double> to_point3(const Vec3& v) {
  return {v.x(), v.y(), v.z()};
}

// Ops of the scalar path.
struct ScalarTriangleOps {
  [[gnu::always_inline]] static double round_to_float(double x) { return static_cast<float>(x); }
  [[gnu::always_inline]] static double sqrt(double x) { return std::sqrt(x); }
  [[gnu::always_inline]] static double positive_or_one(double x) { return x > 0.0 ? x : 1.0; }
};

// §3.2: signed volume of the tetrahedron (p0, A, B, C),
// (C-p0) . ((B-p0) x (A-p0)) / 6, in double [m^3].
template <class T>
[[gnu::always_inline]] inline T triangle_tet_volume(const Point3<T>& pa, const Point3<T>& pb,
                                                    const Point3<T>& pc, const Point3<T>& p0) {
  const T ax = pa.x - p0.x, ay = pa.y - p0.y, az = pa.z - p0.z;
  const T bx = pb.x - p0.x, by = pb.y - p0.y, bz = pb.z - p0.z;
  const T cx = pc.x - p0.x, cy = pc.y - p0.y, cz = pc.z - p0.z;
  const T nx = by * az - bz * ay;
  const T ny = bz * ax - bx * az;
  const T nz = bx * ay - by * ax;
  return (cx * nx + cy * ny + cz * nz) / 6.0;
}

// §3.4: the pressure force on triangle (A, B, C) at gauge pressure `gauge` [bar], one third per
// vertex, each component a float value [N]:
//   n = (C-B) x (A-B) (inward normal times twice the area), area = float(|n| / 2),
//   n_hat = n / |n| (a zero vector stays zero, §2.11 normalise),
//   F = -n_hat * (p - 1) * area * 1e5, evaluated left to right per component; F/3 to float.
// n / positive_or_one(|n|) is the §2.11 normalise bit for bit: for |n| > 0 it is n / |n|, and
// otherwise n / 1 = n exactly.
template <class Ops, class T>
[[gnu::always_inline]] inline Point3<T> triangle_force_third(const Point3<T>& pa,
                                                             const Point3<T>& pb,
                                                             const Point3<T>& pc, T gauge) {
  const T cbx = pc.x - pb.x, cby = pc.y - pb.y, cbz = pc.z - pb.z;
  const T abx = pa.x - pb.x, aby = pa.y - pb.y, abz = pa.z - pb.z;
  const T nx = cby * abz - cbz * aby;
  const T ny = cbz * abx - cbx * abz;
  const T nz = cbx * aby - cby * abx;
  const T len = Ops::sqrt(nx * nx + ny * ny + nz * nz);
  const T area = Ops::round_to_float(0.5 * len);  // [m^2], a float in the reference
  const T unit = Ops::positive_or_one(len);
  const T ux = nx / unit, uy = ny / unit, uz = nz / unit;
  const T fx = -ux * gauge * area * kPascalPerBar;
  const T fy = -uy * gauge * area * kPascalPerBar;
  const T fz = -uz * gauge * area * kPascalPerBar;
  return {Ops::round_to_float(fx / 3.0), Ops::round_to_float(fy / 3.0),
          Ops::round_to_float(fz / 3.0)};
}

}  // namespace softevo::physics
