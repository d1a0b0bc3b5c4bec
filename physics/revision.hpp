// The physics revision: which numbers a simulation gives. A physics change that alters fitness
// bits (not just speed) bumps it. Archives record the revision they were simulated with
// (attribute `physics_revision`); `softevo-mpi --resume` refuses to continue a run of another
// revision and `softevo replay --verify` refuses to compare bits across revisions, each with a
// message naming both, instead of mixing or reporting false mismatches.
//
// History:
//   1  the reference's formulas with glibc acos / sin / cos (archives without the attribute).
//   2  acos / sin / cos of physics/reproducible_math.hpp (within 1 ulp of glibc, computed on SIMD
//      lanes), and the large-angle link frame (q1 and rotvec(q1), §2.11) in closed form by
//      half-angle identities (physics/lane_math.hpp frame_to_pos_x_lanes). The same formulas up to
//      rounding: fitness values differ in their last bits and, through the chaotic gaits, by a
//      few percent (issue 4 note).
//   3  the same functions evaluated with fewer dependent operations (issue 4 speed): polynomials by
//      Estrin's scheme instead of Horner's, quat_from_rotvec's sin / cos from the squared half
//      angle (no square root, range reduction or division), rotvec's acos branch with one
//      division instead of three. Still within 1 ulp of glibc per function; fitness values move
//      as between revisions 1 and 2.
#pragma once

namespace softevo::physics {

inline constexpr int kPhysicsRevision = 3;

}  // namespace softevo::physics
