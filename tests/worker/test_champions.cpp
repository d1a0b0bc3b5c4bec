// Thesis champions (../shared/reference/bestbots): a fast subset for the default suite. Three
// champions that are not chaotic in the thesis simulator (§9.8) are evaluated for 2 simulated
// seconds (gait task; directed: direction 0 only): not killed and moving forward. The full
// 10 s evaluation of all 40 is test_champions_all (LABELS long) and `softevo champions`.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "tasks/task.hpp"
#include "tests/reference_data.hpp"
#include "worker/evaluate.hpp"

namespace fs = std::filesystem;
using namespace softevo;

namespace {
fs::path bestbots() {
  return test::reference_bestbots();
}
}  // namespace

TEST(ChampionsFast, ThreeChampionsWalkForwardForTwoSeconds) {
  if (!fs::exists(bestbots())) GTEST_SKIP() << "../shared not found (" << bestbots() << ")";
  for (const char* name : {"gait-open-08", "gait-closed-03", "dir-closed-04"}) {
    const RobotFile robot =
        read_robot_file((bestbots() / (std::string(name) + ".robot.json")).string());
    Config cfg;
    cfg.run.eval_timeout_seconds = 0.0;  // results must not depend on machine load
    cfg.task.eval_seconds = 2.0;
    cfg.task.control = robot.controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
    cfg.task.kind = tasks::default_task_for(robot.controller.task_inputs());
    const auto task = tasks::make_task(cfg);
    const EvalResult r = worker::evaluate(cfg, *task, robot.body, robot.controller, 0);
    EXPECT_EQ(r.status, EvalStatus::ok) << name << ": " << to_string(r.status) << " " << r.message;
    EXPECT_GT(r.fitness, 0.0) << name;
    ASSERT_FALSE(r.components.empty());
    // distance: the first component of the gait task, the second of the directed one.
    const auto names = task->component_names();
    double distance = 0.0;
    for (std::size_t k = 0; k < names.size(); ++k)
      if (names[k].name == "distance") distance = r.components[0].values[k];
    EXPECT_GT(distance, 2.0) << name << " moved less than 2 cm in 2 s";
  }
}
