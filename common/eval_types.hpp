// Work units and their results: plain data exchanged between master and workers (wire.hpp
// encodes them) and produced by the single-process `softevo eval`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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

const char* to_string(EvalStatus status);  // "ok", "killed: flipped", ...
bool is_killed(EvalStatus status);         // anything but ok scores like a killed robot

// Fitness components of one direction of the directed task (§7.2), or of the gait task (§7.1:
// only distance is meaningful: mean x displacement [cm]).
struct DirectionComponents {
  double direction_deg = 0.0;
  double fitness = 0.0;
  double distance = 0.0;               // D [cm], signed distance along the target line
  double path_length = 0.0;            // L [cm]
  double angle_error = 0.0;            // delta [rad]
  double perpendicular_penalty = 0.0;  // P (already x omega) [cm]
  EvalStatus status = EvalStatus::ok;
};

struct EvalRequest {
  std::uint64_t config_hash = 0;
  std::int64_t generation = 0;
  std::int64_t genome_id = 0;
  std::int32_t direction_index = -1;  // -1: gait task; 0..4 index into task.directions
  std::vector<std::uint8_t> genome;   // canonical genome encoding (evo)
};

struct EvalResult {
  std::int64_t genome_id = 0;
  std::int32_t direction_index = -1;
  EvalStatus status = EvalStatus::ok;
  double fitness = 0.0;
  std::vector<DirectionComponents> components;  // one per evaluated direction (gait: one)
  std::int32_t voxels = 0;
  std::int32_t chambers = 0;
  std::int64_t steps = 0;        // physics steps simulated
  double sim_seconds = 0.0;      // simulated time [s]
  double wall_seconds = 0.0;     // evaluation wall time [s] (not part of determinism)
  std::int32_t worker_rank = 0;  // (not part of determinism)
  std::string message;           // failure explanation, "" when ok
};

}  // namespace softevo
