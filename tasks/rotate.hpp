// The rotate task (docs/model.md §7.6; thesis section 5.3.3 proposes in-place rotation as a
// further objective): turn about +z on the spot. One work unit, no controller input.
//
//   F = |Theta| - w d / l
//
// Theta [rad]: heading change about +z over the evaluation, accumulated frame by frame so that
// full turns count; the heading of a frame is the least-squares rotation angle about z of the
// voxels' horizontal offsets from their centroid, against the same offsets in the rest shape
// (2-D Kabsch). d [m]: horizontal centroid travel at the end; l [m]: body length, the larger
// horizontal extent of the rest shape; w [rad / body length]: task.rotate_travel_penalty.
// Either sense of rotation scores. Components: heading_change Theta [rad] (signed,
// counter-clockwise positive), travel d / l [body lengths], travel_penalty w d / l [rad].
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "tasks/task.hpp"

namespace softevo::tasks {

// Unwrapped heading about +z of a set of points: observe() each frame the current positions
// [m] of the same points in the same order as `rest` (z ignored); heading_change() is the sum
// of the frame-to-frame turns, each the signed angle in [-pi, pi] between consecutive headings,
// so a body that turns less than half a turn per frame is tracked through any number of turns.
class HeadingTracker {
 public:
  explicit HeadingTracker(std::span<const Eigen::Vector3d> rest);
  void observe(std::span<const Eigen::Vector3d> positions);
  double heading_change() const { return heading_change_; }  // [rad]

 private:
  std::vector<Eigen::Vector2d> rest_offsets_;  // horizontal offsets from the rest centroid [m]
  bool has_heading_ = false;
  Eigen::Vector2d heading_{1.0, 0.0};  // unit vector (cos, sin) of the last heading
  double heading_change_ = 0.0;
};

struct RotateScore {
  double heading_change = 0.0;  // Theta [rad]
  double travel = 0.0;          // d / l [body lengths]
  double travel_penalty = 0.0;  // w d / l [rad]
  double fitness = 0.0;         // |Theta| - w d / l [rad]
};
// heading_change [rad], travel [m], body_length [m] (> 0), travel_penalty_weight w
// [rad / body length].
RotateScore rotate_score(double heading_change, double travel, double body_length,
                         double travel_penalty_weight);

std::unique_ptr<Task> make_rotate_task(const Config& config);

}  // namespace softevo::tasks
