// One physics time step: step(model, state, scratch, external_force).
//
// Integrator (Model::integrator, from physics.integrator):
//  - pneuvox:    the thesis fork's two-part step of docs/model.md §2.12-2.13, exactly: link
//                pass, collisions, CoG + L_A, part 1 (link + external forces, doubled position
//                term), mid-step link pass, L_B, angular-momentum correction, part 2 (gravity,
//                collision, floor; static-friction capture of §2.8).
//  - symplectic: upstream Voxelyze single-pass symplectic Euler (§2.9) with the same forces.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "common/choice.hpp"
#include "physics/model.hpp"
#include "physics/state.hpp"

namespace softevo::physics {

enum class StepStatus : std::uint8_t {
  ok = 0,
  diverged = 1,    // some link strain > 100: voxels not advanced (§2.12 step 1)
  non_finite = 2,  // a NaN/inf appeared in the state (the reference would abort, §2.6/§2.15)
};

}  // namespace softevo::physics
template <>
struct softevo::ChoiceNames<softevo::physics::StepStatus> {
  static constexpr std::array<const char*, 3> names = {"ok", "diverged", "non_finite"};
};
namespace softevo::physics {

// Per-step buffers derived from State each step; allocated once by make_scratch(), never
// reallocated by step() (except the documented pair-capacity growth, see State::col_pairs).
struct Scratch {
  // link pass output: force/moment on each link end in that end voxel's local frame (§2.6),
  // index = 2 * link + end (0 = N, 1 = P), i.e. exactly a Model::voxel_load_slots entry, so the
  // voxel pass gathers its loads without a branch.
  struct EndLoad {
    Vec3 force;   // [N]
    Vec3 moment;  // [N m]
  };
  // Entry Model::missing_load_slot() = 2 x links is always zero: the end load of a missing link.
  std::vector<EndLoad> link_end_load;  // (2 x links + 1)
  // link ids of the link pass's mixed groups, collected per mode (links)
  std::vector<int> link_list_small;
  std::vector<int> link_list_large;
  // §2.5 link damping multiplier c_V = damp_base_V / previous_dt (a float, held as a double) of
  // each link's end voxels N and P, refreshed at the start of a force link pass when previous_dt
  // changed (instead of two divisions per link and step); per link, so that a group of
  // consecutive links loads them as vectors.
  std::vector<double> link_damping_neg;  // c_N [sqrt(kg)/s] (links)
  std::vector<double> link_damping_pos;  // c_P [sqrt(kg)/s] (links)
  // previous_dt that link_damping_neg / _pos were computed for (NaN: not yet); the division is
  // redone only when State::previous_dt changes (in practice once, after the first step)
  float link_damping_dt = std::numeric_limits<float>::quiet_NaN();  // [s]
  // voxel pass (pneuvox part 1 -> part 2 carry-over, §2.1 "fork-only per-voxel scratch")
  std::vector<Vec3> collision_force;  // collisionF [N] (voxels)
  // every collision_force entry is +0: update_collisions then skips refilling it (most steps have
  // no touching pair, and the refill was a third of the collision time of a champion)
  bool collision_force_zero = true;
  std::vector<Vec3> part2_force;  // gravityF + collisionF + fric [N] (voxels)
  std::vector<Vec3> fric;         // floor normal + friction force [N] (voxels)
  std::vector<Vec3> old_pos;      // position at the start of the step [m] (voxels)
  // Broadphase grid of a rebuild: the surface voxels with their grid cell and a copy of their
  // position, in slot order (grid_entries) and sorted by hash bucket of the cell (grid_sorted,
  // counting sort; within a bucket by cell, then ascending slot), so that the surface voxels of
  // one cell are one contiguous run.
  struct GridEntry {
    double x, y, z;  // position [m]
    int slot;        // index into Model::surface_voxels
    int cx, cy, cz;  // grid cell
  };
  std::vector<GridEntry> grid_entries;  // (surface voxels)
  std::vector<GridEntry> grid_sorted;   // (surface voxels)
  // bucket b = grid_sorted[begin[b] .. begin[b + 1]) (buckets + 1)
  std::vector<int> grid_bucket_begin;
  std::vector<int> candidates;  // grid_sorted indices within the radius (surface voxels)
};

Scratch make_scratch(const Model& model);

// Advance `state` by one time step model.dt. external_force[v] is the force applied to voxel v
// [N], global frame (e.g. pneumatic pressure forces, set by the caller before every step); it is
// rounded to float as the reference's External stores it. An empty span means no external force;
// otherwise its size must equal model.voxel_count (else std::invalid_argument).
StepStatus step(const Model& model, State& state, Scratch& scratch,
                std::span<const Vec3> external_force = {});

}  // namespace softevo::physics
