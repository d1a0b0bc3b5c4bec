// Robot evaluation entry points. See evaluate_robot.hpp.
#include "worker/evaluate_robot.hpp"

#include <chrono>
#include <exception>
#include <stdexcept>
#include <vector>

#include "worker/fitness.hpp"

namespace softevo {

EvalResult evaluate_robot(const Config& config, const BodyPlan& plan,
                          const ControllerSpec& controller, int direction_index,
                          const EvalOptions& opts) {
  const auto start = std::chrono::steady_clock::now();
  try {
    return worker::simulate(config, plan, controller, direction_index, opts);
  } catch (const std::exception& e) {
    EvalResult failed;
    failed.direction_index = direction_index;
    failed.status = EvalStatus::failed;
    failed.fitness = 0.0;
    failed.message = e.what();
    failed.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return failed;
  }
}

EvalResult evaluate_task(const Config& config, const BodyPlan& plan,
                         const ControllerSpec& controller, const EvalOptions& opts) {
  if (config.task.kind == "gait") return evaluate_robot(config, plan, controller, -1, opts);
  if (config.task.kind != "directed") {
    EvalResult failed;
    failed.status = EvalStatus::failed;
    failed.message = "unknown task.kind '" + config.task.kind + "' (gait or directed)";
    return failed;
  }
  std::vector<EvalResult> per_direction;
  for (int d = 0; d < static_cast<int>(config.task.directions.size()); ++d)
    per_direction.push_back(evaluate_robot(config, plan, controller, d, opts));
  return worker::combine_directions(per_direction);
}

}  // namespace softevo
