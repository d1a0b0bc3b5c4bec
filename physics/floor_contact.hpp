// Floor contact of one voxel (§2.8): the normal spring-damper, friction, and the static-friction
// capture of the fork's part 2. Where the floor is comes from physics/floor.hpp alone. Internal
// to physics/ (see physics/lanes.hpp).
#pragma once

#include <cmath>
#include <cstdint>

#include "physics/floor.hpp"
#include "physics/lanes.hpp"
#include "physics/model.hpp"

namespace softevo::physics {
namespace {

// Voxel penetration below the floor: height - z (s/2 - s/2 - z of the reference: the
// voxel's half size cancels), rounded to float as the reference's penetration. A voxel touches
// the floor when it is >= 0 (NaN never touches).
[[gnu::always_inline]] inline float penetration(const Vec3& pos) {
  return static_cast<float>(floor_at(pos.x(), pos.y()).height - pos.z());
}
// The same for W voxels: lane bit k set where voxel k touches the floor.
template <class L>
[[gnu::always_inline]] inline int floor_contact_lanes(const VL<L>& pos) {
  return L::bits(L::round_to_float(floor_at(pos.x, pos.y).height - pos.z) >= 0.0);
}

// §2.8 floorForce(Fsum): normal spring-damper + friction at the start-of-step velocity; may
// clear the static flag. Returns fric (normal + friction).
inline Vec3 floor_force(const VoxelConst& c, const Vec3& pos, const Vec3& vel, const Vec3& fsum,
                        std::uint8_t& static_flag) {
  const float pen = penetration(pos);
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
  const float pen = penetration(pos);
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

}  // namespace
}  // namespace softevo::physics
