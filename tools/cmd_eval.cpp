// `softevo eval ROBOT.json [--task gait|directed|rotate] [--integrator pneuvox|symplectic]
//  [--seconds S] [--ablate oscillator|sensors] [--json] [--trace FILE.h5] [--config FILE]
//  [--set section.key=value ...] [--timeout S] [--force]`
//
// Evaluates one robot file (docs/model.md §10) and prints fitness, the task's named components
// per work unit, status, simulated time, steps, voxel and chamber counts and wall/CPU time.
// Without --config the robot file's evaluation block (the config of the run it was exported
// from) is used, and the archived fitness is compared bit for bit; a file without one gets the
// built-in thesis defaults of softevo::Config, with task.control taken from the robot's
// controller. --set overrides apply to either; the output says which config was used. The task:
// --task, else the --config file's, else the one the controller's inputs fit
// (tasks::default_task_for: directed for a directed controller, else gait). Fitness is printed with
// full double precision (the shortest text that reads back as the same double). --direction D
// evaluates the target direction D alone (task.directions = [D]).
//
// --seconds, --direction and --timeout set task.eval_seconds, task.directions and
// run.eval_timeout_seconds and get their range checks (a bad value is a config error naming the
// key). The work is bounded twice: by the step limits of physics/work_limits.hpp (status failed)
// and by the wall-clock deadline --timeout (default run.eval_timeout_seconds, 600 s; 0 = none;
// status timeout), which covers every unit of the command.
//
// --trace FILE.h5 records one frame per control frame (60 Hz) plus the state after the last
// frame: format softevo.trace/1, docs/trace.md (io/trace.hpp). The trace records the first work
// unit of the task (directed: the first direction, or the one of --direction). It is held in
// memory until the end, so a trace beyond motion::kMaxTraceBytes is refused up front; an existing
// FILE is replaced only with --force (docs/output-files.md).
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/printable.hpp"
#include "common/robot.hpp"
#include "common/round_trip.hpp"
#include "common/safe_write.hpp"
#include "motion/trace_recorder.hpp"
#include "physics/model.hpp"
#include "tasks/task.hpp"
#include "tools/commands.hpp"
#include "worker/evaluate.hpp"
#include "worker/robot_eval_ids.hpp"

namespace softevo::cli {
namespace {

struct EvalArgs {
  std::string robot;
  std::string task;
  std::string integrator;
  std::optional<double> seconds;  // task.eval_seconds (none = the config's)
  std::vector<std::string> ablate;
  bool json = false;
  std::string trace;
  std::string config_file;
  std::vector<std::string> overrides;
  std::optional<double> direction;  // [deg] the one target direction (none = the config's)
  std::optional<double> timeout;    // [s] run.eval_timeout_seconds (none = the config's)
  bool force = false;               // replace an existing --trace file
  std::string simd = "best";
};

// JSON has no NaN or infinity: null.
nlohmann::ordered_json json_number(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json();
}

int run_eval(const EvalArgs& a) {
  const RobotFile robot = read_robot_file(a.robot);
  // --seconds, --direction and --timeout go in as text, so that the config's range checks see
  // what was typed (nan, 1e999); the task stays the last override (robot_eval_config).
  worker::RobotEvalSettings settings;
  settings.config_path = a.config_file;
  settings.overrides = a.overrides;
  if (a.seconds) settings.overrides.push_back("task.eval_seconds=" + toml_number(*a.seconds));
  if (a.direction)
    settings.overrides.push_back("task.directions=[" + toml_number(*a.direction) + "]");
  if (a.timeout)
    settings.overrides.push_back("run.eval_timeout_seconds=" + toml_number(*a.timeout));
  settings.task = a.task;
  if (!a.integrator.empty())
    settings.integrator = parse_choice<Integrator>(a.integrator, "--integrator");
  const Config config = worker::robot_eval_config(robot, settings);
  const std::string config_source = worker::describe_config_source(robot, settings);
  const Overwrite overwrite = a.force ? Overwrite::replace : Overwrite::refuse;
  if (!a.trace.empty()) {
    check_output_target(a.trace, overwrite);  // before minutes of simulation, not after
    motion::check_trace_memory(a.trace, config, robot.body);
  }
  const std::unique_ptr<tasks::Task> task = tasks::make_task(config);
  const std::vector<tasks::ComponentName> names = task->component_names();

  worker::EvaluateOptions opts;
  opts.deadline = worker::deadline_after(config.run.eval_timeout_seconds);
  opts.ids = worker::robot_eval_ids(robot, settings);  // the ground its run gave it
  opts.simd = physics::parse_simd(a.simd).value();     // checked by the option's IsMember
  if (!physics::simd_supported(opts.simd))
    throw std::invalid_argument("--simd " + a.simd + ": not supported by this CPU or build");
  const physics::Simd simd_used = physics::resolve_simd(opts.simd);  // = the Model's width
  for (const std::string& what : a.ablate) {
    if (what == "oscillator") opts.ablate_oscillator = true;
    if (what == "sensors") opts.ablate_sensors = true;
  }

  motion::TraceRecorder trace;
  if (!a.trace.empty()) trace.attach(opts);

  std::timespec cpu0{}, cpu1{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu0);
  // A trace records one work unit: the first.
  const EvalResult result =
      a.trace.empty()
          ? worker::evaluate_all_units(config, *task, robot.body, robot.controller, opts)
          : tasks::combine_units(*task, std::vector<EvalResult>{worker::evaluate(
                                            config, *task, robot.body, robot.controller, 0, opts)});
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu1);
  const double cpu_seconds = static_cast<double>(cpu1.tv_sec - cpu0.tv_sec) +
                             1e-9 * static_cast<double>(cpu1.tv_nsec - cpu0.tv_nsec);

