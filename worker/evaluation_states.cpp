#include "worker/evaluation_states.hpp"

#include "common/config.hpp"
#include "tasks/task.hpp"
#include "worker/controller.hpp"
#include "worker/simulation.hpp"

namespace softevo::worker {

EvaluationStates evaluation_states(const RobotFile& robot, int count, int first_frame,
                                   int gap_frames) {
  Config cfg;
  cfg.run.eval_timeout_seconds = 0.0;
  cfg.task.eval_seconds = 10.0;
  cfg.task.control = robot.controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
  cfg.task.kind = tasks::default_task_for(robot.controller.task_inputs());
  const auto task = tasks::make_task(cfg);
  Simulation sim(cfg, *task, robot.body, 0, physics::Simd::best);
  ElmanController brain(robot.controller, cfg.task.control_rate);
  brain.check_chambers(sim.chambers());
  std::vector<float> inputs(static_cast<std::size_t>(task->controller_inputs()), 0.0f);
  std::vector<float> sensor(static_cast<std::size_t>(sim.chambers()), 0.0f);
  std::vector<float> commands(static_cast<std::size_t>(sim.valve_count()), 1.0f);
  EvaluationStates out;
  for (int frame = 0; sim.running() && static_cast<int>(out.states.size()) < count; ++frame) {
    if (frame >= first_frame && (frame - first_frame) % gap_frames == 0)
      out.states.push_back(sim.state());
    sim.task_inputs(inputs);
    for (int q = 0; q < sim.chambers(); ++q) sensor[q] = sim.sensor_pressure_bar(q);
    brain.act(inputs, sensor, commands);
    sim.step(commands);
  }
  out.model = sim.model();
  return out;
}

}  // namespace softevo::worker
