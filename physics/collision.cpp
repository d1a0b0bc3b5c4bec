// §2.10 self-collision: the staleness check of the pair list, the rebuild when stale
// (collision_broadphase.cpp) and the pair forces. Internal to physics/ (collision.hpp).
#include "physics/collision.hpp"

#include <algorithm>
#include <cmath>

namespace softevo::physics {

// §2.10: staleness check, rebuild if stale, pair forces -> collision_force (collisionF of §2.7).
void update_collisions(const Model& m, State& st, Scratch& sc) {
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
  if (st.collisions_stale) rebuild_collision_pairs(m, st, sc);

  if (!sc.collision_force_zero) {
    std::fill(sc.collision_force.begin(), sc.collision_force.end(), Vec3::Zero());
    sc.collision_force_zero = true;
  }
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
    sc.collision_force_zero = false;
    sc.collision_force[a] -= Vec3(fx, fy, fz);
    sc.collision_force[b] -= Vec3(-fx, -fy, -fz);
  }
}

}  // namespace softevo::physics
