// The one evaluation entry (docs/model.md §5). See evaluate.hpp.
#include "worker/evaluate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "evo/development.hpp"
#include "physics/pneumatics.hpp"
#include "worker/controller.hpp"
#include "worker/simulation.hpp"

namespace softevo::worker {
namespace {

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The main loop: the stepping simulation driven by the robot's own controller. Throws
// std::invalid_argument for a body, controller or config that cannot be simulated (evaluate()
// turns it into status failed).
EvalResult simulate(const Config& config, const tasks::Task& task, const BodyPlan& plan,
                    const ControllerSpec& controller, int unit, const EvaluateOptions& opts) {
  Simulation sim(config, task, plan, unit, opts.simd, opts.ids);
  if (sim.status() == EvalStatus::invalid_body) return sim.finish();
  ElmanController brain(controller, config.task.control_rate, opts.ablate_oscillator,
                        opts.ablate_sensors);
  brain.check_chambers(sim.chambers());

  std::vector<float> task_inputs(static_cast<std::size_t>(task.controller_inputs()), 0.0f);
  std::vector<float> sensor_bar(static_cast<std::size_t>(sim.chambers()), 0.0f);
  std::vector<float> commands(static_cast<std::size_t>(sim.valve_count()), 1.0f);
  std::vector<double> pressures_pa(static_cast<std::size_t>(sim.chambers()), 0.0);
  auto emit = [&](int frame) {
    if (!opts.on_frame) return;
    for (int q = 0; q < sim.chambers(); ++q)
      pressures_pa[q] = physics::chamber_pressure_pa(sim.pneumatics(), q);
    TraceFrame tf;
    tf.frame = frame;
    tf.time = sim.time();
    tf.positions = sim.state().pos;
    tf.orientations = sim.state().orient;
    tf.pressures = pressures_pa;
    tf.valve_commands = commands;
    tf.inputs = brain.inputs();
    opts.on_frame(tf);
  };
  if (opts.on_start) {
    TraceHeader h;
    h.model = &sim.model();
    h.chambers = sim.chambers();
    h.frames = sim.frames();
    h.steps_per_frame = sim.steps_per_frame();
    opts.on_start(h);
  }

  while (sim.running()) {
    // 1-2. What the controller senses -> valve commands.
    sim.task_inputs(task_inputs);
    for (int q = 0; q < sim.chambers(); ++q) sensor_bar[q] = sim.sensor_pressure_bar(q);
    brain.act(task_inputs, sensor_bar, commands);
    emit(sim.frame());
    // 3-5. Kill checks, the task's observation, the physics steps.
    if (sim.step(commands) != EvalStatus::ok) break;
    // 6. Deadline and abandon request.
    if (opts.deadline && Clock::now() > *opts.deadline)
      sim.stop(
          EvalStatus::timeout,
          "evaluation exceeded its wall-clock deadline (run.eval_timeout_seconds, softevo eval "
          "--timeout)");
    else if (opts.abandon && opts.abandon())
      sim.stop(EvalStatus::timeout, "evaluation abandoned: the run is stopping");
  }
  if (sim.status() == EvalStatus::ok) emit(sim.frames());
  return sim.finish();
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
  // Saturated: beyond the clock's range (about 9.2e9 s of nanoseconds from now) the sum would
  // overflow into the past and every evaluation would time out at once. Half the room left is
  // the threshold, far from where the double's rounding could matter (still ~146 years).
  const Clock::time_point now = Clock::now();
  const double room = std::chrono::duration<double>(Clock::time_point::max() - now).count();
  if (seconds >= 0.5 * room) return Clock::time_point::max();
  return now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

void finalize_unit_result(const tasks::Task& task, EvalResult& result) {
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
  finalize_unit_result(task, result);
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

RobotConfigSource robot_config_source(const RobotFile& robot, const RobotEvalSettings& settings) {
  if (!settings.config_path.empty()) return RobotConfigSource::config_file;
  if (settings.config_text) return RobotConfigSource::config_text;
  if (robot.evaluation) return RobotConfigSource::robot_file;
  return RobotConfigSource::built_in;
}

std::string describe_config_source(const RobotFile& robot, const RobotEvalSettings& settings) {
  std::string text;
  switch (robot_config_source(robot, settings)) {
    case RobotConfigSource::config_file:
      text = "--config " + settings.config_path;
      break;
    case RobotConfigSource::config_text:
      text = "the given config " + settings.source_name;
      break;
    case RobotConfigSource::robot_file: {
      const RobotEvaluation& e = *robot.evaluation;
      text = "the robot file's run config (hash " + e.config_hash;
      if (!e.run.empty()) text += ", from " + e.run;
      if (e.generation) text += " generation " + std::to_string(*e.generation);
      if (e.id) text += " id " + std::to_string(*e.id);
      text += ")";
      break;
    }
    case RobotConfigSource::built_in:
      text = "the built-in thesis defaults (the robot file has no evaluation block)";
      break;
  }
  if (!settings.overrides.empty())
    text += " with " + std::to_string(settings.overrides.size()) + " --set override" +
            (settings.overrides.size() == 1 ? "" : "s");
  return text;
}

Config robot_eval_config(const RobotFile& robot, const RobotEvalSettings& settings) {
  const ControllerSpec& controller = robot.controller;
  // Seconds and direction as overrides, so that they pass the config's range checks (a NaN or
  // 1e308 is refused, naming the key); %.17g gives the double back exactly.
  std::vector<std::string> overrides = settings.overrides;
  auto exact = [](double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return std::string(text);
  };
  if (settings.seconds) overrides.push_back("task.eval_seconds=" + exact(*settings.seconds));
  if (settings.direction)
    overrides.push_back("task.directions=[" + exact(*settings.direction) + "]");
  if (!settings.task.empty()) overrides.push_back("task.kind=" + settings.task);
  const RobotConfigSource source = robot_config_source(robot, settings);
  const bool built_in = source == RobotConfigSource::built_in;
  if (settings.task.empty() && built_in)
    overrides.push_back(std::string("task.kind=") +
                        to_string(tasks::default_task_for(controller.task_inputs())));
  Config config;
  switch (source) {
    case RobotConfigSource::config_file:
      config = load_config(settings.config_path, overrides);
      break;
    case RobotConfigSource::config_text:
      config = parse_config(*settings.config_text, settings.source_name, overrides);
      break;
    case RobotConfigSource::robot_file:
      config = parse_config(robot.evaluation->config, "evaluation.config", overrides);
      break;
    case RobotConfigSource::built_in:
      config = parse_config("", "<built-in defaults>", overrides);
      break;
  }
  if (built_in)
    config.task.control = controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
  if (settings.integrator) config.physics.integrator = *settings.integrator;
  return config;
}

BuiltRobot build_robot(const Config& config, const evo::Genome& genome, const tasks::Task& task) {
  BuiltRobot robot;
  evo::DevelopedBody developed = evo::develop_body(genome.cppn, config.body);
  robot.valid = developed.valid;
  robot.actuatable = developed.actuatable;
  robot.body = std::move(developed.plan);
  robot.body.materials = material_table(config.physics);
  robot.body.voxel_size = config.physics.voxel_size;
  robot.controller = evo::to_controller_spec(genome, config, task.controller_inputs());
  return robot;
}

RobotFile robot_file_of(const Config& config, const evo::Genome& genome, const std::string& name) {
  BuiltRobot robot = build_robot(config, genome, *tasks::make_task(config));
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
  unit_options.ids = {request.generation, request.genome_id};
  EvalResult result;
  try {
    const evo::Genome genome = evo::decode_genome(request.genome);
    const BuiltRobot robot = build_robot(config, genome, task);
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
