#include "scene/cells.hpp"

namespace softevo::scene {

CellIndex::CellIndex(const Body& body) {
  Eigen::Vector3i hi(0, 0, 0);
  for (const auto& c : body.voxel_cells) hi = hi.cwiseMax(c);
  for (const auto& c : body.chamber_cells) hi = hi.cwiseMax(c);
  dims_ = hi + Eigen::Vector3i::Ones();
  items_.assign(static_cast<std::size_t>(dims_.prod()), -1);
  const int v = static_cast<int>(body.voxel_cells.size());
  for (int i = 0; i < v; ++i) items_[index(body.voxel_cells[i])] = i;
  for (int j = 0; j < static_cast<int>(body.chamber_cells.size()); ++j) {
    items_[index(body.chamber_cells[j])] = v + j;
  }
}

}  // namespace softevo::scene
