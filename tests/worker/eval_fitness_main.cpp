// Helper of test_eval_determinism: evaluates ROBOT.json for SECONDS with the built-in config
// (task from the controller) and prints the fitness bits ("%a") and status. Run in separate
// processes by the test to show that the result does not depend on the process.
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "worker/evaluate_robot.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s ROBOT.json SECONDS\n", argv[0]);
    return 2;
  }
  try {
    const softevo::RobotFile robot = softevo::read_robot_file(argv[1]);
    softevo::Config config;
    config.run.eval_timeout_seconds = 0.0;
    config.task.eval_seconds = std::atof(argv[2]);
    config.task.kind = robot.controller.directed ? "directed" : "gait";
    const softevo::EvalResult r = softevo::evaluate_task(config, robot.body, robot.controller);
    std::printf("%a %s\n", r.fitness, softevo::to_string(r.status));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
