// Shared by the batched-step tests (test_batch.cpp, test_batch_champions.cpp): lanes made of a
// champion's own evaluation, and the check that every lane of step_batch() equals
// physics::step() of that evaluation alone, bit for bit.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/robot.hpp"
#include "physics/batch.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"
#include "worker/evaluation_states.hpp"

namespace softevo::test {

struct BatchCase {
  physics::Model model;
  std::vector<physics::State> states;  // the lanes' starting states
};

// `count` states of the robot's own evaluation, one every `gap_frames` control frames from frame
// `first_frame` on (worker/evaluation_states.hpp).
inline BatchCase batch_case_of_robot(const std::filesystem::path& file, int count,
                                     int first_frame = 10, int gap_frames = 3) {
  worker::EvaluationStates e =
      worker::evaluation_states(read_robot_file(file.string()), count, first_frame, gap_frames);
  return BatchCase{std::move(e.model), std::move(e.states)};
}

// A different external force for every lane [N] (the pneumatics of each evaluation).
inline std::vector<std::vector<physics::Vec3>> lane_forces(const physics::Model& m, int lanes) {
  std::vector<std::vector<physics::Vec3>> f(static_cast<std::size_t>(lanes));
  for (int k = 0; k < lanes; ++k)
    for (int v = 0; v < m.voxel_count; ++v)
      f[k].emplace_back(1e-4 * ((v * 7 + k * 3) % 11 - 5), 1e-4 * ((v * 5 + k) % 7 - 3),
                        1e-4 * ((v + 2 * k) % 5 - 2));
  return f;
}

// Steps `states` (one per lane) `steps` times with step_batch() at `simd` and each state alone
// with physics::step() (scalar width), lane k with forces[k]; lane k ends after end_after[k]
// steps (if given) as a killed evaluation would. Expects every lane's final state (state_hash:
// every field, time and counters included) and every step's status to be the reference's.
inline void expect_lanes_equal_steps_alone(physics::Model model,
                                           const std::vector<physics::State>& states,
                                           physics::Simd simd, int steps,
                                           const std::vector<int>& end_after = {},
                                           const std::string& what = "") {
  const int lanes = static_cast<int>(states.size());
  const auto forces = lane_forces(model, lanes);
  // the reference: each evaluation alone, stopped at its first failed step or at end_after
  model.simd = physics::Simd::scalar;
  std::vector<physics::State> alone(states);
  std::vector<std::vector<physics::StepStatus>> alone_status(static_cast<std::size_t>(lanes));
  for (int k = 0; k < lanes; ++k) {
    physics::Scratch sc = physics::make_scratch(model);
    const int last = k < static_cast<int>(end_after.size()) ? end_after[k] : steps;
    for (int s = 0; s < last; ++s) {
      alone_status[k].push_back(physics::step(model, alone[k], sc, forces[k]));
      if (alone_status[k].back() != physics::StepStatus::ok) break;
    }
  }
  model.simd = simd;
  physics::BatchState batch = physics::make_batch_state(model, states);
  physics::BatchScratch scratch = physics::make_batch_scratch(model, batch);
  std::vector<std::span<const physics::Vec3>> ext(forces.begin(), forces.end());
  std::vector<physics::StepStatus> status(static_cast<std::size_t>(lanes));
  for (int s = 0; s < steps; ++s) {
    for (int k = 0; k < lanes; ++k)
      if (k < static_cast<int>(end_after.size()) && end_after[k] == s) physics::end_lane(batch, k);
    physics::step_batch(model, batch, scratch, ext, status);
    for (int k = 0; k < lanes; ++k) {
      if (s < static_cast<int>(alone_status[k].size())) {
        EXPECT_EQ(status[k], alone_status[k][s])
            << what << " " << softevo::to_string(simd) << " K=" << lanes << " lane " << k
            << " step " << s;
      }
    }
  }
  physics::State out;
  for (int k = 0; k < lanes; ++k) {
    physics::get_lane(batch, k, out);
    EXPECT_EQ(physics::state_hash(out), physics::state_hash(alone[k]))
        << what << " " << softevo::to_string(simd) << " K=" << lanes << " lane " << k;
  }
}

}  // namespace softevo::test
