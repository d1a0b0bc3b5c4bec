// The passes of one physics time step (§2.3-2.13), written once over a SIMD lane width, and the
// table a translation unit exports. Internal to physics/: included only by the step_<ISA>.cpp
// translation units, each of which supplies its lane traits L and is compiled for its own
// instruction set (step_scalar.cpp: any CPU, W = 1; step_sse2.cpp: W = 2; step_neon.cpp: AArch64,
// W = 2; step_avx2.cpp / step_avx512.cpp: W = 4). Everything here has internal linkage
// (anonymous namespace), so the copies built with different instruction sets never meet in the
// linker; the only thing a translation unit exports is its StepKernels table (checked by the
// PhysicsIsa ctest).
//
// Precision: state is double; constants are float (Model); products the reference forms in float
// (dt * (1/m), k_pen * pen, mu * N, strain, stress * A, collision forces) are formed in float
// here too, and a float times a double is promoted exactly as in the reference. The build uses
// -ffp-contract=off, so the written operation order is the executed one.
//
// Lanes: links (small-angle and large-angle mode in separate groups) and free voxels go through
// the passes W at a time, one link or voxel per lane of a W x double vector. Each formula is
// written once, over the lanes, and the exceptions to a group (a link switching mode, the last
// voxels of a pass) run it one lane wide (LanesScalar), which is the reference's scalar IEEE
// arithmetic. Every lane performs those operations in the same order (the quaternion formulas are
// the shared templates of quat.hpp; float roundings are a float conversion of the same double;
// float x float products and float / float quotients are formed in double and rounded to float,
// which gives the float result exactly since 53 >= 2 x 24 + 2), so every width gives the same
// bits. The acos / sin / cos branches of rotvec, frame_to_pos_x and quat_from_rotvec run on the
// lanes too (physics/lane_math.hpp: the scalar functions' bits); rare branches (floor contact)
// run per lane in the scalar code.
//
// The rooms: lane utilities (lanes.hpp) and lane math (lane_math.hpp); the link pass
// (link_lanes.hpp); the voxel passes (voxel_pass.hpp) with the floor contact (floor_contact.hpp,
// floor.hpp); the chamber meshes (mesh_lanes.hpp).
#pragma once

#include "physics/batch_kernels.hpp"
#include "physics/link_lanes.hpp"
#include "physics/mesh_lanes.hpp"
#include "physics/step_kernels_table.hpp"
#include "physics/voxel_pass.hpp"

namespace softevo::physics {
namespace {

// The exported table of this translation unit's passes: L for one robot (lanes = links or
// voxels), LB for the batched step (lanes = evaluations; physics/batch_kernels.hpp).
template <class L, class LB = L>
constexpr StepKernels make_step_kernels(Simd simd) {
  return StepKernels{simd,
                     L::W,
                     &link_pass_forces<L, LinkPass::forces_and_state>,
                     &link_pass_forces<L, LinkPass::forces>,
                     &link_pass_state<L, LinkPass::restore_state>,
                     &fork_voxel_passes<L>,
                     &symplectic_voxel_pass<L>,
                     &chamber_volume_lanes<L>,
                     &pressure_forces_lanes<L>,
                     {LB::W, &batch_link_pass<LB, LinkPass::forces>, &batch_voxel_passes<LB>},
                     {L::W, &batch_link_pass<L, LinkPass::forces>, &batch_voxel_passes<L>}};
}

}  // namespace
}  // namespace softevo::physics
