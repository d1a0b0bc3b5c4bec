// Floor contact of one voxel (§2.8): the normal spring-damper, friction, and the static-friction
// capture of the fork's part 2 and of the symplectic step. Where the ground is comes from
// physics/floor.hpp (flat lanes) and physics/terrain.hpp (Model::terrain). Internal to physics/
// (see physics/lanes.hpp).
#pragma once

#include <cmath>
#include <cstdint>

#include "physics/floor.hpp"
#include "physics/lanes.hpp"
#include "physics/model.hpp"

namespace softevo::physics {
namespace {

// The same for W voxels on the flat floor: lane bit k set where voxel k touches it (height - z,
// rounded to float as the reference's penetration, >= 0; NaN never touches).
template <class L>
[[gnu::always_inline]] inline int floor_contact_lanes(const VL<L>& pos) {
  return L::bits(L::round_to_float(floor_at(pos.x, pos.y).height - pos.z) >= 0.0);
}

// The ground's contact with W voxels (Model::terrain): lane bit k set where voxel k touches, and
// its contact in fc[k] (filled for touching lanes only). Flat ground is decided on the lanes
// (physics/floor.hpp), other terrains ask terrain_contact() per lane, only for the voxels low
// enough to reach the ground's highest point.
template <class L>
[[gnu::always_inline]] inline int ground_contacts(const Model& m, const VL<L>& pos,
                                                  FloorContact (&fc)[L::W]) {
  if (m.terrain.kind == TerrainKind::flat) {
    const int bits = floor_contact_lanes<L>(pos);
    for (int k = 0; k < L::W; ++k)
      if (bits >> k & 1) fc[k].penetration = static_cast<float>(0.0 - pos.z[k]);
    return bits;
  }
  int bits = 0;
  for (int k = 0; k < L::W; ++k) {
    if (!(pos.z[k] <= m.terrain.top)) continue;
    fc[k] = terrain_contact(m.terrain, pos.x[k], pos.y[k], pos.z[k]);
    if (fc[k].touches()) bits |= 1 << k;
  }
  return bits;
}

[[gnu::always_inline]] inline double dot(const Vec3& a, const FloorContact& n) {
  return (a.x() * n.nx + a.y() * n.ny) + a.z() * n.nz;
}
// Explicit sums (not Eigen's reductions, whose order can follow its vectorisation, which differs
// between the step translation units).
[[gnu::always_inline]] inline double dot(const Vec3& a, const Vec3& b) {
  return (a.x() * b.x() + a.y() * b.y()) + a.z() * b.z();
}
// The part of `a` in the contact's tangent plane: a - (a . n) n.
[[gnu::always_inline]] inline Vec3 tangential(const Vec3& a, const FloorContact& n) {
  const double an = dot(a, n);
  return Vec3(a.x() - an * n.nx, a.y() - an * n.ny, a.z() - an * n.nz);
}

// §2.8 floorForce(Fsum): normal spring-damper + friction at the start-of-step velocity; may
// clear the static flag. Returns fric (normal + friction). The contact `fc` touches
// (penetration >= 0). A vertical normal takes the reference's axis-aligned formulas (the flat
// floor's bits); any other normal the same formulas in its frame: the spring-damper along n,
// friction in the tangent plane (docs/model.md §2.8a).
inline Vec3 surface_force(const VoxelConst& c, const FloorContact& fc, const Vec3& vel,
                          const Vec3& fsum, std::uint8_t& static_flag) {
  const float pen = fc.penetration;
  const float normal = c.k_pen * pen;  // N = 2 E s pen (float)
  if (fc.vertical) {
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
  const double push = normal - c.c_col * dot(vel, fc);
  Vec3 fric(push * fc.nx, push * fc.ny, push * fc.nz);
  if (static_flag) {
    const Vec3 surface = tangential(fsum + fric, fc);
    const float surface_sq = static_cast<float>(dot(surface, surface));
    const float limit = c.mu_static * normal;
    if (surface_sq > limit * limit) static_flag = 0;
  } else {
    const Vec3 slip = tangential(vel, fc);
    const double sl = std::sqrt(dot(slip, slip));
    if (sl > 0) {
      const float f = c.mu_kinetic * normal;
      fric -= slip * (f / sl);
    }
  }
  return fric;
}

// The push of a vertical face the voxel touches (FloorContact::side_penetration >= 0): the
// spring-damper along the face's horizontal normal, no friction.
inline Vec3 side_push(const VoxelConst& c, const FloorContact& fc, const Vec3& vel) {
  const float normal = c.k_pen * fc.side_penetration;
  const double push = normal - c.c_col * (vel.x() * fc.side_nx + vel.y() * fc.side_ny);
  return Vec3(push * fc.side_nx, push * fc.side_ny, 0.0);
}

// The ground's force on a touching voxel (fc.touches()): the surface it stands on (if it
// penetrates it; else the static flag clears) plus the push of a vertical face, which the
// static-friction test sees as part of the surface force.
inline Vec3 floor_force(const VoxelConst& c, const FloorContact& fc, const Vec3& vel,
                        const Vec3& fsum, std::uint8_t& static_flag) {
  if (!(fc.side_penetration >= 0)) return surface_force(c, fc, vel, fsum, static_flag);
  const Vec3 side = side_push(c, fc, vel);
  if (!(fc.penetration >= 0)) {
    static_flag = 0;
    return side;
  }
  return surface_force(c, fc, vel, fsum + side, static_flag) + side;
}

// The static-friction capture on a surface that is not horizontal: `moved` is the step's
// displacement, `force` the friction (or total) force of the step; a captured voxel loses the
// tangential parts of its momentum and of that displacement (taken off `undo`, the position or
// the displacement itself). The normal motion is kept.
inline void tilted_capture(const VoxelConst& c, const FloorContact& fc, const Vec3& force,
                           const Vec3& moved, Vec3& mom, Vec3& undo, std::uint8_t& sf) {
  const Vec3 step = tangential(moved, fc);
  const Vec3 slide = tangential(mom, fc);
  const double work = dot(tangential(force, fc), step);
  const double hke = 0.5 * c.inv_mass * dot(slide, slide);
  if (hke + work <= 0) sf = 1;
  if (sf) {
    mom -= slide;
    undo -= step;
  }
}

// §2.8 static-friction capture of the fork's part 2 for a voxel in ground contact `fc` at its
// new position: whole-step displacement against the friction force of part 1. A captured voxel
// loses its tangential momentum and its tangential displacement of the step.
inline void fork_static_capture(const VoxelConst& c, const FloorContact& fc, const Vec3& fr,
                                const Vec3& op, Vec3& pos, Vec3& mom, std::uint8_t& sf) {
  if (!(fc.penetration >= 0)) {  // touching a face only
    sf = 0;
    return;
  }
  if (fc.vertical) {
    const double work = fr.x() * (pos.x() - op.x()) + fr.y() * (pos.y() - op.y());
    const double hke = 0.5 * c.inv_mass * (mom.x() * mom.x() + mom.y() * mom.y());
    if (hke + work <= 0) sf = 1;
    if (sf) {
      mom.x() = 0.0;
      mom.y() = 0.0;
      pos.x() = op.x();
      pos.y() = op.y();
    }
    return;
  }
  tilted_capture(c, fc, fr, pos - op, mom, pos, sf);
}

// §2.9 static-friction capture of the symplectic step for a voxel in ground contact `fc` (at the
// start of the step): force f and displacement tr of the step; a captured voxel loses its
// tangential momentum and displacement.
inline void symplectic_static_capture(const VoxelConst& c, const FloorContact& fc, const Vec3& f,
                                      Vec3& mom, Vec3& tr, std::uint8_t& sf) {
  if (!(fc.penetration >= 0)) {  // touching a face only
    sf = 0;
    return;
  }
  if (fc.vertical) {
    const double work = f.x() * tr.x() + f.y() * tr.y();
    const double hke = 0.5 * c.inv_mass * (mom.x() * mom.x() + mom.y() * mom.y());
    if (hke + work <= 0) sf = 1;
    if (sf) {
      mom.x() = mom.y() = 0.0;
      tr.x() = tr.y() = 0.0;
    }
    return;
  }
  tilted_capture(c, fc, f, tr, mom, tr, sf);
}

}  // namespace
}  // namespace softevo::physics
