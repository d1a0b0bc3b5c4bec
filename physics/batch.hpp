// Many evaluations of one body in one step (issue 40): K States of one Model stepped together,
// lane k of every SIMD vector holding evaluation k. A link reads its two end voxels with plain
// vector loads at one index for all lanes, and the index arithmetic, loop control and constants
// are shared; each lane performs exactly the scalar step's operations in its order, so lane k's
// state after step_batch() equals physics::step() of evaluation k alone, bit for bit, at every
// SIMD width.
//
// Layout ("element by lane"): component c of voxel or link e of lane k at
// (e * components + c) * padded + k, where padded is K rounded up to the kernels' vector width
// (Model::simd: scalar 1, sse2 / neon 2, avx2 4, avx512 8 or 4 lanes, whichever leaves fewer
// lanes idle: 4 for K <= 4 and 9-12). Per lane, what differs between
// evaluations is handled per lane: link modes (a link whose lanes are in different modes computes
// the large-angle frame and selects per lane), damping validity, floor contact and static friction
// (per lane in scalar code, as in the one-robot passes), self-collision (each lane's own pair
// list and forces: physics/collision.cpp on the lane's positions), the external force (the
// pneumatics of each lane, given per lane) and the statuses: a lane whose step fails, or that
// end_lane() ends, keeps its state from then on and is no longer stepped; a batch whose lanes all
// ended does nothing.
//
// What docs/scaling.md ("Lanes across evaluations") measured on a full-width AVX-512 core: 8 or
// 16 evaluations per step cost 0.77-0.85 of each stepped alone (a body whose batch fits the L2:
// 0.67), 4 about the same as alone, 5 and 10 (lanes idle) more; a batch of 1 runs the one-robot
// step itself.
//
// Only the pneuvox integrator is batched: a symplectic Model steps each lane with
// physics::step() (same bits, no gain). Pure computation: no allocation in step_batch(), no
// MPI, no HDF5.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "physics/model.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"

namespace softevo::physics {

// The most evaluations one batch holds (two 8-lane vectors per element at avx512).
inline constexpr int kMaxBatchLanes = 16;

struct BatchState {
  int lanes = 0;   // K
  int width = 0;   // evaluations per vector of its kernels (0: each lane steps alone)
  int padded = 0;  // element stride: K rounded up to `width` (lanes >= K are idle)
  // Voxels: (v * 3 + c) * padded + k; orientation (v * 4 + c) * padded + k, (w, x, y, z).
  std::vector<double> pos;                    // [m]
  std::vector<double> lin_mom;                // [kg m/s]
  std::vector<double> ang_mom;                // [kg m^2/s]
  std::vector<double> orient;                 // [-]
  std::vector<std::uint8_t> static_friction;  // v * padded + k
  // Links: (i * 3 + c) * padded + k
  std::vector<double> link_pos2;                               // [m]
  std::vector<double> link_angle1v;                            // [rad]
  std::vector<double> link_angle2v;                            // [rad]
  std::vector<float> link_strain;                              // i * padded + k [-]
  std::vector<std::uint8_t> link_small_angle, link_vel_valid;  // i * padded + k
  // Per lane: the rest of its State (time, previous_dt, counters, collision bookkeeping). While
  // a lane runs, the voxel and link fields of lane[k] are only a workspace (its positions and
  // momenta are copied there for the collisions); once it has ended, lane[k] is its state.
  std::vector<State> lane;
  std::vector<std::uint8_t> running;  // 1 = stepped by step_batch (lanes)
};

// Per-step buffers of a batch, sized once (element by lane like BatchState).
struct BatchScratch {
  std::vector<double> end_load;  // link end loads (slot * 6 + c) * padded + k, [N] and [N m]
  std::vector<double> old_pos, part2_force, fric, collision_force,
      external_force;               // (v * 3 + c) * padded + k, [m] and [N]
  bool external_force_zero = true;  // every external_force entry is +0
  // §2.5 link damping multipliers c_N, c_P of each link for previous_dt = Model::dt_f (every
  // lane's previous_dt is 0 or dt_f, and at 0 no link has a valid local velocity)
  std::vector<double> damping_neg, damping_pos;  // [sqrt(kg)/s] (links)
  std::vector<Scratch> lane;                     // each lane's collision scratch (lanes)
};

// The batch of `states` (one per lane, in lane order), each a State of `model` (made by
// initial_state() and step()). Throws std::invalid_argument for no states, more than
// kMaxBatchLanes, a state of another size, or a previous_dt that is neither 0 nor dt_f.
BatchState make_batch_state(const Model& model, std::span<const State> states);
BatchScratch make_batch_scratch(const Model& model, const BatchState& batch);

// Lane k's whole state (as physics::step() would have left evaluation k alone). `out` is
// overwritten (a State of the same Model allocates nothing).
void get_lane(const BatchState& batch, int lane, State& out);
const State& ended_lane(const BatchState& batch, int lane);  // the state of a lane that ended

// Ends lane k: it keeps its present state and is not stepped again (a finished, killed or
// timed-out evaluation). Ending an ended lane does nothing.
void end_lane(BatchState& batch, int lane);
bool lane_running(const BatchState& batch, int lane);

// One step of every running lane. external_force: empty (no external force), or one span per
// lane (lanes), each empty or of model.voxel_count forces [N] (global frame, as physics::step()).
// status[k] receives lane k's StepStatus (ok for a lane that was not running); a lane whose step
// is not ok ends with that step's state (as physics::step() leaves it). Throws
// std::invalid_argument for wrong sizes.
void step_batch(const Model& model, BatchState& batch, BatchScratch& scratch,
                std::span<const std::span<const Vec3>> external_force,
                std::span<StepStatus> status);

}  // namespace softevo::physics
