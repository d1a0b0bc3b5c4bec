// The step passes of physics/step_kernels.hpp one lane wide, with no instruction-set extension:
// they run on any CPU, and are the only passes of a build for an architecture without wider lane
// traits. Same results as every other width, bit for bit.
#include "physics/lanes_scalar.hpp"
#include "physics/step_kernels.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

const StepKernels& step_kernels_scalar() {
  static constexpr StepKernels kernels = make_step_kernels<LanesScalar>(Simd::scalar);
  return kernels;
}

}  // namespace softevo::physics
