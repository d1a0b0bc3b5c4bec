// Thesis champions, full evaluation (LABELS long: about 4,300 CPU seconds on this machine's
// kind; run with `ctest -L long`). Every champion the thesis simulator does not kill
// (reference.killed false, reference.fitness > 0) must walk here too with the pneuvox
// integrator: not killed and fitness > 0 (forward for gait, towards the targets for directed).
// The comparison figures (Spearman, open-loop median difference) are printed; the report
// command `softevo champions` prints the full table.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "tasks/task.hpp"
#include "tests/reference_data.hpp"
#include "worker/evaluate.hpp"

namespace fs = std::filesystem;
using namespace softevo;

TEST(ChampionsAll, EveryReferenceWalkerWalksHere) {
  const fs::path dir = test::reference_bestbots();
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared not found (" << dir << ")";
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 40u);
  std::vector<EvalResult> results(files.size());
  std::vector<RobotFile> robots;
  for (const auto& f : files) robots.push_back(read_robot_file(f.string()));
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < robots.size();) {
      Config cfg;
      cfg.run.eval_timeout_seconds = 0.0;  // results must not depend on machine load
      cfg.task.control = robots[i].controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
      cfg.task.kind = tasks::default_task_for(robots[i].controller.task_inputs());
      const auto task = tasks::make_task(cfg);
      results[i] = worker::evaluate_all_units(cfg, *task, robots[i].body, robots[i].controller);
    }
  };
  std::thread t1(work), t2(work);
  t1.join();
  t2.join();
  int walkers = 0;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const auto ref = nlohmann::json::parse(robots[i].reference_json);
    const double ref_fitness = ref.at("fitness").get<double>();
    const bool ref_killed = ref.value("killed", false);
    std::printf("%-16s ours %12.4f  reference %10.4f  %s\n", robots[i].name.c_str(),
                results[i].fitness, ref_fitness, to_string(results[i].status));
    if (ref_killed || !(ref_fitness > 0.0)) continue;
    ++walkers;
    EXPECT_EQ(results[i].status, EvalStatus::ok) << robots[i].name << " " << results[i].message;
    EXPECT_GT(results[i].fitness, 0.0) << robots[i].name;
  }
  EXPECT_GE(walkers, 38);
}
