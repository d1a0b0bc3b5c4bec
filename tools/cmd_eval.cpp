// `softevo eval ROBOT.json [--task gait|directed] [--integrator pneuvox|symplectic]
//  [--seconds S] [--ablate oscillator|sensors] [--json] [--trace FILE.h5] [--config FILE]
//  [--set section.key=value ...]`
//
// Evaluates one robot file (SPEC.md section 9) and prints fitness, its components (D, L, delta,
// P per direction), status, simulated time, steps, voxel and chamber counts and wall/CPU time.
// Without --config the built-in thesis defaults of softevo::Config are used, with task.control
// taken from the robot's controller. Default task: directed if the controller is directed,
// else gait. Fitness is printed with full double precision (%.17g).
//
// --trace FILE.h5 records one frame per control frame (60 Hz) plus the state after the last
// frame: format softevo.trace/1, docs/trace.md (io/trace.hpp). With the directed task the trace
// records the first direction (or the one of --direction).
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/robot.hpp"
#include "io/trace.hpp"
#include "physics/model.hpp"
#include "tools/commands.hpp"
#include "worker/evaluate_robot.hpp"
#include "worker/fitness.hpp"

namespace softevo::cli {
namespace {

struct EvalArgs {
  std::string robot;
  std::string task;
  std::string integrator;
  double seconds = 0.0;
  std::vector<std::string> ablate;
  bool json = false;
  std::string trace;
  std::string config_file;
  std::vector<std::string> overrides;
  double direction = 0.0;
  bool direction_set = false;
  std::string simd = "best";
};

// Frames buffered in memory, written once at the end (a 10 s trace of an 800-voxel robot is
// about 35 MB of doubles).
struct TraceBuffer {
  const physics::Model* model = nullptr;
  int chambers = 0;
  int steps_per_frame = 0;
  std::vector<double> positions, orientations, pressures, time;
  std::vector<float> valves;
  std::vector<int> voxel_cells, voxel_material;
  double dt = 0.0, voxel_size = 0.0;
  int frames = 0;
};

void write_trace(const std::string& path, const TraceBuffer& t, const RobotFile& robot,
                 const EvalResult& result, double control_rate, const double* direction_deg) {
  io::Trace trace;
  trace.frames = t.frames;
  trace.voxels = static_cast<std::int64_t>(t.voxel_material.size());
  trace.chambers = t.chambers;
  trace.positions = t.positions;
  trace.orientations = t.orientations;
  trace.pressures = t.pressures;
  trace.valve_commands = t.valves;
  trace.time = t.time;
  trace.voxel_cells.assign(t.voxel_cells.begin(), t.voxel_cells.end());
  trace.voxel_material.assign(t.voxel_material.begin(), t.voxel_material.end());
  trace.robot_json = robot_to_json(robot);
  trace.dt = t.dt;
  trace.voxel_size = t.voxel_size;
  trace.frame_rate = control_rate;
  trace.steps_per_frame = t.steps_per_frame;
  if (direction_deg) trace.direction_deg = *direction_deg;
  trace.fitness = result.fitness;
  trace.status = to_string(result.status);
  io::write_trace(path, trace);
}

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

int run_eval(const EvalArgs& a) {
  const RobotFile robot = read_robot_file(a.robot);
  Config config = a.config_file.empty() ? parse_config("", "<built-in defaults>", a.overrides)
                                        : load_config(a.config_file, a.overrides);
  if (a.config_file.empty()) {
    config.task.control = robot.controller.closed_loop ? "closed" : "open";
    config.run.eval_timeout_seconds = 0.0;  // interactive: no wall-clock limit
  }
  config.task.kind = a.task.empty() ? (robot.controller.directed ? "directed" : "gait") : a.task;
  if (!a.integrator.empty()) config.physics.integrator = a.integrator;
  if (a.seconds > 0.0) config.task.eval_seconds = a.seconds;

  EvalOptions opts;
  opts.simd = physics::parse_simd(a.simd).value();  // checked by the option's IsMember
  if (!physics::simd_supported(opts.simd))
    throw std::invalid_argument("--simd " + a.simd + ": not supported by this CPU or build");
  const physics::Simd simd_used = physics::resolve_simd(opts.simd);  // = the Model's width
  for (const std::string& what : a.ablate) {
    if (what == "oscillator") opts.ablate_oscillator = true;
    if (what == "sensors") opts.ablate_sensors = true;
  }

  TraceBuffer trace;
  if (!a.trace.empty()) {
    opts.on_start = [&trace](const worker::TraceHeader& h) {
      trace.model = h.model;
      trace.chambers = h.chambers;
      trace.steps_per_frame = h.steps_per_frame;
      trace.dt = h.model->dt;
      trace.voxel_size = h.model->voxel_size;
      trace.voxel_cells.clear();
      trace.voxel_material.clear();
      for (int v = 0; v < h.model->voxel_count; ++v) {
        for (int i = 0; i < 3; ++i) trace.voxel_cells.push_back(h.model->voxel_cell[v][i]);
        trace.voxel_material.push_back(h.model->voxel_material[v]);
      }
      trace.positions.clear();
      trace.orientations.clear();
      trace.pressures.clear();
      trace.valves.clear();
      trace.time.clear();
      trace.frames = 0;
    };
    opts.on_frame = [&trace](const worker::TraceFrame& f) {
      for (const auto& p : f.positions)
        trace.positions.insert(trace.positions.end(), {p.x(), p.y(), p.z()});
      for (const auto& q : f.orientations)
        trace.orientations.insert(trace.orientations.end(), {q.w, q.x, q.y, q.z});
      trace.pressures.insert(trace.pressures.end(), f.pressures.begin(), f.pressures.end());
      trace.valves.insert(trace.valves.end(), f.valve_commands.begin(), f.valve_commands.end());
      trace.time.push_back(f.time);
      ++trace.frames;
    };
  }

  std::timespec cpu0{}, cpu1{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu0);
  EvalResult result;
  const bool directed = config.task.kind == "directed";
  double trace_direction = 0.0;
  if (directed && (a.direction_set || !a.trace.empty())) {
    // One direction only: the one asked for (appended if not configured) or the first.
    int index = 0;
    if (a.direction_set) {
      index = -1;
      for (std::size_t i = 0; i < config.task.directions.size(); ++i)
        if (config.task.directions[i] == a.direction) index = static_cast<int>(i);
      if (index < 0) {
        config.task.directions.push_back(a.direction);
        index = static_cast<int>(config.task.directions.size()) - 1;
      }
    }
    trace_direction = config.task.directions.at(static_cast<std::size_t>(index));
    result = evaluate_robot(config, robot.body, robot.controller, index, opts);
  } else {
    result = evaluate_task(config, robot.body, robot.controller, opts);
  }
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu1);
  const double cpu_seconds = static_cast<double>(cpu1.tv_sec - cpu0.tv_sec) +
                             1e-9 * static_cast<double>(cpu1.tv_nsec - cpu0.tv_nsec);

