// Fitness of one evaluation (pneuvox-model.md §7): gait (§7.1), directed locomotion towards one
// target direction (§7.2) with its direction sensor (§7.3), and the five-direction sum (§7.4).
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/eval_types.hpp"

namespace softevo::worker {

using Vec3d = Eigen::Vector3d;

// §7.1: F = 100 x mean x displacement [cm]; `centroid_displacement` in [m].
double gait_fitness(const Vec3d& centroid_displacement);

// Unit target vector (cos beta, sin beta, 0), beta [deg] counter-clockwise (towards +y).
Vec3d target_direction(double direction_deg);

// §7.3: direction sensor input theta_dir [rad] in [-pi, pi], positive = target to the left.
// centroid: current centroid displacement [m]; heading: mean rotvec z [rad]; voxel_size [m]
// (the target point is 20 voxel lengths ahead of the centroid's projection on the target line).
// acos arguments are clamped to [-1, 1] (the reference does not clamp and aborts on the NaN,
// §11 item 10; clamping changes nothing else).
float direction_sensor(const Vec3d& centroid, double heading, double direction_deg,
                       double voxel_size);

// §7.2 for one direction from the 11 waypoints w_0..w_10 [cm] (z ignored): D, L, delta, P and
// F = |D|/(L + 1e-5) (D/(delta + 1) - P), omega = path_penalty_weight.
DirectionComponents directed_components(std::span<const Vec3d> waypoints_cm, double direction_deg,
                                        double path_penalty_weight);

// §7.4: sum of the per-direction fitnesses; any direction not ok -> fitness 0 and the status of
// the first such direction. Components are kept as they are.
EvalResult combine_directions(std::span<const EvalResult> per_direction);

}  // namespace softevo::worker
