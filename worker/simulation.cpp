// The main simulation loop (pneuvox-model.md §5). See simulation.hpp.
#include "worker/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "physics/observables.hpp"
#include "physics/pneumatics.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"
#include "worker/controller.hpp"
#include "worker/fitness.hpp"

namespace softevo::worker {
namespace {

constexpr int kMaxSensorValues = 10;  // §4.1/§11 item 15: cap after the oscillator inputs
constexpr double kCmPerM = 100.0;

EvalStatus status_of(physics::StepStatus s) {
  return s == physics::StepStatus::ok ? EvalStatus::ok : EvalStatus::diverged;
}

}  // namespace

EvalResult simulate(const Config& config, const BodyPlan& plan, const ControllerSpec& controller,
                    int direction_index, const EvalOptions& opts) {
  const auto wall_start = std::chrono::steady_clock::now();
  const TaskConfig& task = config.task;
  const bool directed_task = direction_index >= 0;
  if (directed_task && direction_index >= static_cast<int>(task.directions.size()))
    throw std::invalid_argument("direction index " + std::to_string(direction_index) +
                                " outside task.directions (" +
                                std::to_string(task.directions.size()) + " directions)");
  if (!(task.control_rate > 0.0) || !(task.eval_seconds >= 0.0))
    throw std::invalid_argument("task.control_rate must be > 0 and task.eval_seconds >= 0");
  const double direction_deg = directed_task ? task.directions[direction_index] : 0.0;

  EvalResult result;
  result.direction_index = direction_index;

  // ---- setup (§5 setup 1-8) -------------------------------------------------------------------
  physics::BuildOptions build_options;
  build_options.simd = opts.simd;
  const physics::Model model = physics::build_model(plan, config.physics, build_options);
  const physics::PneumaticsModel pm = physics::build_pneumatics(plan, model, config.pneumatics);
  result.voxels = model.voxel_count;
  result.chambers = pm.chamber_count;
  if (model.voxel_count == 0 || pm.chamber_count == 0) {
    result.status = EvalStatus::invalid_body;
    result.message = "body has no voxels or no chamber (not actuatable)";
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

  // §5 setup 8: stepsPerFrame = (int)(1.0f / 60.0f / dt) in float arithmetic.
  const float frame_seconds_f = 1.0f / static_cast<float>(task.control_rate);
  const int steps_per_frame = static_cast<int>(frame_seconds_f / model.dt_f);
  const int frames = static_cast<int>(std::lround(task.control_rate * task.eval_seconds));
  const int waypoint_every = std::max(1, static_cast<int>(std::lround(task.control_rate)));
  // First sensor reading (SPEC section 3): config value for every chamber, in bar.
  const float initial_sensor_bar =
      static_cast<float>(config.pneumatics.initial_sensor_pressure / physics::kPascalPerBar);
  const double timeout = config.run.eval_timeout_seconds;

  std::vector<Vec3d> waypoints_cm;
  waypoints_cm.reserve(static_cast<std::size_t>(frames / waypoint_every + 2));
  auto record_waypoint = [&] {
    const Vec3d c = physics::centroid_displacement(model, state);
    waypoints_cm.emplace_back(c.x() * kCmPerM, c.y() * kCmPerM, 0.0);  // cm, z set to 0
  };
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

  const int sensor_slots = weights.inputs - 2;  // after sin, cos
  for (int frame = 0; frame < frames; ++frame) {
    // 1. Inputs [sin, cos, (direction), (pressures)], the sensor part capped at 10 values and
    //    zero-padded (§4.1).
    advance_oscillator(weights, brain, task.control_rate);  // §4.2: before the inputs are read
    inputs[0] = opts.ablate_oscillator ? 0.0f : static_cast<float>(std::sin(brain.phase));
    inputs[1] = opts.ablate_oscillator ? 0.0f : static_cast<float>(std::cos(brain.phase));
    std::fill(inputs.begin() + 2, inputs.end(), 0.0f);
    int sensor = 0;
    auto push_sensor = [&](float value) {
      if (sensor < kMaxSensorValues && sensor < sensor_slots) inputs[2 + sensor] = value;
      ++sensor;
    };
    if (controller.directed) {
      const Vec3d c = physics::centroid_displacement(model, state);
      const double heading = physics::mean_rotation_vector(model, state).z();
      push_sensor(direction_sensor(c, heading, direction_deg, model.voxel_size));
    }
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
    // 4. Waypoint at the start of every 60th frame (§7.2).
    if (frame % waypoint_every == 0) record_waypoint();
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
    if (timeout > 0.0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count() >
            timeout) {
      result.status = EvalStatus::timeout;
      result.message = "evaluation exceeded run.eval_timeout_seconds";
      break;
    }
  }
  result.sim_seconds = state.time;

  DirectionComponents comp;
  comp.direction_deg = direction_deg;
  comp.status = result.status;
  if (result.status == EvalStatus::ok) {
    record_waypoint();  // final waypoint after the last frame
    emit(frames);
    if (directed_task) {
      comp = directed_components(waypoints_cm, direction_deg, task.path_penalty_weight);
    } else {
      const Vec3d c = physics::centroid_displacement(model, state);
      comp.fitness = gait_fitness(c);
      comp.distance = c.x() * kCmPerM;
    }
    comp.status = EvalStatus::ok;
    result.fitness = comp.fitness;
  }  // killed / diverged / timeout: fitness and components 0 (§7.1, §7.2 "Killed")
  result.components.push_back(comp);
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace softevo::worker
