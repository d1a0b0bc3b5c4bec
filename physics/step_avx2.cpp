// The step passes of physics/step_kernels.hpp with 4 lanes (AVX2 build of this file only; picked
// at run time by step() when the CPU has AVX2). Same results as the SSE2 passes, bit for bit.
#include "physics/lanes_avx2.hpp"
#include "physics/step_kernels.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

const StepKernels& step_kernels_avx2() {
  static constexpr StepKernels kernels = make_step_kernels<LanesAvx2>(Simd::avx2);
  return kernels;
}

}  // namespace softevo::physics
