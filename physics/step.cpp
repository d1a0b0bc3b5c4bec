// One physics time step: the public step(), the per-step buffers and the choice of SIMD width.
// The link, voxel and mesh passes are in physics/step_kernels.hpp, built once per lane width in
// step_<ISA>.cpp; all widths give bit-identical results (see step_kernels.hpp). Self-collision:
// physics/collision.cpp.
#include "physics/step.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <stdexcept>
#include <string>

#include "physics/collision.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

Scratch make_scratch(const Model& model) {
  Scratch sc;
  const std::size_t nl = model.link_count, nv = model.voxel_count;
  sc.link_end_load.assign(model.missing_load_slot() + 1,
                          Scratch::EndLoad{Vec3::Zero(), Vec3::Zero()});
  sc.link_list_small.assign(nl, 0);
  sc.link_list_large.assign(nl, 0);
  sc.link_damping_neg.assign(nl, 0.0);
  sc.link_damping_pos.assign(nl, 0.0);
  sc.collision_force.assign(nv, Vec3::Zero());
  sc.part2_force.assign(nv, Vec3::Zero());
  sc.fric.assign(nv, Vec3::Zero());
  sc.old_pos.assign(nv, Vec3::Zero());
  const std::size_t ns = model.surface_voxels.size();
  std::size_t buckets = 1;
  while (buckets < 2 * ns + 2) buckets <<= 1;
  sc.grid_entries.assign(ns, Scratch::GridEntry{});
  sc.grid_sorted.assign(ns, Scratch::GridEntry{});
  sc.grid_bucket_begin.assign(buckets + 1, 0);
  sc.candidates.assign(ns, 0);
  return sc;
}

std::optional<Simd> parse_simd(std::string_view name) {
  for (Simd s : {Simd::best, Simd::sse2, Simd::avx2, Simd::avx512, Simd::scalar, Simd::neon})
    if (name == to_string(s)) return s;
  return std::nullopt;
}

std::vector<Simd> simd_widths() {
  std::vector<Simd> widths{Simd::scalar};
#if defined(SOFTEVO_HAVE_SSE2_KERNELS)
  widths.push_back(Simd::sse2);
#endif
#if defined(SOFTEVO_HAVE_NEON_KERNELS)
  widths.push_back(Simd::neon);
#endif
#if defined(SOFTEVO_HAVE_AVX2_KERNELS)
  widths.push_back(Simd::avx2);
#endif
#if defined(SOFTEVO_HAVE_AVX512_KERNELS)
  widths.push_back(Simd::avx512);
#endif
  return widths;
}

std::vector<std::string> simd_names() {
  std::vector<std::string> names{to_string(Simd::best)};
  for (Simd s : simd_widths()) names.emplace_back(to_string(s));
  return names;
}

bool simd_supported(Simd simd) {
  switch (simd) {
    case Simd::best:
    case Simd::scalar:
      return true;
    case Simd::sse2:
#if defined(SOFTEVO_HAVE_SSE2_KERNELS)
      return true;  // part of every x86-64 CPU
#else
      return false;
#endif
    case Simd::neon:
#if defined(SOFTEVO_HAVE_NEON_KERNELS)
      return true;  // part of every AArch64 CPU
#else
      return false;
#endif
    case Simd::avx2:
#if defined(SOFTEVO_HAVE_AVX2_KERNELS)
      return __builtin_cpu_supports("avx2");
#else
      return false;
#endif
    case Simd::avx512:
#if defined(SOFTEVO_HAVE_AVX512_KERNELS)
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("avx512f") &&
             __builtin_cpu_supports("avx512vl");
#else
      return false;
#endif
  }
  return false;
}

Simd best_simd() {
  const std::vector<Simd> widths = simd_widths();  // narrowest first
  for (auto s = widths.rbegin(); s != widths.rend(); ++s)
    if (simd_supported(*s)) return *s;
  return Simd::scalar;
}

Simd resolve_simd(Simd simd) {
  return simd == Simd::best ? best_simd() : simd;
}

const StepKernels& step_kernels(Simd simd) {
  switch (resolve_simd(simd)) {
#if defined(SOFTEVO_HAVE_SSE2_KERNELS)
    case Simd::sse2:
      return step_kernels_sse2();
#endif
#if defined(SOFTEVO_HAVE_AVX2_KERNELS)
    case Simd::avx2:
      return step_kernels_avx2();
#endif
#if defined(SOFTEVO_HAVE_AVX512_KERNELS)
    case Simd::avx512:
      return step_kernels_avx512();
#endif
#if defined(SOFTEVO_HAVE_NEON_KERNELS)
    case Simd::neon:
      return step_kernels_neon();
#endif
    default:
      return step_kernels_scalar();
  }
}

StepStatus step(const Model& model, State& state, Scratch& scratch,
                std::span<const Vec3> external_force) {
  if (!external_force.empty() &&
      external_force.size() != static_cast<std::size_t>(model.voxel_count))
    throw std::invalid_argument("physics::step: external_force has " +
                                std::to_string(external_force.size()) + " entries, model has " +
                                std::to_string(model.voxel_count) + " voxels");
  const StepKernels& kernels = step_kernels(model.simd);
  // 1. link pass; strain > 100 -> nothing else advances. The pneuvox step's mid-step link pass
  //    (§2.12 step 6) overwrites pos2, the angles and the strain before anything reads them, so
  //    its first pass leaves them out, and stores them only for a refused step.
  const bool pneuvox = model.integrator == Integrator::pneuvox;
  if (pneuvox ? kernels.link_pass_forces_only(model, state, scratch)
              : kernels.link_pass_forces(model, state, scratch)) {
    if (pneuvox) kernels.link_pass_restore_state(model, state, scratch);
    ++state.counters.diverged_steps;
    return StepStatus::diverged;
  }
  // 2. collisions
  if (model.self_collision) update_collisions(model, state, scratch);
  const bool finite = pneuvox
                          ? kernels.fork_voxel_passes(model, state, scratch, external_force)
                          : kernels.symplectic_voxel_pass(model, state, scratch, external_force);
  state.time += model.dt_f;  // 9.
  if (!finite) {
    ++state.counters.non_finite_steps;
    return StepStatus::non_finite;
  }
  ++state.counters.steps;
  return StepStatus::ok;
}

}  // namespace softevo::physics
