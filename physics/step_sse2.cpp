// The 2-lane step passes of physics/step_kernels.hpp on x86-64 (SSE2, every x86-64 CPU). Same
// results as every other width, bit for bit.
#include "physics/lanes_sse2.hpp"
#include "physics/step_kernels.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

const StepKernels& step_kernels_sse2() {
  static constexpr StepKernels kernels = make_step_kernels<LanesSse2>(Simd::sse2);
  return kernels;
}

}  // namespace softevo::physics
