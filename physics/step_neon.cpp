// The 2-lane step passes of physics/step_kernels.hpp on AArch64 (NEON, every AArch64 CPU). Same
// results as every other width and as the x86-64 builds, bit for bit.
#include "physics/lanes_neon.hpp"
#include "physics/step_kernels.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

const StepKernels& step_kernels_neon() {
  static constexpr StepKernels kernels = make_step_kernels<LanesNeon>(Simd::neon);
  return kernels;
}

}  // namespace softevo::physics
