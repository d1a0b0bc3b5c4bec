// The predicted cost of a genome's work units, for the hand-out order of master/scheduler.hpp
// (longest first). The physics step's work grows with the voxel count, and every evaluation of
// a run simulates the same seconds at nearly the same time step, so the voxel count of the
// developed body predicts a unit's time (docs/scaling.md measures how well). A body that is
// never simulated (no structural voxel, no chamber) costs 0. The prediction only orders the
// hand-out: results are stored by id, so it cannot change a fitness bit.
#pragma once

#include <vector>

#include "common/config.hpp"
#include "evo/genome.hpp"

namespace softevo::master {

// Voxels of `genome`'s developed body (§6), 0 if it is not valid and actuatable.
double predicted_unit_cost(const evo::Genome& genome, const BodyConfig& body);

}  // namespace softevo::master