  // The trace names its target direction when the task has one (a component of that name): the
  // first configured one, the direction of the traced unit.
  bool has_direction = false;
  for (const tasks::ComponentName& n : names) has_direction |= n.name == "direction_deg";
  if (!a.trace.empty() && trace.started())
    trace.write(
        a.trace, robot, result, config.task.control_rate,
        has_direction ? std::optional<double>(config.task.directions.front()) : std::nullopt,
        overwrite);

  const std::string ablation = opts.ablate_oscillator && opts.ablate_sensors ? "oscillator+sensors"
                               : opts.ablate_oscillator                      ? "oscillator"
                               : opts.ablate_sensors                         ? "sensors"
                                                                             : "none";
  // The fitness the run archived, when the file carries its run's settings unchanged: a
  // re-evaluation must give it bit for bit (anything else is a bug or another config).
  std::optional<double> archived;
  if (robot.evaluation && robot.evaluation->fitness &&
      worker::robot_config_source(robot, settings) == worker::RobotConfigSource::robot_file &&
      settings.overrides.empty() && a.task.empty() && a.integrator.empty() && a.ablate.empty() &&
      a.trace.empty())
    archived = robot.evaluation->fitness;
  if (a.json) {
    nlohmann::ordered_json j;
    j["robot"] = robot.name.empty() ? a.robot : robot.name;
    j["task"] = to_string(config.task.kind);
    j["integrator"] = to_string(config.physics.integrator);
    j["ablate"] = ablation;
    j["fitness"] = json_number(result.fitness);
    j["status"] = to_string(result.status);
    j["killed"] = is_killed(result.status);
    j["config_source"] = softevo::to_string(worker::robot_config_source(robot, settings));
    j["config"] = config_source;
    j["config_hash"] = hash_hex(config_hash(config));
    if (archived) {
      j["archived_fitness"] = json_number(*archived);
      j["reproduces_archived_fitness"] = same_bits(*archived, result.fitness);
    }
    nlohmann::ordered_json names_json = nlohmann::ordered_json::array();
    for (const tasks::ComponentName& n : names)
      names_json.push_back({{"name", n.name}, {"unit", n.unit}});
    j["component_names"] = names_json;
    nlohmann::ordered_json units = nlohmann::ordered_json::array();
    for (const UnitFitness& u : result.components) {
      // The archive's component columns, by the same names (docs/archive.md): fitness, the
      // task's named components, status.
      nlohmann::ordered_json c;
      c["fitness"] = json_number(u.fitness);
      for (std::size_t i = 0; i < names.size() && i < u.values.size(); ++i)
        c[names[i].name] = json_number(u.values[i]);
      c["status"] = to_string(u.status);
      units.push_back(c);
    }
    j["components"] = units;
    j["sim_seconds"] = json_number(result.sim_seconds);
    j["steps"] = result.steps;
    j["voxels"] = result.voxels;
    j["chambers"] = result.chambers;
    j["wall_seconds"] = json_number(result.wall_seconds);
    j["cpu_seconds"] = json_number(cpu_seconds);
    j["simd"] = softevo::to_string(simd_used);
    j["message"] = result.message;
    std::printf("%s\n", j.dump().c_str());
  } else {
    // The name comes from the file: shown escaped (it may hold terminal control sequences).
    std::printf("robot        %s\n", printable(robot.name.empty() ? a.robot : robot.name).c_str());
    std::printf("task         %s (%s loop%s), integrator %s, ablate %s\n",
                to_string(config.task.kind), robot.controller.closed_loop ? "closed" : "open",
                robot.controller.directed ? ", directed controller" : "",
                to_string(config.physics.integrator), ablation.c_str());
    std::printf("config       %s\n", printable(config_source).c_str());
    std::printf("fitness      %s\n", round_trip(result.fitness).c_str());
    if (archived)
      std::printf("archived     %s (%s)\n", round_trip(*archived).c_str(),
                  same_bits(*archived, result.fitness) ? "reproduced bit for bit"
                                                       : "DIFFERS from this evaluation");
    std::printf("status       %s%s%s\n", to_string(result.status),
                result.message.empty() ? "" : ": ", result.message.c_str());
    for (std::size_t k = 0; k < result.components.size(); ++k) {
      const UnitFitness& u = result.components[k];
      std::printf("  unit %zu: F %s", k, round_trip(u.fitness).c_str());
      for (std::size_t i = 0; i < names.size() && i < u.values.size(); ++i)
        std::printf("  %s %.10g%s%s", names[i].name.c_str(), u.values[i],
                    names[i].unit.empty() ? "" : " ", names[i].unit.c_str());
      std::printf("  %s\n", to_string(u.status));
    }
    std::printf("simulated    %.6f s in %lld steps\n", result.sim_seconds,
                static_cast<long long>(result.steps));
    std::printf("body         %d voxels, %d chambers\n", result.voxels, result.chambers);
    std::printf("time         %.3f s wall, %.3f s CPU (physics SIMD width %s)\n",
                result.wall_seconds, cpu_seconds, softevo::to_string(simd_used));
    if (!a.trace.empty())
      std::printf("trace        %s (%d frames)\n", a.trace.c_str(), trace.frames());
  }
  return result.status == EvalStatus::failed ? kExitUsage : kExitOk;
}

}  // namespace

