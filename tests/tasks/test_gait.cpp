// The gait task (tasks/gait.hpp, docs/model.md §7.1).
#include <gtest/gtest.h>

#include "tasks/gait.hpp"

using namespace softevo;
using namespace softevo::tasks;

TEST(Gait, FitnessIsMeanXDisplacementInCm) {
  EXPECT_DOUBLE_EQ(gait_fitness(Eigen::Vector3d(0.6968, -0.2, 0.01)), 69.68);
  EXPECT_DOUBLE_EQ(gait_fitness(Eigen::Vector3d(-0.1, 0, 0)), -10.0);
}

TEST(Gait, OneUnitNoInputAndTheDistanceComponent) {
  const auto task = make_gait_task(Config{});
  EXPECT_EQ(task->kind(), TaskKind::gait);
  EXPECT_EQ(task->units(), 1);
  EXPECT_EQ(task->controller_inputs(), 0);
  ASSERT_EQ(task->component_names().size(), 1u);
  EXPECT_EQ(task->component_names()[0].name, "distance");
}
