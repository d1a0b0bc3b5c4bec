// Whole evaluations keep their bits on every platform: thesis champions
// (../shared/reference/bestbots) evaluated for a short time (a quarter second: 15 control frames,
// short enough for qemu) give fitness values pinned here, bit
// for bit, from x86-64 (Debian 12, GCC 12), at every SIMD width this build runs. On AArch64
// (`tools/bootstrap.sh aarch64`, under qemu) this checks the physics together with the libm calls
// of the evaluation: an open-loop gait (oscillator sin / cos), a closed-loop gait (the Elman
// network's tanhf, pressure sensors) and a directed champion (direction sensor, acos of the
// heading terms). Skipped when ../shared is absent.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "physics/model.hpp"
#include "tasks/task.hpp"
#include "tests/reference_data.hpp"
#include "worker/evaluate.hpp"

namespace fs = std::filesystem;
using namespace softevo;

namespace {

fs::path bestbots() {
  return test::reference_bestbots();
}

struct PinnedFitness {
  const char* robot;
  double seconds;      // simulated [s]
  int unit;            // the task's work unit (directed: index into task.directions)
  std::uint64_t bits;  // the fitness's IEEE 754 bits on x86-64
};

constexpr PinnedFitness kPinned[] = {
    {"gait-open-01", 0.25, 0, 0x400176dd1162c48aull},
    {"gait-closed-10", 0.25, 0, 0x4008004d22842700ull},
    {"dir-closed-04", 0.25, 0, 0x3ffd78635eae96e1ull},
};

TEST(ChampionBits, ShortEvaluationsGiveThePinnedFitnessBits) {
  if (!fs::exists(bestbots())) GTEST_SKIP() << "../shared not found (" << bestbots() << ")";
  for (const PinnedFitness& p : kPinned) {
    const RobotFile robot =
        read_robot_file((bestbots() / (std::string(p.robot) + ".robot.json")).string());
    Config cfg;
    cfg.run.eval_timeout_seconds = 0.0;  // results must not depend on machine load
    cfg.task.eval_seconds = p.seconds;
    cfg.task.control = robot.controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
    cfg.task.kind = tasks::default_task_for(robot.controller.task_inputs());
    const auto task = tasks::make_task(cfg);
    const EvalResult r = worker::evaluate(cfg, *task, robot.body, robot.controller, p.unit);
    ASSERT_EQ(r.status, EvalStatus::ok) << p.robot << ": " << r.message;
    const std::uint64_t bits = std::bit_cast<std::uint64_t>(r.fitness);
    std::printf("%s %.2f s (%s): fitness %.17g = 0x%016llx\n", p.robot, p.seconds,
                softevo::to_string(physics::best_simd()), r.fitness,
                static_cast<unsigned long long>(bits));
    EXPECT_EQ(bits, p.bits) << p.robot;
  }
}

}  // namespace