void register_eval(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("eval", "evaluate a robot file (fitness, components, status)");
  auto a = std::make_shared<EvalArgs>();
  cmd->add_option("ROBOT", a->robot, "robot file (softevo.robot/1 JSON)")->required();
  cmd->add_option("--task", a->task,
                  "the task (default: the --config file's, else the one the controller's inputs "
                  "fit)")
      ->check(CLI::IsMember(choice_names<TaskKind>()));
  cmd->add_option("--integrator", a->integrator, "physics integrator")
      ->check(CLI::IsMember(choice_names<Integrator>()));
  add_seconds_option(*cmd, a->seconds, "simulated seconds");
  cmd->add_option("--ablate", a->ablate, "feed zeros to the oscillator or the pressure sensors")
      ->check(CLI::IsMember({"oscillator", "sensors"}));
  // Numbers, as render's and view's --direction (issue 39: these took any text); the range is
  // the config's check (task.directions, run.eval_timeout_seconds), which names the key.
  cmd->add_option("--direction", a->direction,
                  "directed task: evaluate only this target direction [deg, counter-clockwise] "
                  "(task.directions)");
  cmd->add_option("--timeout", a->timeout,
                  "wall-clock limit of the evaluation [s], status timeout beyond it: sets "
                  "run.eval_timeout_seconds (default 600; 0 = no limit)");
  cmd->add_flag("--force", a->force, "replace an existing --trace file");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->add_option("--trace", a->trace, "record voxel poses, pressures and valves (HDF5)");
  cmd->add_option("--config", a->config_file,
                  "TOML config (default: the robot file's run config, else the built-in thesis "
                  "values)");
  cmd->add_option("--set", a->overrides, "override a config key: section.key=value");
  cmd->add_option("--simd", a->simd,
                  "SIMD width of the physics: best (default), sse2, avx2 or avx512 (the fitness "
                  "is bit-identical at every width; only the speed differs)")
      ->check(CLI::IsMember(physics::simd_names()));
  cmd->callback([&exit_code, a] { exit_code = run_eval(*a); });
}

}  // namespace softevo::cli
