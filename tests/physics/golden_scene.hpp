// The fixed scenes of the golden-hash determinism test, shared by the test and by the helper
// executable that recomputes them in a separate process.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/rng.hpp"
#include "physics/model.hpp"
#include "physics/scenes.hpp"
#include "physics/step.hpp"
#include "tests/physics/random_vec3.hpp"

namespace softevo::physics::golden {

inline constexpr int kSteps = 1500;

// How hard the scene is shaken. `gentle`: links bend by less than a degree, so frame_to_pos_x and
// rotvec take the Taylor branches of §2.11; voxels turn slowly, yet many by more than the 2.7e-4
// rad per step below which quat_from_rotvec takes its Taylor branch. `tumbling`: 1000x the initial
// spin and 10x the external force, so links bend far (frame_to_pos_x and rotvec take their acos /
// sin / cos branches) and voxels turn fast (quat_from_rotvec takes its sin / cos branch).
enum class Motion { gentle, tumbling };

// A 5x4x3 body of two materials (30 kPa / 100 kPa checkerboard) with a hole, lifted 0.3 s,
// random initial momenta (Rng seed 2024) and a time-varying external force on four voxels:
// exercises links in both angle modes, damping, floor contact, friction and self-collision.
// `simd` picks the width of the step passes (results must not depend on it).
// `diverge` adds a last step that diverges (one voxel moved 2 m away, a strain of about 200): the
// state after a refused step keeps the link state of its link pass (§2.12 step 1).
// `terrain`: the ground (flat by default), with the body moved `shift_x` [m] along +x at the
// start (a terrain lays its features out in front of the body's lattice).
inline std::uint64_t run_scene(const std::string& integrator, Simd simd = Simd::best,
                               Motion motion = Motion::gentle, bool diverge = false,
                               const TerrainParams& terrain = {}, double shift_x = 0.0) {
  const double spin = motion == Motion::tumbling ? 1000.0 : 1.0;
  const double push = motion == Motion::tumbling ? 10.0 : 1.0;
  BodyPlan plan = solid_block(5, 4, 3, 3.0e4);
  plan.materials.push_back(StructuralMaterial{1.0e5, 1000.0});
  for (int x = 0; x < 5; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 3; ++z)
        if ((x + y + z) % 2) plan.cells[plan.cell_index(x, y, z)] = 2;
  plan.cells[plan.cell_index(2, 1, 1)] = kEmptyCell;
  plan.cells[plan.cell_index(3, 2, 1)] = kFirstChamberCell;
  PhysicsConfig cfg;
  cfg.integrator = parse_choice<Integrator>(integrator, "integrator");
  BuildOptions options;
  options.simd = simd;
  options.terrain = terrain;
  const Model m = build_model(plan, cfg, options);
  State st = initial_state(m);
  Scratch sc = make_scratch(m);
  Rng rng(2024);
  // (x, y, z drawn in this order: with Vec3(rng.normal(), ...) the scene differed between GCC
  // and clang, see random_vec3.hpp)
  const auto normal = [&rng] { return rng.normal(); };
  for (int v = 0; v < m.voxel_count; ++v) {
    st.pos[v].z() += 0.3 * m.voxel_size;
    if (shift_x != 0.0) st.pos[v].x() += shift_x;
    st.lin_mom[v] = test::random_vec3(normal) * 2e-5;
    st.ang_mom[v] = test::random_vec3(normal) * (2e-10 * spin);
  }
  std::vector<Vec3> ext(m.voxel_count, Vec3::Zero());
  for (int i = 0; i < kSteps; ++i) {
    const double phase = (i % 200) < 100 ? 1.0 : -1.0;
    for (int v = 0; v < m.voxel_count; v += m.voxel_count / 4)
      ext[v] = Vec3(0.0, 0.0, 0.02 * push * phase);
    step(m, st, sc, ext);
  }
  if (diverge) {
    st.pos[m.voxel_count / 2].x() += 2.0;
    if (step(m, st, sc, ext) != StepStatus::diverged) return 0;
  }
  return state_hash(st);
}

}  // namespace softevo::physics::golden
