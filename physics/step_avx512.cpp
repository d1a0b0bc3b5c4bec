// The 4-lane step passes of physics/step_kernels.hpp built with AVX-512VL (this file only): the
// same 256-bit operations as step_avx2.cpp, but the compiler has 32 vector registers instead of
// 16, which removes spills from the long link formulas. Picked at run time by step() when the
// CPU has AVX-512F and AVX-512VL. Same results as the other widths, bit for bit. The batched
// step's passes (lanes = evaluations of one body) are 8 lanes wide here (lanes_avx512.hpp).
#if !defined(__AVX512VL__)
#error "step_avx512.cpp must be compiled with -mavx512vl (see physics/CMakeLists.txt)"
#endif
#include "physics/lanes_avx2.hpp"
#include "physics/lanes_avx512.hpp"
#include "physics/step_kernels.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

const StepKernels& step_kernels_avx512() {
  static constexpr StepKernels kernels = make_step_kernels<LanesAvx2, LanesAvx512>(Simd::avx512);
  return kernels;
}

}  // namespace softevo::physics
