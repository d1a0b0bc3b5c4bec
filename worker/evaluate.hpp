// The one evaluation entry: a robot and a work unit of its task -> EvalResult. Shared by the
// MPI worker loop, the single-rank master, `softevo eval` / `replay` / `champions` and the
// tests. MPI-free, HDF5-free; deterministic (same inputs -> bit-identical result).
//
// One evaluation is the main loop of docs/model.md §5 on a built robot. Per control frame
// f = 0 .. frames-1 (Appendix B item 1):
//   1. inputs [sin, cos, task inputs, pressure sensors] (§4.1): the oscillator, then the task's
//      inputs (tasks::UnitScore::controller_inputs, e.g. the direction sensor of §7.3), then the
//      chamber pressures of a closed-loop controller (§3.7; frame 0 reads
//      pneumatics.initial_sensor_pressure), everything after [sin, cos] capped at 10 values;
//   2. oscillator advance, Elman network, valve commands u = (y + 1)/2 (§4);
//   3. kill checks flipped()/exploded() (§2.15);
//   4. the task observes the robot (tasks::UnitScore::observe, e.g. the §7.2 waypoints);
//   5. steps_per_frame x (pneumatic update §3.6, physics step §2.12);
//   6. the wall-clock deadline and the abandon request, if any.
// After the loop the task scores the final state (§7).
//
// Failures are results, never exceptions: a body or controller that cannot be simulated gives
// status `failed` with the message, an invalid or non-actuatable body `invalid_body`, a deadline
// passed `timeout`, numerical trouble `diverged`; every status but ok scores fitness 0 like a
// killed robot (run.on_failure = "killed"). A controller fed by fewer task inputs than it has
// (a directed controller on the gait task) reads 0 for the missing ones; task inputs beyond the
// controller's are not fed.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "evo/genome.hpp"
#include "physics/model.hpp"
#include "physics/quat.hpp"
#include "tasks/task.hpp"
#include "worker/simulation.hpp"

