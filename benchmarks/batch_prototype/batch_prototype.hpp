// Issue 40's measurement prototype: K evaluations of one Model stepped together, lane k of every
// vector holding evaluation k ("element by lane": component c of voxel v of lane k at
// (v * 3 + c) * K + k). Only what the measurement needs: the pneuvox step's link pass and voxel
// passes (docs/model.md §2.3-2.13) on flat ground, without self-collision and with a fixed
// external force, so that it can be compared with today's physics::step on the same Model
// (self_collision off). Not part of the physics library: a benchmark program
// (benchmarks/batch_prototype/README.md).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "physics/model.hpp"
#include "physics/state.hpp"

namespace softevo::batch_prototype {

struct Batch {
  int lanes = 0;  // K
  int voxels = 0, links = 0;
  float previous_dt = 0.0f;  // [s], the same in every lane once each has stepped
  // voxels: (v * 3 + c) * K + k, orientation (v * 4 + c) * K + k (w, x, y, z)
  std::vector<double> pos, lin_mom, ang_mom, orient;  // [m], [kg m/s], [kg m^2/s], [-]
  std::vector<std::uint8_t> static_friction;          // v * K + k
  // links: (i * 3 + c) * K + k
  std::vector<double> link_pos2, link_angle1v, link_angle2v;   // [m], [rad], [rad]
  std::vector<float> link_strain;                              // i * K + k [-]
  std::vector<std::uint8_t> link_small_angle, link_vel_valid;  // i * K + k
  // per-step buffers: end loads (slot * 6 + c) * K + k (force [N], moment [N m]), the missing
  // slot 2 x links zero; voxel vectors (v * 3 + c) * K + k
  std::vector<double> end_load, old_pos, part2_force, fric, collision_force, external_force;
  std::vector<double> damping_neg, damping_pos;  // per link [sqrt(kg)/s]
  float damping_dt = -1.0f;                      // previous_dt they were computed for [s]
};

// The batch of these states (one per lane) with zero external force.
Batch pack(const physics::Model& model, std::span<const physics::State* const> states);
// Lane k's voxel and link state back into `out` (a copy of a State of the same Model).
void unpack(const Batch& batch, int lane, physics::State& out);

// One pneuvox step of every lane (link pass, part 1, mid-step link pass, part 2); the lanes that
// diverged or became non-finite as bits. Kernels built for AVX-512 (batch_prototype_kernels.cpp).
int step_k1(const physics::Model& model, Batch& batch);
int step_k4(const physics::Model& model, Batch& batch);
int step_k8(const physics::Model& model, Batch& batch);

}  // namespace softevo::batch_prototype
