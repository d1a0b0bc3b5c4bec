// Helper of test_eval_determinism: evaluates ROBOT.json for SECONDS with the built-in config
// (task from the controller) and prints the fitness bits ("%a") and status. Run in separate
// processes by the test to show that the result does not depend on the process. An optional
// third argument names the SIMD width of the physics (sse2, avx2, avx512; default: the best
// here).
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "tasks/task.hpp"
#include "worker/evaluate.hpp"

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr, "usage: %s ROBOT.json SECONDS [sse2|avx2|avx512]\n", argv[0]);
    return 2;
  }
  softevo::worker::EvaluateOptions options;
  if (argc == 4) {
    const std::optional<softevo::physics::Simd> simd = softevo::physics::parse_simd(argv[3]);
    if (!simd) {
      std::fprintf(stderr, "unknown SIMD width '%s'\n", argv[3]);
      return 2;
    }
    options.simd = *simd;
  }
  try {
    const softevo::RobotFile robot = softevo::read_robot_file(argv[1]);
    softevo::Config config;
    config.run.eval_timeout_seconds = 0.0;
    config.task.eval_seconds = std::atof(argv[2]);
    config.task.kind = softevo::tasks::default_task_for(robot.controller.task_inputs());
    const auto task = softevo::tasks::make_task(config);
    const softevo::EvalResult r =
        softevo::worker::evaluate_all_units(config, *task, robot.body, robot.controller, options);
    std::printf("%a %s\n", r.fitness, softevo::to_string(r.status));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