namespace softevo::worker {

// Plain data of one recorded frame, handed to an observer (e.g. the HDF5 trace writer of
// `softevo eval --trace`). Views are valid only during the call.
struct TraceFrame {
  int frame = 0;      // control frame index; the record after the last frame has index `frames`
  double time = 0.0;  // simulated time at this record [s]
  std::span<const physics::Vec3> positions;     // voxel centres [m] (voxels)
  std::span<const physics::Quat> orientations;  // (w,x,y,z) (voxels)
  std::span<const double> pressures;            // chamber pressure, absolute [Pa] (chambers)
  std::span<const float> valve_commands;        // valve openings in [0,1] (2 x chambers)
  std::span<const float> inputs;                // controller inputs of this frame
};

// Called once before the first frame with the built model (for static trace data).
struct TraceHeader {
  const physics::Model* model = nullptr;
  int chambers = 0;
  int frames = 0;           // control frames planned
  int steps_per_frame = 0;  // physics steps per control frame
};

using Clock = std::chrono::steady_clock;

// The wall-clock deadline `seconds` from now; none for seconds <= 0 (no limit).
std::optional<Clock::time_point> deadline_after(double seconds);

// A genome turned into what the simulator needs.
struct BuiltRobot {
  bool valid = false;       // §6.5: at least one structural cell
  bool actuatable = false;  // §6.5: at least one chamber
  BodyPlan body;            // materials and voxel size filled from the config
  ControllerSpec controller;
};

struct EvaluateOptions {
  bool ablate_oscillator = false;  // feed 0 to the sin/cos inputs (thesis section 5.1.1)
  bool ablate_sensors = false;     // feed 0 to the pressure-sensor inputs
  // SIMD width of the physics step passes; results are bit-identical for every width
  physics::Simd simd = physics::Simd::best;
  // The evaluation's generation and genome id (the ground of terrain.resample depends on them);
  // the request entry sets them from the work unit.
  EvaluationIds ids;
  // Wall-clock deadline: an evaluation still running then stops with status timeout (checked
  // once per control frame). Work units from a request get now + run.eval_timeout_seconds
  // unless a deadline is given here.
  std::optional<Clock::time_point> deadline;
  // Asked once per control frame, with the deadline: true = the run is stopping (SIGTERM, the
  // launcher died), so the evaluation stops at once with status timeout and a message saying
  // it was abandoned. Such a result must never be archived; the caller discards it.
  std::function<bool()> abandon;
  std::function<void(const TraceHeader&)> on_start;  // optional observer
  std::function<void(const TraceFrame&)> on_frame;   // optional observer, 60 Hz
  // Stand-in for the evaluation of a built robot (tests inject faults and stand-in simulators
  // here); empty = evaluate(). Only the request entry uses it.
  std::function<EvalResult(const Config&, const tasks::Task&, const BuiltRobot&, const EvalRequest&,
                           const EvaluateOptions&)>
      evaluate_robot;
};

// Work unit `unit` of `task` for a robot. Never throws.
EvalResult evaluate(const Config& config, const tasks::Task& task, const BodyPlan& body,
                    const ControllerSpec& controller, int unit,
                    const EvaluateOptions& options = {});

// How a unit's result from worker::Simulation::finish() is scored: a non-finite fitness is
// status diverged, any status but ok scores 0, the unit's component row carries fitness and
// status. evaluate() applies it; a driver of its own Simulation applies it too.
void finalize_unit_result(const tasks::Task& task, EvalResult& result);

// Every unit of `task`, one after the other, combined (tasks::combine_units).
EvalResult evaluate_all_units(const Config& config, const tasks::Task& task, const BodyPlan& body,
                              const ControllerSpec& controller,
                              const EvaluateOptions& options = {});

// The master and a worker disagree about the experiment: no result would mean anything.
class ConfigMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A work unit as the master sends it: decode the genome, develop the body (§6), materials from
// the config, the controller, evaluate. `config_hash` must be config_hash(config) (passed in so
// it is computed once per run). Throws ConfigMismatch if request.config_hash differs; never
// throws otherwise (an undecodable genome is status failed).
EvalResult evaluate(const Config& config, const tasks::Task& task, std::uint64_t config_hash,
                    const EvalRequest& request, const EvaluateOptions& options = {});

// How a robot file is evaluated on its own (`softevo eval` and the Python package share it, so
// both give the same bits for the same inputs).
struct RobotEvalSettings {
  // The config: a TOML file, else TOML text (named `source_name` in error messages), else the
  // robot file's evaluation block (the settings of the run it was exported from), else the
  // built-in thesis defaults with task.control taken from the robot's controller. The overrides
  // apply to whichever it is.
  std::string config_path;
  std::optional<std::string> config_text;
  std::string source_name = "<config>";
  std::vector<std::string> overrides;  // "section.key=value"
  // The task: this name, else the config text's, else (built-in defaults) the one the
  // controller's inputs fit (tasks::default_task_for). Applied as the last override, so that a
  // key of that task is accepted.
  std::string task;
  std::optional<Integrator> integrator;  // none = the config's physics.integrator
  std::optional<double> seconds;         // replaces task.eval_seconds [s] (range-checked)
  std::optional<double> direction;       // replaces task.directions by [direction] [deg]
};
// Where the config of a robot evaluation comes from (the order of RobotEvalSettings).
enum class RobotConfigSource : std::uint8_t { config_file, config_text, robot_file, built_in };
RobotConfigSource robot_config_source(const RobotFile& robot, const RobotEvalSettings& settings);
}  // namespace softevo::worker
// "robot" (its evaluation block), "file", "text" or "defaults": the JSON spelling.
template <>
struct softevo::ChoiceNames<softevo::worker::RobotConfigSource> {
  static constexpr std::array<const char*, 4> names = {"file", "text", "robot", "defaults"};
};
namespace softevo::worker {
// One line for people: "the robot file's run config (hash ..., from RUN.h5 generation G id I)",
// "--config FILE", ... with the --set overrides counted.
std::string describe_config_source(const RobotFile& robot, const RobotEvalSettings& settings);
// The resolved config; throws ConfigError.
Config robot_eval_config(const RobotFile& robot, const RobotEvalSettings& settings);

// The controller gets the inputs of `task` (config's task: the caller's, evaluate() holds one).
BuiltRobot build_robot(const Config& config, const evo::Genome& genome, const tasks::Task& task);

// The robot file of a genome (body, controller, genome records), named `name`.
RobotFile robot_file_of(const Config& config, const evo::Genome& genome, const std::string& name);

}  // namespace softevo::worker
