// The work of one evaluation and its limits (docs/model.md §5 step 8).
//
// A control frame runs stepsPerFrame = (int)(1/control_rate / dt) physics steps (float
// arithmetic, §5 step 8), and an evaluation runs round(control_rate x eval_seconds) frames. The
// time step shrinks with the voxel size and grows with the square root of density over
// stiffness (§2.14), so a hostile or mistyped input (a voxel of 1e-6 m: about a million steps per
// frame) would run for days, and one beyond float range would silently run none. The limits
// below are about a thousand times the thesis' work (104 steps per frame, 62,400 per 10 s
// evaluation); beyond them an evaluation is refused before it starts. The wall-clock deadline
// (run.eval_timeout_seconds, `softevo eval --timeout`) is checked once per frame, so the
// per-frame limit also bounds how late a deadline can be noticed.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"

namespace softevo::physics {

inline constexpr std::int64_t kMaxStepsPerFrame = 100'000;
inline constexpr std::int64_t kMaxStepsPerEvaluation = 100'000'000;

// An evaluation beyond a limit, or one that would simulate nothing; the message gives the
// numbers and what to change.
class WorkLimitError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct EvaluationWork {
  int steps_per_frame = 0;  // physics steps per control frame, 1 .. kMaxStepsPerFrame
  int frames = 0;           // control frames, >= 1
  std::int64_t steps() const { return static_cast<std::int64_t>(steps_per_frame) * frames; }
};

// The schedule of §5 step 8 for a model of time step `dt_f` [s]: the same numbers the main loop
// has always used. Throws WorkLimitError if a frame would need no step or more than
// kMaxStepsPerFrame, if no frame would be simulated, or if the total exceeds
// kMaxStepsPerEvaluation.
EvaluationWork evaluation_work(float dt_f, double control_rate, double eval_seconds);

// The smallest time step [s] of any body built from `materials` at `cfg` (voxel size, dt_fraction,
// integrator): the minimum over single voxels and linked pairs of every material. A run's
// evaluations all stay within evaluation_work() of this step.
float smallest_time_step(const PhysicsConfig& cfg,
                         const std::vector<StructuralMaterial>& materials);

// The work check of a run's config, before anything is started: throws WorkLimitError naming
// the config keys when the stiffest body the config allows (smallest_time_step of its material
// table) would exceed a limit.
void check_run_work(const Config& config);

}  // namespace softevo::physics
