// Small named body plans used by validation tests and `softevo bench physics`.
#pragma once

#include "common/body_plan.hpp"

namespace softevo::physics {

// A solid X x Y x Z block of one structural material (cell value 1) with Young's modulus `e`
// [Pa], density `rho` [kg/m^3] and voxel edge `s` [m].
BodyPlan solid_block(int x, int y, int z, double e, double rho = 1000.0, double s = 0.01);

}  // namespace softevo::physics
