// Self-collision (§2.10) of one step: the pair list and the pair forces. Internal to physics/:
// called by step() (physics/step.cpp).
#pragma once

#include "physics/model.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"

namespace softevo::physics {

// §2.10 pair rebuild: every pair of surface voxels within the watch radius that is not within 5
// link hops, in the reference's order (State::col_pairs), and the watch positions; clears
// State::collisions_stale.
void rebuild_collision_pairs(const Model& m, State& st, Scratch& sc);

// §2.10: staleness check, rebuild if stale, pair forces -> Scratch::collision_force (collisionF
// of §2.7).
void update_collisions(const Model& m, State& st, Scratch& sc);

}  // namespace softevo::physics
