#include "scene/scene.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace softevo::scene {

Body body_from_plan(const BodyPlan& plan, int material_count) {
  const auto& d = plan.lattice;
  if (d[0] <= 0 || d[1] <= 0 || d[2] <= 0 ||
      plan.cells.size() != static_cast<std::size_t>(d[0]) * d[1] * d[2]) {
    throw std::invalid_argument("body plan: lattice and cell count do not match");
  }
  Body body;
  body.voxel_size = plan.voxel_size;
  body.material_count = std::max(material_count, static_cast<int>(plan.materials.size()));
  // Simulator order: x outer, y middle, z inner (§2.1), which is also the cell index order.
  for (int x = 0; x < d[0]; ++x) {
    for (int y = 0; y < d[1]; ++y) {
      for (int z = 0; z < d[2]; ++z) {
        const int value = plan.cell(x, y, z);
        if (BodyPlan::is_structural(value)) {
          body.voxel_cells.emplace_back(x, y, z);
          body.voxel_material.push_back(value);
        } else if (BodyPlan::is_chamber(value)) {
          body.chamber_cells.emplace_back(x, y, z);
          body.chamber_index.push_back(value - kFirstChamberCell);
          body.chamber_count = std::max(body.chamber_count, value - kFirstChamberCell + 1);
        } else if (value != kEmptyCell) {
          throw std::invalid_argument("body plan: cell value " + std::to_string(value) +
                                      " is neither empty, material nor chamber");
        }
      }
    }
  }
  if (body.voxel_cells.empty()) throw std::invalid_argument("body plan has no structural voxel");
  return body;
}

Pose rest_pose(const Body& body) {
  Pose pose;
  pose.position.reserve(body.voxel_cells.size());
  for (const auto& c : body.voxel_cells)
    pose.position.push_back(c.cast<double>() * body.voxel_size);
  pose.orientation.assign(body.voxel_cells.size(), Eigen::Quaterniond::Identity());
  return pose;
}

Eigen::Vector3d centroid(const Pose& pose) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& p : pose.position) sum += p;
  return pose.position.empty() ? sum : Eigen::Vector3d(sum / pose.position.size());
}

}  // namespace softevo::scene
