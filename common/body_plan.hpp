// A developed robot body: what evo/ produces and physics/ builds a Model from (plain data).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace softevo {

// Cell values of a body plan (docs/model.md §10).
inline constexpr int kEmptyCell = 0;
inline constexpr int kFirstChamberCell = 11;  // 11..20 = chamber q = value - 11 (controller order)

struct StructuralMaterial {
  double youngs_modulus = 0.0;  // [Pa]
  double density = 0.0;         // [kg/m^3]
};

struct BodyPlan {
  std::array<int, 3> lattice{0, 0, 0};  // cells along x (forward), y (left), z (up)
  // X*Y*Z cell values, index = (x*Y + y)*Z + z: 0 empty, 1..K structural material k,
  // 11.. chamber q = value - 11.
  std::vector<int> cells;
  // materials[k-1] = structural material k.
  std::vector<StructuralMaterial> materials;
  double voxel_size = 0.01;  // [m]

  std::size_t cell_index(int x, int y, int z) const {
    return (static_cast<std::size_t>(x) * lattice[1] + y) * lattice[2] + z;
  }
  int cell(int x, int y, int z) const { return cells[cell_index(x, y, z)]; }
  static bool is_structural(int value) { return value > 0 && value < kFirstChamberCell; }
  static bool is_chamber(int value) { return value >= kFirstChamberCell; }
  // Number of chambers = highest chamber id present - 10 (ids are dense from 11).
  int chamber_count() const {
    int highest = 0;
    for (int v : cells) highest = v >= kFirstChamberCell ? std::max(highest, v - 10) : highest;
    return highest;
  }
};

}  // namespace softevo
