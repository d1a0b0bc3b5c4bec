// One work unit advanced one control frame at a time (docs/model.md §5). See simulation.hpp.
#include "worker/simulation.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/rng.hpp"
#include "physics/observables.hpp"
#include "physics/work_limits.hpp"

namespace softevo::worker {
namespace {

// The unit, checked before anything is built (the task must be able to score it).
int checked_unit(const Config& config, const tasks::Task& task, int unit) {
  if (unit < 0 || unit >= task.units())
    throw std::invalid_argument("work unit " + std::to_string(unit) + " outside the " +
                                std::to_string(task.units()) + " units of task " +
                                to_string(task.kind()));
  const TaskConfig& tc = config.task;
  if (!(tc.control_rate > 0.0) || !(tc.eval_seconds >= 0.0))
    throw std::invalid_argument("task.control_rate must be > 0 and task.eval_seconds >= 0");
  return unit;
}

// The pneumatics of a body with structural voxels; a model without voxels has no time step, and
// the pneumatics' complaint about it would hide the real cause (reported by the constructor).
// The work limits are checked first too (WorkLimitError): a time step far too large or small
// for a frame is the cause that the pneumatics' own complaint (its valve filter) would hide.
physics::PneumaticsModel pneumatics_of(const BodyPlan& body, const physics::Model& model,
                                       const Config& config) {
  if (model.voxel_count == 0) return {};
  physics::evaluation_work(model.dt_f, config.task.control_rate, config.task.eval_seconds);
  return physics::build_pneumatics(body, model, config.pneumatics);
}

physics::BuildOptions build_options_for(physics::Simd simd, physics::TerrainParams terrain) {
  physics::BuildOptions options;
  options.simd = simd;
  options.terrain = terrain;
  return options;
}

}  // namespace

physics::TerrainParams terrain_params(const Config& config, const EvaluationIds& ids, int unit) {
  const TerrainConfig& tc = config.terrain;
  physics::TerrainParams p;
  p.kind = physics::terrain_kind(tc.kind, tc.heightfield);
  if (p.kind == physics::TerrainKind::flat) return p;
  p.shape = tc.shape;
  // -1 = "not part of this ground's identity" (derive_seed's convention for a missing id).
  const bool per_generation = tc.ground_varies_with_generation();
  const bool per_evaluation = tc.ground_varies_with_evaluation();
  std::uint64_t base = static_cast<std::uint64_t>(tc.seed);
  base = splitmix64(base) ^ static_cast<std::uint64_t>(config.run.seed);
  p.seed = derive_seed(base, per_generation ? ids.generation : -1,
                       per_evaluation ? ids.genome_id : -1, per_evaluation ? unit : -1);
  return p;
}

Simulation::Simulation(const Config& config, const tasks::Task& task, const BodyPlan& body,
                       int unit, physics::Simd simd, const EvaluationIds& ids)
    : task_(task),
      unit_(checked_unit(config, task, unit)),
      model_(physics::build_model(body, config.physics,
                                  build_options_for(simd, terrain_params(config, ids, unit_)))),
      pneumatics_model_(pneumatics_of(body, model_, config)) {
  if (model_.voxel_count == 0) {
    status_ = EvalStatus::invalid_body;
    message_ = body.chamber_count() > 0
                   ? "body has only chamber cells, no structural voxel (material 1..10)"
                   : "body has no cells (every cell is empty)";
    return;
  }
  if (pneumatics_model_.chamber_count == 0) {
    status_ = EvalStatus::invalid_body;
    message_ = "body has no chamber (not actuatable)";
    return;
  }
  state_ = physics::initial_state(model_);
  scratch_ = physics::make_scratch(model_);
  pneumatics_ = physics::initial_pneumatics_state(pneumatics_model_, state_.pos);
  pneumatics_scratch_ = physics::make_pneumatics_scratch(pneumatics_model_);
  external_force_.assign(static_cast<std::size_t>(model_.voxel_count), physics::Vec3::Zero());
  score_ = task.start_unit(unit, model_);

  const TaskConfig& tc = config.task;
  // §5 step 8, within the limits of physics/work_limits.hpp (WorkLimitError before any step).
  const physics::EvaluationWork work =
      physics::evaluation_work(model_.dt_f, tc.control_rate, tc.eval_seconds);
  steps_per_frame_ = work.steps_per_frame;
  frames_ = work.frames;
  // First sensor reading (§3.7): config value for every chamber, in bar.
  initial_sensor_bar_ =
      static_cast<float>(config.pneumatics.initial_sensor_pressure / physics::kPascalPerBar);
}

Simulation::~Simulation() = default;

void Simulation::task_inputs(std::span<float> inputs) {
  if (score_ && !inputs.empty()) score_->controller_inputs(model_, state_, inputs);
}

UnitFitness Simulation::score_so_far() const {
  UnitFitness f;
  if (score_ && status_ == EvalStatus::ok) f = score_->so_far(model_, state_);
  f.status = status_;
  f.values.resize(task_.component_names().size(), 0.0);  // a stopped unit scores 0 (§7.1)
  return f;
}

void Simulation::steer(double direction_deg) {
  if (!task_.steerable())
    throw std::logic_error(std::string("the ") + to_string(task_.kind()) +
                           " task has no target direction to steer");
  if (!(direction_deg >= -180.0 && direction_deg <= 180.0))
    throw std::invalid_argument("steering direction must be within [-180, 180] degrees");
  if (score_) score_->steer(direction_deg);
}

float Simulation::sensor_pressure_bar(int chamber) const {
  return frame_ == 0 ? initial_sensor_bar_ : pneumatics_.pressure[chamber];  // §3.7
}

EvalStatus Simulation::step(std::span<const float> valve_commands) {
  if (!running())
    throw std::logic_error("Simulation::step: the simulation has ended (status " +
                           std::string(to_string(status_)) + ", frame " + std::to_string(frame_) +
                           " of " + std::to_string(frames_) + ")");
  if (static_cast<int>(valve_commands.size()) != pneumatics_model_.valve_count)
    throw std::invalid_argument("Simulation::step: " + std::to_string(valve_commands.size()) +
                                " valve commands for " + std::to_string(chambers()) +
                                " chambers (2 per chamber: inlet, outlet)");
  physics::set_valve_commands(pneumatics_, valve_commands);
  // 3. Kill checks at the start of the frame (§2.15).
  if (physics::flipped(model_, state_)) {
    status_ = EvalStatus::killed_flipped;
    return status_;
  }
  if (physics::exploded(model_, state_)) {
    status_ = EvalStatus::killed_exploded;
    return status_;
  }
  // 4. The task's observation of the frame.
  score_->observe(frame_, model_, state_);
  // 5. Physics: pneumatics before every step (§3.6).
  for (int s = 0; s < steps_per_frame_; ++s) {
    physics::pneumatics_update(pneumatics_model_, pneumatics_, pneumatics_scratch_, state_.pos,
                               external_force_);
    const physics::StepStatus st = physics::step(model_, state_, scratch_, external_force_);
    ++steps_;
    if (st != physics::StepStatus::ok) {
      status_ = EvalStatus::diverged;
      message_ = "physics step failed (link strain > 100 or non-finite state)";
      return status_;
    }
  }
  ++frame_;
  return status_;
}

void Simulation::stop(EvalStatus status, std::string message) {
  if (status == EvalStatus::ok) throw std::invalid_argument("Simulation::stop: status ok");
  status_ = status;
  message_ = std::move(message);
}

EvalResult Simulation::finish() {
  EvalResult result;
  result.unit = unit_;
  result.voxels = model_.voxel_count;
  result.chambers = pneumatics_model_.chamber_count;
  result.status = status_;
  result.message = message_;
  if (status_ == EvalStatus::invalid_body) return result;  // never simulated
  result.steps = steps_;
  result.sim_seconds = state_.time;
  UnitFitness unit_fitness;
  if (status_ == EvalStatus::ok) {
    unit_fitness = score_->finish(model_, state_);
    result.fitness = unit_fitness.fitness;
  }  // killed / diverged / timeout: fitness and components 0 (§7.1, §7.2 "Killed")
  unit_fitness.values.resize(task_.component_names().size(), 0.0);
  result.components.push_back(std::move(unit_fitness));
  return result;
}

}  // namespace softevo::worker