  if (!a.trace.empty() && trace.model != nullptr)
    write_trace(a.trace, trace, robot, result, config.task.control_rate,
                directed ? &trace_direction : nullptr);

  const std::string ablation = opts.ablate_oscillator && opts.ablate_sensors ? "oscillator+sensors"
                               : opts.ablate_oscillator                      ? "oscillator"
                               : opts.ablate_sensors                         ? "sensors"
                                                                             : "none";
  if (a.json) {
    std::string s = "{";
    s += "\"robot\": " + json_string(robot.name.empty() ? a.robot : robot.name);
    s += ", \"task\": " + json_string(config.task.kind);
    s += ", \"integrator\": " + json_string(config.physics.integrator);
    s += ", \"ablate\": " + json_string(ablation);
    s += ", \"fitness\": " + json_number(result.fitness);
    s += ", \"status\": " + json_string(to_string(result.status));
    s += ", \"killed\": " + std::string(is_killed(result.status) ? "true" : "false");
    s += ", \"components\": [";
    for (std::size_t i = 0; i < result.components.size(); ++i) {
      const DirectionComponents& c = result.components[i];
      s += i ? ", " : "";
      s += "{\"direction_deg\": " + json_number(c.direction_deg) +
           ", \"fitness\": " + json_number(c.fitness) + ", \"D\": " + json_number(c.distance) +
           ", \"L\": " + json_number(c.path_length) + ", \"delta\": " + json_number(c.angle_error) +
           ", \"P\": " + json_number(c.perpendicular_penalty) +
           ", \"status\": " + json_string(to_string(c.status)) + "}";
    }
    s += "], \"sim_seconds\": " + json_number(result.sim_seconds);
    s += ", \"steps\": " + std::to_string(result.steps);
    s += ", \"voxels\": " + std::to_string(result.voxels);
    s += ", \"chambers\": " + std::to_string(result.chambers);
    s += ", \"wall_seconds\": " + json_number(result.wall_seconds);
    s += ", \"cpu_seconds\": " + json_number(cpu_seconds);
    s += ", \"simd\": " + json_string(physics::to_string(simd_used));
    s += ", \"message\": " + json_string(result.message);
    s += "}";
    std::printf("%s\n", s.c_str());
  } else {
    std::printf("robot        %s\n", robot.name.empty() ? a.robot.c_str() : robot.name.c_str());
    std::printf("task         %s (%s loop%s), integrator %s, ablate %s\n", config.task.kind.c_str(),
                robot.controller.closed_loop ? "closed" : "open",
                robot.controller.directed ? ", directed controller" : "",
                config.physics.integrator.c_str(), ablation.c_str());
    std::printf("fitness      %.17g\n", result.fitness);
    std::printf("status       %s%s%s\n", to_string(result.status),
                result.message.empty() ? "" : ": ", result.message.c_str());
    for (const DirectionComponents& c : result.components) {
      if (config.task.kind == "gait")
        std::printf("  gait: mean x displacement %.17g cm\n", c.distance);
      else
        std::printf(
            "  direction %+6.1f deg: F %.10g  D %.10g cm  L %.10g cm  delta %.10g rad  "
            "P %.10g cm  %s\n",
            c.direction_deg, c.fitness, c.distance, c.path_length, c.angle_error,
            c.perpendicular_penalty, to_string(c.status));
    }
    std::printf("simulated    %.6f s in %lld steps\n", result.sim_seconds,
                static_cast<long long>(result.steps));
    std::printf("body         %d voxels, %d chambers\n", result.voxels, result.chambers);
    std::printf("time         %.3f s wall, %.3f s CPU (physics SIMD width %s)\n",
                result.wall_seconds, cpu_seconds, physics::to_string(simd_used));
    if (!a.trace.empty())
      std::printf("trace        %s (%d frames)\n", a.trace.c_str(), trace.frames);
  }
  return result.status == EvalStatus::failed ? kExitUsage : kExitOk;
}

}  // namespace

