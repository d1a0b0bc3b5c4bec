// One work unit of a task on a built body, advanced one control frame at a time: the main loop
// of docs/model.md §5 with the controller taken out, so that any controller can drive it (the
// built-in Elman network in worker::evaluate, a Python policy through the softevo package).
//
// A driver calls, per control frame f = 0 .. frames()-1:
//   task_inputs() and sensor_pressure_bar(q)   what a controller reads this frame (§4.1, §3.7);
//   step(valve_commands)                       the rest of the frame (§5 steps 3-5): valves set,
//                                              kill checks, task observation, steps_per_frame x
//                                              (pneumatic update, physics step);
// and, when every frame ran, finish() for the unit's score. worker::evaluate is exactly this
// loop with worker::ElmanController as the driver, so a driver feeding the same valve commands
// gets the same bits.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "physics/model.hpp"
#include "physics/pneumatics.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"
#include "tasks/task.hpp"

namespace softevo::worker {

// Which evaluation a simulation is: the ground of terrain.resample = "per_generation" or
// "per_evaluation" depends on it (the master's work unit carries both; `softevo eval` of a robot
// file with its run's config takes those it was archived with, worker::robot_eval_ids).
struct EvaluationIds {
  std::int64_t generation = 0;
  std::int64_t genome_id = 0;
};

// The ground of one evaluation (docs/model.md §2.8a): config.terrain with its seed derived from
// (terrain.seed, run.seed) and, as terrain.resample says, the generation, the genome id and the
// work unit (the direction of the directed task). A function of these ids only, so the same
// evaluation gets the same ground on any rank, at any rank count, and in replay.
physics::TerrainParams terrain_params(const Config& config, const EvaluationIds& ids, int unit);

class Simulation {
 public:
  // Builds the model and pneumatics of `body` for work unit `unit` of `task`. Throws
  // std::invalid_argument for a unit outside the task, a bad control rate or evaluation length,
  // or a body the physics cannot build. A body without voxels or chambers is not an error: the
  // simulation starts with status invalid_body and never runs. `task` must outlive
  // the simulation.
  Simulation(const Config& config, const tasks::Task& task, const BodyPlan& body, int unit,
             physics::Simd simd = physics::Simd::best, const EvaluationIds& ids = {});
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  int unit() const { return unit_; }
  int frames() const { return frames_; }  // control frames of a full evaluation
  int frame() const { return frame_; }    // frames simulated so far
  int steps_per_frame() const { return steps_per_frame_; }
  int voxels() const { return model_.voxel_count; }
  int chambers() const { return pneumatics_model_.chamber_count; }
  int valve_count() const { return pneumatics_model_.valve_count; }  // 2 per chamber
  std::int64_t steps() const { return steps_; }                      // physics steps so far
  double time() const { return state_.time; }                        // simulated time [s]
  EvalStatus status() const { return status_; }
  const std::string& message() const { return message_; }
  // Status ok and frames left to simulate.
  bool running() const { return status_ == EvalStatus::ok && frame_ < frames_; }

  const physics::Model& model() const { return model_; }
  const physics::State& state() const { return state_; }
  const physics::PneumaticsState& pneumatics() const { return pneumatics_; }
  const tasks::Task& task() const { return task_; }

  // The task's controller inputs of this frame (task().controller_inputs() values, e.g. the
  // direction sensor of §7.3).
  void task_inputs(std::span<float> inputs);
  // The task's fitness and components if the unit ended now (UnitScore::so_far); zeros once
  // the unit has stopped with a status other than ok (as finish() would give).
  UnitFitness score_so_far() const;
  // A new target direction [deg, within [-180, 180]] for a steerable task (the viewer's dial,
  // a Python agent): the controller senses it and the unit is scored towards it from now on.
  // Throws std::logic_error for a task that is not steerable, std::invalid_argument for a
  // direction out of range.
  void steer(double direction_deg);
  // The pressure sensor reading of chamber q this frame [bar] (§3.7): the configured
  // pneumatics.initial_sensor_pressure at frame 0, the chamber pressure afterwards.
  float sensor_pressure_bar(int chamber) const;

  // One control frame with these valve openings in [0, 1] (valve_count() values: 2q inlet, 2q+1
  // outlet of chamber q). Returns the status afterwards: ok, killed (flipped or exploded at the
  // start of the frame: no step is made) or diverged. Throws std::logic_error unless running()
  // and std::invalid_argument for a wrong number of commands.
  EvalStatus step(std::span<const float> valve_commands);

  // Ends the simulation early with `status` (not ok), e.g. a driver's wall-clock deadline.
  void stop(EvalStatus status, std::string message);

  // The unit's result: the task's score of the final state when the status is ok (fitness and
  // named components; every frame should have run), else fitness 0 and zero components. Steps,
  // simulated time and body counts are filled in; wall time is left to the caller.
  EvalResult finish();

 private:
  const tasks::Task& task_;
  int unit_ = 0;
  physics::Model model_;
  physics::PneumaticsModel pneumatics_model_;
  physics::State state_;
  physics::Scratch scratch_;
  physics::PneumaticsState pneumatics_;
  physics::PneumaticsScratch pneumatics_scratch_;
  std::vector<physics::Vec3> external_force_;
  std::unique_ptr<tasks::UnitScore> score_;
  int frames_ = 0;
  int steps_per_frame_ = 0;
  int frame_ = 0;
  std::int64_t steps_ = 0;
  float initial_sensor_bar_ = 0.0f;
  EvalStatus status_ = EvalStatus::ok;
  std::string message_;
};

}  // namespace softevo::worker
