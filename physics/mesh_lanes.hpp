// The chamber meshes (§3.2, §3.4) W triangles at a time: chamber volume and pressure forces.
// Internal to physics/ (see physics/lanes.hpp).
#pragma once

#include <span>

#include "physics/lanes.hpp"
#include "physics/pneumatics.hpp"
#include "physics/pneumatics_triangle.hpp"

namespace softevo::physics {
namespace {

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
    float* rows[W];  // (fx, fy, fz, 0) of each triangle
    for (int k = 0; k < W; ++k) rows[k] = scratch.triangle_force[t + k].data();
    store_float_rows<L>(f3.x, f3.y, f3.z, rows);
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

}  // namespace
}  // namespace softevo::physics
