// Lattice lookups shared by everything that walks a body's faces: the renderer's skin and chamber
// faces (render/) and the fabrication meshes (fabricate/), so both see one face extraction.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "scene/scene.hpp"

namespace softevo::scene {

// Face directions in the link order of docs/model.md §2.1: X+, X-, Y+, Y-, Z+, Z-.
inline const std::array<Eigen::Vector3i, 6> kFaceSteps = {
    Eigen::Vector3i(1, 0, 0),  Eigen::Vector3i(-1, 0, 0), Eigen::Vector3i(0, 1, 0),
    Eigen::Vector3i(0, -1, 0), Eigen::Vector3i(0, 0, 1),  Eigen::Vector3i(0, 0, -1)};

// Lattice lookup of a body: which item sits in a cell. Items 0..V-1 are structural voxels,
// V..V+C-1 chamber cells; -1 = empty (or outside the lattice).
class CellIndex {
 public:
  explicit CellIndex(const Body& body);
  int at(const Eigen::Vector3i& c) const {
    if ((c.array() < 0).any() || (c.array() >= dims_.array()).any()) return -1;
    return items_[index(c)];
  }
  // Cells along x, y, z: one past the highest occupied index on each axis.
  const Eigen::Vector3i& dims() const { return dims_; }

 private:
  std::size_t index(const Eigen::Vector3i& c) const {
    return (static_cast<std::size_t>(c.x()) * dims_.y() + c.y()) * dims_.z() + c.z();
  }
  Eigen::Vector3i dims_;
  std::vector<int> items_;
};

}  // namespace softevo::scene
