// The Task seam: what a robot is evaluated for (docs/model.md §7). One module per task
// (gait.cpp, directed.cpp, rotate.cpp), registered in registry.cpp. Everything that depends on
// the task asks it:
//   - the simulation loop (worker/evaluate.cpp) asks for the controller inputs of every frame,
//     hands it the robot once per frame and at the end, and gets the unit's score;
//   - the scheduler and replay ask for the work units per genome and how they combine;
//   - the archive and `eval --json` ask for the names of the fitness components;
//   - live views (the viewer, the Python env) ask a running unit for its score so far and hand
//     it the steering input.
// The task's config keys live in [task] (common/config_schema.cpp, each row marked with its task).
//
// MPI-free and HDF5-free; the interface itself is physics-free (the robot is passed as the
// physics model and state, forward-declared here).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"

namespace softevo::physics {
struct Model;
struct State;
}  // namespace softevo::physics

namespace softevo::tasks {

// A fitness component: its name (a stable identifier, archived) and its unit.
struct ComponentName {
  std::string name;
  std::string unit;  // "cm", "rad", "deg", "body lengths", "" (dimensionless)
};

// The score of one work unit while it is simulated. The simulation loop calls, per control
// frame f = 0 .. frames-1 (docs/model.md §5):
//   controller_inputs  when the controller reads its inputs (step 1, before the network);
//   observe            after the kill checks, before the physics steps of the frame (step 4);
// and, when the frame loop ended ok, finish once on the final state.
class UnitScore {
 public:
  virtual ~UnitScore() = default;
  // Writes the task's Task::controller_inputs() inputs of this frame into `inputs`.
  virtual void controller_inputs(const physics::Model& model, const physics::State& state,
                                 std::span<float> inputs);
  virtual void observe(int frame, const physics::Model& model, const physics::State& state);
  // Fitness and component values (in Task::component_names() order) of the finished unit.
  virtual UnitFitness finish(const physics::Model& model, const physics::State& state) = 0;
  // What finish would give if the unit ended on `state` now, changing nothing: the fitness and
  // components a live view shows while the robot moves (the viewer, the Python env's reward).
  virtual UnitFitness so_far(const physics::Model& model, const physics::State& state) const = 0;
  // Steering (Task::steerable()): from now on the target is `direction_deg` [deg], for the
  // controller's inputs and for the score. Throws std::logic_error for a task without a target.
  virtual void steer(double direction_deg);
};

// Fitness of a genome from its units.
struct CombinedFitness {
  EvalStatus status = EvalStatus::ok;  // first status that is not ok, in unit order
  double fitness = 0.0;
  std::string message;  // of that unit
};

class Task {
 public:
  virtual ~Task() = default;
  virtual TaskKind kind() const = 0;
  // Names of the controller inputs the task feeds after the oscillator's [sin, cos] and before
  // the pressure sensors (§4.1), e.g. "direction_sensor".
  virtual std::vector<std::string> controller_input_names() const = 0;
  int controller_inputs() const { return static_cast<int>(controller_input_names().size()); }
  // Whether a unit's target direction can be changed while it runs (UnitScore::steer).
  virtual bool steerable() const { return false; }
  // Work units per genome; each is simulated on its own (one MPI work unit each).
  virtual int units() const = 0;
  virtual std::vector<ComponentName> component_names() const = 0;
  // Unit of the genome's fitness ("cm", "rad"), for progress lines and plot axes.
  virtual std::string fitness_unit() const = 0;
  // A fresh score for work unit `unit` (0 .. units()-1) of the robot built as `model`.
  virtual std::unique_ptr<UnitScore> start_unit(int unit, const physics::Model& model) const = 0;
  // Default: the sum of the unit fitnesses in unit order (§7.4), 0 if any unit is not ok (a
  // killed or failed unit scores the genome like a killed robot, §7.1, §7.4).
  virtual CombinedFitness combine(std::span<const EvalResult> units) const;
};

// The task of `config` (registry.cpp). `config` must outlive the task.
std::unique_ptr<Task> make_task(const Config& config);

// The task to evaluate a robot file with when none is configured: the first registered task
// whose controller inputs match the controller's (gait for none, directed for one).
TaskKind default_task_for(int controller_task_inputs);

// One genome's units (in unit order) combined into one result: fitness and status from
// task.combine, one component row per unit (fitness and status of the unit's result; values
// zero-filled to the task's component count when a unit has none), steps, simulated and wall
// time summed, body counts and worker rank of the first unit.
EvalResult combine_units(const Task& task, std::span<const EvalResult> units);

// A unit's components as a row [fitness, values..., status]: the archive's component columns
// (names: component_columns(task)).
std::vector<double> component_row(const UnitFitness& unit);
std::vector<std::string> component_columns(const Task& task);

}  // namespace softevo::tasks
