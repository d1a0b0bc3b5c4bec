// A robot as it is drawn and moved, in plain types: its cells (Body) and where they are at one
// instant (Pose). motion/ makes them from robot files, traces and archives; render/ and view/
// draw them. Below all three (docs/architecture.md §1), so motion/ does not depend on the
// renderer for its data types.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/body_plan.hpp"

namespace softevo::scene {

// What is drawn of a robot: its cells, independent of where they are.
struct Body {
  double voxel_size = 0.01;  // [m]
  int material_count = 10;   // structural materials 1..material_count (colour scale)
  // Structural voxels in simulator order (x outer, y, z inner; docs/model.md §2.1).
  std::vector<Eigen::Vector3i> voxel_cells;
  std::vector<int> voxel_material;  // 1..material_count (voxels)
  // Chamber cells (no voxel in the simulation) and their chamber index q = value - 11.
  std::vector<Eigen::Vector3i> chamber_cells;
  std::vector<int> chamber_index;  // (chamber cells)
  int chamber_count = 0;
};
// Throws std::invalid_argument when the plan has no structural voxel or a cell out of range.
Body body_from_plan(const BodyPlan& plan, int material_count = 10);

// Where the voxels are at one instant.
struct Pose {
  double time = 0.0;                            // [s]
  std::vector<Eigen::Vector3d> position;        // [m] voxel centres (voxels)
  std::vector<Eigen::Quaterniond> orientation;  // unit quaternions (voxels)
  std::vector<double> chamber_pressure;         // [Pa] absolute (chambers); may be empty
};
// The lattice at rest: centre = s * (i, j, k), identity orientation (docs/model.md §2.1).
Pose rest_pose(const Body& body);
// Mean voxel position [m] (the centroid of §5, but absolute rather than a displacement).
Eigen::Vector3d centroid(const Pose& pose);

}  // namespace softevo::scene
