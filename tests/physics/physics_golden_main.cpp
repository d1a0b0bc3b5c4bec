// Helper for test_physics_determinism: prints the golden-scene hashes of both integrators, so
// the test can compare results computed in separate processes.
#include <cinttypes>
#include <cstdio>

#include "tests/physics/golden_scene.hpp"

int main() {
  using softevo::physics::golden::Motion;
  for (const char* integrator : {"pneuvox", "symplectic"})
    std::printf("%s %016" PRIx64 "\n", integrator, softevo::physics::golden::run_scene(integrator));
  for (const char* integrator : {"pneuvox", "symplectic"})
    std::printf("%s tumbling %016" PRIx64 "\n", integrator,
                softevo::physics::golden::run_scene(integrator, softevo::physics::Simd::best,
                                                    Motion::tumbling));
  return 0;
}
