// Work units and their results: plain data exchanged between master and workers (wire.hpp
// encodes them) and produced by the single-process `softevo eval`.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/choice.hpp"

namespace softevo {

enum class EvalStatus : std::uint8_t {
  ok = 0,
  killed_flipped = 1,   // mean tilt > 60 degrees (§2.15)
  killed_exploded = 2,  // link strain > 2 (§2.15)
  diverged = 3,         // link strain > 100 or non-finite state (numerical trouble as data)
  failed = 4,           // worker-side exception; message says why
  timeout = 5,          // evaluation exceeded run.eval_timeout_seconds
  invalid_body = 6,     // body not valid or not actuatable (never simulated)
};

template <>
struct ChoiceNames<EvalStatus> {
  static constexpr std::array<const char*, 7> names = {
      "ok", "killed: flipped", "killed: exploded", "diverged", "failed", "timeout", "invalid body"};
};
bool is_killed(EvalStatus status);  // anything but ok scores like a killed robot

// Score of one work unit: its fitness, its status and the values of the task's named
// components (names and units: tasks::Task::component_names(), values in that order; all 0 for
// a unit that is not ok).
struct UnitFitness {
  double fitness = 0.0;
  EvalStatus status = EvalStatus::ok;
  std::vector<double> values;
};

struct EvalRequest {
  std::uint64_t config_hash = 0;
  std::int64_t generation = 0;
  std::int64_t genome_id = 0;
  std::int32_t unit = 0;             // work unit of the genome, 0 .. Task::units() - 1
  std::vector<std::uint8_t> genome;  // canonical genome encoding (evo)
};

struct EvalResult {
  std::int64_t genome_id = 0;
  std::int32_t unit = 0;
  EvalStatus status = EvalStatus::ok;
  double fitness = 0.0;
  std::vector<UnitFitness> components;  // one per evaluated unit
  std::int32_t voxels = 0;
  std::int32_t chambers = 0;
  std::int64_t steps = 0;        // physics steps simulated
  double sim_seconds = 0.0;      // simulated time [s]
  double wall_seconds = 0.0;     // evaluation wall time [s] (not part of determinism)
  std::int32_t worker_rank = 0;  // (not part of determinism)
  std::string message;           // failure explanation, "" when ok
};

}  // namespace softevo
