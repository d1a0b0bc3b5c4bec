// The small synthetic robot body of the worker tests: a 7x4x4 block of material 10 with two
// 2x2x2 chambers (cells 11 and 12) one behind the other along x.
#pragma once

#include "common/body_plan.hpp"

namespace softevo::test {

inline BodyPlan two_chamber_block() {
  BodyPlan plan;
  plan.lattice = {7, 4, 4};
  plan.voxel_size = 0.01;
  for (int k = 1; k <= 10; ++k) plan.materials.push_back({1.0e4 * k, 1000.0});
  plan.cells.assign(7 * 4 * 4, 10);
  for (int y = 1; y <= 2; ++y)
    for (int z = 1; z <= 2; ++z) {
      plan.cells[plan.cell_index(1, y, z)] = 11;
      plan.cells[plan.cell_index(2, y, z)] = 11;
      plan.cells[plan.cell_index(4, y, z)] = 12;
      plan.cells[plan.cell_index(5, y, z)] = 12;
    }
  return plan;
}

}  // namespace softevo::test