void register_eval(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("eval", "evaluate a robot file (fitness, components, status)");
  auto a = std::make_shared<EvalArgs>();
  cmd->add_option("ROBOT", a->robot, "robot file (softevo.robot/1 JSON)")->required();
  cmd->add_option("--task", a->task, "gait or directed (default: from the controller)")
      ->check(CLI::IsMember({"gait", "directed"}));
  cmd->add_option("--integrator", a->integrator, "physics integrator")
      ->check(CLI::IsMember({"pneuvox", "symplectic"}));
  cmd->add_option("--seconds", a->seconds, "simulated seconds (default task.eval_seconds = 10)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--ablate", a->ablate, "feed zeros to the oscillator or the pressure sensors")
      ->check(CLI::IsMember({"oscillator", "sensors"}));
  auto* dir = cmd->add_option("--direction", a->direction,
                              "directed task: evaluate only this target direction [deg]");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->add_option("--trace", a->trace, "record voxel poses, pressures and valves (HDF5)");
  cmd->add_option("--config", a->config_file, "TOML config (default: built-in thesis values)");
  cmd->add_option("--set", a->overrides, "override a config key: section.key=value");
  cmd->add_option("--simd", a->simd,
                  "SIMD width of the physics: best (default), sse2, avx2 or avx512 (the fitness "
                  "is bit-identical at every width; only the speed differs)")
      ->check(CLI::IsMember(physics::simd_names()));
  cmd->callback([&exit_code, a, dir] {
    EvalArgs args = *a;
    args.direction_set = dir->count() > 0;
    exit_code = run_eval(args);
  });
}

}  // namespace softevo::cli
