// The directed task (docs/model.md §7.2-§7.4): walk towards each target direction of
// task.directions [deg], one work unit per direction, the fitnesses summed in direction order
// (§7.4). The controller gets one input, the direction sensor (§7.3). Components per unit:
// direction_deg [deg], distance D [cm], path_length L [cm], angle_error delta [rad] and
// perpendicular_penalty P [cm] (already x omega = task.path_penalty_weight).
#pragma once

#include <memory>
#include <span>

#include <Eigen/Core>

#include "tasks/task.hpp"

namespace softevo::tasks {

using Vec3d = Eigen::Vector3d;

// Unit target vector (cos beta, sin beta, 0), beta [deg] counter-clockwise (towards +y).
Vec3d target_direction(double direction_deg);

// §7.3: direction sensor input theta_dir [rad] in [-pi, pi], positive = target to the left.
// centroid: current centroid displacement [m]; heading: mean rotvec z [rad]; voxel_size [m]
// (the target point is 20 voxel lengths ahead of the centroid's projection on the target line).
// acos arguments are clamped to [-1, 1] (the reference does not clamp and aborts on the NaN,
// §7.3; clamping changes nothing else).
float direction_sensor(const Vec3d& centroid, double heading, double direction_deg,
                       double voxel_size);

// §7.2 for one direction from the waypoints w_0..w_10 [cm] (z ignored).
struct DirectedScore {
  double distance = 0.0;               // D [cm], signed distance along the target line
  double path_length = 0.0;            // L [cm]
  double angle_error = 0.0;            // delta [rad]
  double perpendicular_penalty = 0.0;  // P (already x omega) [cm]
  double fitness = 0.0;                // F = |D|/(L + 1e-5) (D/(delta + 1) - P)
};
DirectedScore directed_score(std::span<const Vec3d> waypoints_cm, double direction_deg,
                             double path_penalty_weight);

std::unique_ptr<Task> make_directed_task(const Config& config);

}  // namespace softevo::tasks
