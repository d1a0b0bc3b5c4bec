// Random 3-vectors for the physics tests, drawn in a fixed order.
#pragma once

#include "physics/quat.hpp"

namespace softevo::physics::test {

// (draw(), draw(), draw()) drawn x first, then y, then z. Written as
// Vec3(draw(), draw(), draw()) the order would be the compiler's: function arguments are evaluated
// in an unspecified order (GCC 12 goes right to left, clang 14 left to right), so a test scene
// would differ between compilers.
template <class Draw>
Vec3 random_vec3(Draw&& draw) {
  const double x = draw();
  const double y = draw();
  const double z = draw();
  return {x, y, z};
}

}  // namespace softevo::physics::test
