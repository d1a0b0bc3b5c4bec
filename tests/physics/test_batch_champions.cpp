// Every lane of the batched step (physics/batch.hpp) equals its evaluation stepped alone, bit
// for bit: the 20 gait champions and dir-open-09 (../shared/reference/bestbots, skipped when
// absent), lanes from their own evaluations (controller, pneumatics, self-collision), at batch
// sizes 1, 3, 5, 8 and 16 and every SIMD width this CPU runs. Label long (about a minute).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/physics/batch_lanes.hpp"
#include "tests/reference_data.hpp"

namespace fs = std::filesystem;
using namespace softevo;

namespace {

TEST(BatchChampions, EveryLaneEqualsItsEvaluationAloneAtEverySizeAndWidth) {
  const fs::path dir = test::reference_bestbots();
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared not found (" << dir << ")";
  std::vector<std::string> robots{"dir-open-09"};
  for (const char* kind : {"gait-open-", "gait-closed-"})
    for (int i = 1; i <= 10; ++i)
      robots.push_back(kind + std::string(i < 10 ? "0" : "") + std::to_string(i));
  for (const std::string& robot : robots) {
    const test::BatchCase c = test::batch_case_of_robot(dir / (robot + ".robot.json"), 16, 10, 2);
    ASSERT_EQ(c.states.size(), 16u) << robot;
    for (physics::Simd simd : physics::simd_widths()) {
      if (!physics::simd_supported(simd)) continue;
      for (int lanes : {1, 3, 5, 8, 16})
        test::expect_lanes_equal_steps_alone(
            c.model, std::vector<physics::State>(c.states.begin(), c.states.begin() + lanes), simd,
            12, {}, robot);
    }
  }
}

}  // namespace
