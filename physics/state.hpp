// Everything that changes during a simulation, and nothing else. Copyable with `=` (a copy can
// be stepped independently and gives bit-identical results to the original); hashable.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "physics/model.hpp"

namespace softevo::physics {

// One self-collision pair (§2.10): voxel ids a < b.
struct CollisionPair {
  std::int32_t a;
  std::int32_t b;
};

// One 3-vector per link, stored by component (an x, a y and a z array): the link pass reads and
// writes the components of W consecutive links with one vector access each. (The accessors are
// always_inline: the step passes are also compiled for AVX2 / AVX-512, and an out-of-line copy
// emitted there could be linked into the SSE2 code; see quat.hpp.)
struct LinkVec3Columns {
  std::vector<double> x, y, z;

  std::size_t size() const { return x.size(); }
  [[gnu::always_inline]] Vec3 operator[](std::size_t i) const { return {x[i], y[i], z[i]}; }
  [[gnu::always_inline]] void set(std::size_t i, const Vec3& v) {
    x[i] = v.x();
    y[i] = v.y();
    z[i] = v.z();
  }
  void assign(std::size_t n, double value) {
    x.assign(n, value);
    y.assign(n, value);
    z.assign(n, value);
  }
};

// Diagnostics counters (data, never asserts).
struct StepCounters {
  std::uint64_t steps = 0;                   // steps performed (status ok)
  std::uint64_t diverged_steps = 0;          // steps refused because a link strain > 100 (§2.12)
  std::uint64_t non_finite_steps = 0;        // steps that produced a NaN/inf
  std::uint64_t collision_rebuilds = 0;      // self-collision pair list rebuilds (§2.10)
  std::uint64_t collision_pair_growths = 0;  // pair list outgrew its reserved capacity
};

struct State {
  double time = 0.0;  // simulated time [s] (double += float dt, as the reference)
  // Voxel dt of the last integration (Voxelyze previousDt, float); 0 before the first step.
  // Link damping multiplier = damp_base / previous_dt (§2.5).
  float previous_dt = 0.0f;  // [s]

  // ---- voxels (index = voxel id) -------------------------------------------------------------
  std::vector<Vec3> pos;                      // centre position, global frame [m] (voxels)
  std::vector<Vec3> lin_mom;                  // linear momentum [kg m/s] (voxels)
  std::vector<Quat> orient;                   // orientation (w,x,y,z), never renormalised (voxels)
  std::vector<Vec3> ang_mom;                  // angular momentum [kg m^2/s] (voxels)
  std::vector<std::uint8_t> static_friction;  // §2.8 floor static-friction flag (voxels)

  // ---- links (index = link id): history used by damping (§2.5) and hysteresis (§2.3) -------
  LinkVec3Columns link_pos2;       // P relative to N in the link frame, minus rest length [m]
  LinkVec3Columns link_angle1v;    // rotation vector of end N in the link frame [rad]
  LinkVec3Columns link_angle2v;    // rotation vector of end P in the link frame [rad]
  std::vector<float> link_strain;  // axial strain of the most recent link update [-]
  std::vector<std::uint8_t> link_small_angle;  // §2.3 small-angle mode flag (initially 1)
  std::vector<std::uint8_t> link_vel_valid;    // §2.5 "local velocity valid" (initially 0)

  // ---- self-collision bookkeeping (§2.10) -----------------------------------------------------
  bool collisions_stale = true;  // rebuild the pair list at the next step
  // Position of each voxel at the last pair rebuild (float, as Voxelyze's lastColWatchPosition);
  // only surface voxels are read. [m] (voxels)
  std::vector<std::array<float, 3>> col_watch_pos;
  // Pair slots; the first col_pair_count are the live pairs in creation order (lexicographic
  // (a, b), a < b). The slot count is fixed by initial_state() (so a copied State never
  // allocates when stepped); only a pathological pile-up beyond it grows the slots (counted).
  std::vector<CollisionPair> col_pairs;
  int col_pair_count = 0;

  StepCounters counters;
};

// Initial state of §2.1: pos = s*(i,j,k), identity orientation, zero momenta, static-friction
// flag true, links small-angle with invalid local velocity, collision list stale.
State initial_state(const Model& model);

// 64-bit FNV-1a over the bytes of every field in declaration order (time, previous_dt, each
// array's element count then its elements' bytes, collisions_stale, col pairs, counters). A
// LinkVec3Columns array is hashed as the array of its Vec3 (x, y, z per link).
// Identical states give identical hashes in any process on the same platform.
std::uint64_t state_hash(const State& state);

}  // namespace softevo::physics
