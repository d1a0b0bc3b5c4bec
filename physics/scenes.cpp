#include "physics/scenes.hpp"

namespace softevo::physics {

BodyPlan solid_block(int x, int y, int z, double e, double rho, double s) {
  BodyPlan plan;
  plan.lattice = {x, y, z};
  plan.cells.assign(static_cast<std::size_t>(x) * y * z, 1);
  plan.materials = {StructuralMaterial{e, rho}};
  plan.voxel_size = s;
  return plan;
}

}  // namespace softevo::physics
