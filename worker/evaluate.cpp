// The one evaluation entry (docs/model.md §5). See evaluate.hpp.
#include "worker/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "evo/development.hpp"
#include "physics/observables.hpp"
#include "physics/pneumatics.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"
#include "physics/work_limits.hpp"
#include "worker/controller.hpp"

namespace softevo::worker {
namespace {

constexpr int kOscillatorInputs = 2;  // sin, cos (§4.1)
constexpr int kMaxSensorValues = 10;  // §4.1: cap after the oscillator inputs

EvalStatus status_of(physics::StepStatus s) {
  return s == physics::StepStatus::ok ? EvalStatus::ok : EvalStatus::diverged;
}

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The main loop; throws std::invalid_argument for a body, controller or config that cannot be
// simulated (evaluate() turns it into status failed).
EvalResult simulate(const Config& config, const tasks::Task& task, const BodyPlan& plan,
                    const ControllerSpec& controller, int unit, const EvaluateOptions& opts) {
  const TaskConfig& tc = config.task;
  if (unit < 0 || unit >= task.units())
    throw std::invalid_argument("work unit " + std::to_string(unit) + " outside the " +
                                std::to_string(task.units()) + " units of task " +
                                to_string(task.kind()));
  if (!(tc.control_rate > 0.0) || !(tc.eval_seconds >= 0.0))
    throw std::invalid_argument("task.control_rate must be > 0 and task.eval_seconds >= 0");

  EvalResult result;
  result.unit = unit;

  // ---- setup (§5 steps 1-8) -------------------------------------------------------------------
  physics::BuildOptions build_options;
  build_options.simd = opts.simd;
  const physics::Model model = physics::build_model(plan, config.physics, build_options);
  result.voxels = model.voxel_count;
  result.chambers = plan.chamber_count();
  // Before the pneumatics: a model without voxels has no time step, and its error would hide
  // the real cause.
  if (model.voxel_count == 0) {
    result.status = EvalStatus::invalid_body;
    result.message = result.chambers > 0
                         ? "body has only chamber cells, no structural voxel (material 1..10)"
                         : "body has no cells (every cell is empty)";
    return result;
  }
  // §5 step 8, within the limits of physics/work_limits.hpp (else status failed, before any
  // step).
  const physics::EvaluationWork work =
      physics::evaluation_work(model.dt_f, tc.control_rate, tc.eval_seconds);
  const physics::PneumaticsModel pm = physics::build_pneumatics(plan, model, config.pneumatics);
  result.chambers = pm.chamber_count;
  if (pm.chamber_count == 0) {
    result.status = EvalStatus::invalid_body;
    result.message = "body has no chamber (not actuatable)";
    return result;
  }
  physics::State state = physics::initial_state(model);
  physics::Scratch scratch = physics::make_scratch(model);
  physics::PneumaticsState ps = physics::initial_pneumatics_state(pm, state.pos);
  physics::PneumaticsScratch pscratch = physics::make_pneumatics_scratch(pm);
  std::vector<physics::Vec3> external_force(static_cast<std::size_t>(model.voxel_count),
                                            physics::Vec3::Zero());

  const ElmanWeights weights = make_elman_weights(controller);
  ElmanState brain = initial_elman_state(weights);
  std::vector<float> inputs(static_cast<std::size_t>(weights.inputs), 0.0f);
  std::vector<float> outputs(static_cast<std::size_t>(weights.outputs), 0.0f);
  std::vector<float> commands(static_cast<std::size_t>(pm.valve_count), 1.0f);
  std::vector<double> pressures_pa(static_cast<std::size_t>(pm.chamber_count), 0.0);
  if (2 * pm.chamber_count > weights.outputs)
    throw std::invalid_argument(std::to_string(pm.chamber_count) + " chambers need " +
                                std::to_string(2 * pm.chamber_count) +
                                " controller outputs, controller has " +
                                std::to_string(weights.outputs));
  const std::unique_ptr<tasks::UnitScore> score = task.start_unit(unit, model);
  std::vector<float> task_inputs(static_cast<std::size_t>(task.controller_inputs()), 0.0f);
  const auto fed_task_inputs =
      static_cast<std::size_t>(std::min(task.controller_inputs(), controller.task_inputs()));

  const int steps_per_frame = work.steps_per_frame;
  const int frames = work.frames;
  // First sensor reading (§3.7): config value for every chamber, in bar.
  const float initial_sensor_bar =
      static_cast<float>(config.pneumatics.initial_sensor_pressure / physics::kPascalPerBar);

  auto emit = [&](int frame) {
    if (!opts.on_frame) return;
    for (int q = 0; q < pm.chamber_count; ++q)
      pressures_pa[q] = physics::chamber_pressure_pa(ps, q);
    TraceFrame tf;
    tf.frame = frame;
    tf.time = state.time;
    tf.positions = state.pos;
    tf.orientations = state.orient;
    tf.pressures = pressures_pa;
    tf.valve_commands = commands;
    tf.inputs = inputs;
    opts.on_frame(tf);
  };
  if (opts.on_start) {
    TraceHeader h;
    h.model = &model;
    h.chambers = pm.chamber_count;
    h.frames = frames;
    h.steps_per_frame = steps_per_frame;
    opts.on_start(h);
  }

  const int sensor_slots = weights.inputs - kOscillatorInputs;
  for (int frame = 0; frame < frames; ++frame) {
    // 1. Inputs [sin, cos, (task inputs), (pressures)], the sensor part capped at 10 values and
    //    zero-padded (§4.1).
    advance_oscillator(weights, brain, tc.control_rate);  // §4.2: before the inputs are read
    inputs[0] = opts.ablate_oscillator ? 0.0f : static_cast<float>(std::sin(brain.phase));
    inputs[1] = opts.ablate_oscillator ? 0.0f : static_cast<float>(std::cos(brain.phase));
    std::fill(inputs.begin() + kOscillatorInputs, inputs.end(), 0.0f);
    int sensor = 0;
    auto push_sensor = [&](float value) {
      if (sensor < kMaxSensorValues && sensor < sensor_slots)
        inputs[kOscillatorInputs + sensor] = value;
      ++sensor;
    };
    if (!task_inputs.empty()) score->controller_inputs(model, state, task_inputs);
    for (std::size_t i = 0; i < fed_task_inputs; ++i) push_sensor(task_inputs[i]);
    for (int i = static_cast<int>(fed_task_inputs); i < controller.task_inputs(); ++i)
      push_sensor(0.0f);
    if (controller.closed_loop) {
      for (int q = 0; q < pm.chamber_count; ++q) {
        const float p_bar = frame == 0 ? initial_sensor_bar : ps.pressure[q];  // §3.7
        push_sensor(opts.ablate_sensors ? 0.0f : physics::pressure_sensor_input(p_bar));
      }
    }
    // 2. Network -> valve commands (y + 1)/2, output 2q inlet / 2q+1 outlet of chamber q (§4.5).
    elman_forward(weights, brain, inputs, outputs);
    for (int k = 0; k < pm.valve_count; ++k) commands[k] = (outputs[k] + 1.0f) / 2.0f;
    physics::set_valve_commands(ps, commands);
    emit(frame);
    // 3. Kill checks at the start of the frame (§2.15).
    if (physics::flipped(model, state)) {
      result.status = EvalStatus::killed_flipped;
      break;
    }
    if (physics::exploded(model, state)) {
      result.status = EvalStatus::killed_exploded;
      break;
    }
    // 4. The task's observation of the frame.
    score->observe(frame, model, state);
    // 5. Physics: pneumatics before every step (§3.6).
    for (int s = 0; s < steps_per_frame && result.status == EvalStatus::ok; ++s) {
      physics::pneumatics_update(pm, ps, pscratch, state.pos, external_force);
      result.status = status_of(physics::step(model, state, scratch, external_force));
      ++result.steps;
    }
    if (result.status != EvalStatus::ok) {
      result.message = "physics step failed (link strain > 100 or non-finite state)";
      break;
    }
    // 6. Deadline and abandon request.
    if (opts.deadline && Clock::now() > *opts.deadline) {
      result.status = EvalStatus::timeout;
      result.message =
          "evaluation exceeded its wall-clock deadline (run.eval_timeout_seconds, softevo eval "
          "--timeout)";
      break;
    }
    if (opts.abandon && opts.abandon()) {
      result.status = EvalStatus::timeout;
      result.message = "evaluation abandoned: the run is stopping";
      break;
    }
  }
  result.sim_seconds = state.time;

  UnitFitness unit_fitness;
  if (result.status == EvalStatus::ok) {
    emit(frames);
    unit_fitness = score->finish(model, state);
    result.fitness = unit_fitness.fitness;
  }  // killed / diverged / timeout: fitness and components 0 (§7.1, §7.2 "Killed")
  unit_fitness.values.resize(task.component_names().size(), 0.0);
  result.components.push_back(std::move(unit_fitness));
  return result;
}

EvalResult failed(int unit, EvalStatus status, std::string message) {
  EvalResult r;
  r.unit = unit;
  r.status = status;
  r.message = std::move(message);
  return r;
}

}  // namespace

std::optional<Clock::time_point> deadline_after(double seconds) {
  if (!(seconds > 0.0)) return std::nullopt;
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

EvalResult evaluate(const Config& config, const tasks::Task& task, const BodyPlan& body,
                    const ControllerSpec& controller, int unit, const EvaluateOptions& options) {
  const auto start = Clock::now();
  EvalResult result;
  try {
    result = simulate(config, task, body, controller, unit, options);
  } catch (const std::exception& e) {
    result = failed(unit, EvalStatus::failed, e.what());
  }
  // A non-finite fitness is numerical trouble that escaped the physics' own checks.
  if (result.status == EvalStatus::ok && !std::isfinite(result.fitness)) {
    result.status = EvalStatus::diverged;
    result.message = "non-finite fitness";
  }
  if (result.status != EvalStatus::ok) result.fitness = 0.0;  // scored like a killed robot
  if (result.components.empty())
    result.components.emplace_back().values.resize(task.component_names().size(), 0.0);
  result.components.front().fitness = result.fitness;
  result.components.front().status = result.status;
  result.wall_seconds = seconds_since(start);
  return result;
}

EvalResult evaluate_all_units(const Config& config, const tasks::Task& task, const BodyPlan& body,
                              const ControllerSpec& controller, const EvaluateOptions& options) {
  std::vector<EvalResult> units;
  for (int u = 0; u < task.units(); ++u)
    units.push_back(evaluate(config, task, body, controller, u, options));
  return tasks::combine_units(task, units);
}

BuiltRobot build_robot(const Config& config, const evo::Genome& genome) {
  BuiltRobot robot;
  evo::DevelopedBody developed = evo::develop_body(genome.cppn, config.body);
  robot.valid = developed.valid;
  robot.actuatable = developed.actuatable;
  robot.body = std::move(developed.plan);
  robot.body.materials = material_table(config.physics);
  robot.body.voxel_size = config.physics.voxel_size;
  robot.controller =
      evo::to_controller_spec(genome, config, tasks::make_task(config)->controller_inputs());
  return robot;
}

RobotFile robot_file_of(const Config& config, const evo::Genome& genome, const std::string& name) {
  BuiltRobot robot = build_robot(config, genome);
  RobotFile file;
  file.name = name;
  file.body = std::move(robot.body);
  file.controller = std::move(robot.controller);
  file.genome = evo::to_genome_record(genome, config);
  return file;
}

EvalResult evaluate(const Config& config, const tasks::Task& task, std::uint64_t config_hash,
                    const EvalRequest& request, const EvaluateOptions& options) {
  if (request.config_hash != config_hash)
    throw ConfigMismatch("work unit (generation " + std::to_string(request.generation) +
                         ", genome " + std::to_string(request.genome_id) + ") has config hash " +
                         hash_hex(request.config_hash) + ", this worker has " +
                         hash_hex(config_hash) + ": master and worker run different configs");
  const auto start = Clock::now();
  EvaluateOptions unit_options = options;
  if (!unit_options.deadline)
    unit_options.deadline = deadline_after(config.run.eval_timeout_seconds);
  EvalResult result;
  try {
    const evo::Genome genome = evo::decode_genome(request.genome);
    const BuiltRobot robot = build_robot(config, genome);
    if (!robot.valid || !robot.actuatable) {
      result = failed(
          request.unit, EvalStatus::invalid_body,
          robot.valid ? "body has no chamber (not actuatable)" : "body has no structural voxel");
      result.components.emplace_back().values.resize(task.component_names().size(), 0.0);
      result.components.front().status = result.status;
    } else if (unit_options.evaluate_robot) {
      result = unit_options.evaluate_robot(config, task, robot, request, unit_options);
    } else {
      result = evaluate(config, task, robot.body, robot.controller, request.unit, unit_options);
    }
  } catch (const std::exception& e) {  // undecodable genome, bad controller shape
    result = failed(request.unit, EvalStatus::failed, e.what());
  }
  result.genome_id = request.genome_id;
  result.unit = request.unit;
  if (result.status != EvalStatus::ok) result.fitness = 0.0;
  result.wall_seconds = seconds_since(start);
  return result;
}

}  // namespace softevo::worker
