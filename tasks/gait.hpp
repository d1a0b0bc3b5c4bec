// The gait task (docs/model.md §7.1): walk along +x. One work unit, no controller input;
// fitness F = 100 x (mean x displacement of the voxels [m]), in cm. Component: distance [cm].
#pragma once

#include <memory>

#include <Eigen/Core>

#include "tasks/task.hpp"

namespace softevo::tasks {

// §7.1: F [cm] from the centroid displacement [m].
double gait_fitness(const Eigen::Vector3d& centroid_displacement);

std::unique_ptr<Task> make_gait_task(const Config& config);

}  // namespace softevo::tasks
