// Read-only quantities derived from a Model + State: kill rules (§2.15), centroid and heading
// (§5), momentum and energy for tests and telemetry. Positions and orientations for rendering
// are State::pos and State::orient directly.
#pragma once

#include "physics/model.hpp"
#include "physics/state.hpp"

namespace softevo::physics {

// Max over links of the axial strain stored by the most recent link update (in the pneuvox
// integrator: the mid-step update of the last step, §2.9 item 6). 0 without links.
double max_link_strain(const Model& model, const State& state);

// §2.15 exploded(): max_link_strain > 2.
bool exploded(const Model& model, const State& state);

// Mean over non-fixed voxels of rotvec(orient) [rad] (§2.15; heading = .z(), §5).
Vec3 mean_rotation_vector(const Model& model, const State& state);

// §2.15 flipped(): mean rotation vector .x or .y beyond +-3.14159/3.
bool flipped(const Model& model, const State& state);

// §5 "centerOfGravity": mean over non-fixed voxels of pos - s*(i,j,k) [m] (0 at the start).
Vec3 centroid_displacement(const Model& model, const State& state);

// Mean position of the non-fixed voxels [m].
Vec3 centre_of_mass(const Model& model, const State& state);

// Sum of linear momenta of non-fixed voxels [kg m/s].
Vec3 total_linear_momentum(const Model& model, const State& state);

// Sum over non-fixed voxels of (pos - about) x lin_mom + ang_mom [kg m^2/s].
Vec3 total_angular_momentum(const Model& model, const State& state, const Vec3& about);

// Translational + rotational kinetic energy, sum p^2/2m + L^2/2I [J].
double kinetic_energy(const Model& model, const State& state);

// Beam strain energy of all links from the stored link state, 1/2 q^T K q of §2.4 [J].
double elastic_energy(const Model& model, const State& state);

// Gravitational potential energy sum m g z (z = 0 at the floor) [J].
double gravity_energy(const Model& model, const State& state, double gravity);

}  // namespace softevo::physics
