// The per-instruction-set tables of the step passes (internal to physics/). Each step_*.cpp
// translation unit builds the passes of physics/step_kernels.hpp for its own lane width and
// exports only its table; step() picks the table of Model::simd.
#pragma once

#include <span>

#include "physics/batch.hpp"
#include "physics/model.hpp"
#include "physics/pneumatics.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"

namespace softevo::physics {

struct StepKernels {
  Simd simd;
  int lanes;  // links / voxels per SIMD group
  // §2.3-2.6 link pass with forces and the new link state; true if some strain > 100
  bool (*link_pass_forces)(const Model&, State&, Scratch&);
  // the same without storing pos2, angles and strain (pneuvox: its mid-step pass stores them)
  bool (*link_pass_forces_only)(const Model&, State&, Scratch&);
  // after link_pass_forces_only reported a strain > 100: stores what it left out
  void (*link_pass_restore_state)(const Model&, State&, Scratch&);
  // §2.12 steps 3-9 (pneuvox); false if the state became non-finite
  bool (*fork_voxel_passes)(const Model&, State&, Scratch&, std::span<const Vec3>);
  // §2.9 (symplectic); false if the state became non-finite
  bool (*symplectic_voxel_pass)(const Model&, State&, Scratch&, std::span<const Vec3>);
  // §3.2 volume of one chamber (= chamber_volume) [m^3]
  float (*chamber_volume)(const PneumaticsModel&, int chamber, std::span<const Vec3> positions);
  // §3.4 pressure force shares of one chamber's triangles at gauge pressure [bar]
  // (PneumaticsScratch::triangle_force)
  void (*pressure_forces)(const PneumaticsModel&, int chamber, float gauge,
                          std::span<const Vec3> positions, PneumaticsScratch&);
  // The batched step (physics/batch.hpp) at two lane widths, the widest of this instruction set
  // and the one-robot passes' (equal except at avx512: 8 and 4): evaluations per vector, the
  // pneuvox step's first link pass (forces only; the lanes with a strain > 100 as bits) and its
  // voxel passes with the mid-step link pass (§2.12 steps 3-9; the non-finite lanes as bits).
  struct Batch {
    int lanes;
    int (*forces_pass)(const Model&, BatchState&, BatchScratch&);
    int (*voxel_passes)(const Model&, BatchState&, BatchScratch&);
  };
  Batch batch_wide;
  Batch batch_narrow;
};

// The table of a width (`best` resolved to the widest this CPU runs; a width this build does not
// contain gives the scalar table, but Model and PneumaticsModel only ever hold supported widths).
const StepKernels& step_kernels(Simd simd);

// One per step_<ISA>.cpp of this build (physics/CMakeLists.txt).
const StepKernels& step_kernels_scalar();
#if defined(SOFTEVO_HAVE_SSE2_KERNELS)
const StepKernels& step_kernels_sse2();
#endif
#if defined(SOFTEVO_HAVE_AVX2_KERNELS)
const StepKernels& step_kernels_avx2();
#endif
#if defined(SOFTEVO_HAVE_AVX512_KERNELS)
const StepKernels& step_kernels_avx512();
#endif
#if defined(SOFTEVO_HAVE_NEON_KERNELS)
const StepKernels& step_kernels_neon();
#endif

}  // namespace softevo::physics
