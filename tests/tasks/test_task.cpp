// The Task seam (tasks/task.hpp): the registry, the default combination of units (§7.4) and
// combine_units.
#include <gtest/gtest.h>

#include <vector>

#include "tasks/task.hpp"

using namespace softevo;
using namespace softevo::tasks;

TEST(Task, TheRegistryBuildsEveryKind) {
  for (TaskKind kind : task_kinds()) {
    Config c;
    c.task.kind = kind;
    EXPECT_EQ(make_task(c)->kind(), kind) << to_string(kind);
  }
}

TEST(Task, DefaultTaskFollowsTheControllerInputs) {
  EXPECT_EQ(default_task_for(0), TaskKind::gait);
  EXPECT_EQ(default_task_for(1), TaskKind::directed);
  EXPECT_THROW(default_task_for(7), std::invalid_argument);
}

TEST(Task, UnitsSumInOrderAndAnyKillZeroes) {
  Config c;
  c.task.kind = TaskKind::directed;
  const auto task = make_task(c);
  std::vector<EvalResult> r(5);
  for (int i = 0; i < 5; ++i) {
    r[i].unit = i;
    r[i].fitness = 10.0 + i;
    r[i].components.push_back({10.0 + i, EvalStatus::ok, {1, 2, 3, 4, 5}});
    r[i].steps = 100;
    r[i].voxels = 7;
  }
  EvalResult all = combine_units(*task, r);
  EXPECT_DOUBLE_EQ(all.fitness, 60.0);
  EXPECT_EQ(all.status, EvalStatus::ok);
  ASSERT_EQ(all.components.size(), 5u);
  EXPECT_EQ(all.components[2].values, (std::vector<double>{1, 2, 3, 4, 5}));
  EXPECT_EQ(all.steps, 500);
  EXPECT_EQ(all.voxels, 7);
  r[3].status = EvalStatus::killed_flipped;
  r[3].fitness = 0.0;
  r[3].message = "flipped";
  r[3].components.clear();  // e.g. a failed unit: zero-filled to the task's components
  all = combine_units(*task, r);
  EXPECT_DOUBLE_EQ(all.fitness, 0.0);
  EXPECT_EQ(all.status, EvalStatus::killed_flipped);
  EXPECT_EQ(all.message, "flipped");
  EXPECT_EQ(all.components[3].status, EvalStatus::killed_flipped);
  EXPECT_EQ(all.components[3].values, std::vector<double>(5, 0.0));
}

TEST(Task, ComponentRowIsFitnessValuesStatus) {
  Config c;
  c.task.kind = TaskKind::rotate;
  const auto task = make_task(c);
  EXPECT_EQ(component_columns(*task),
            (std::vector<std::string>{"fitness", "heading_change", "travel", "travel_penalty",
                                      "status"}));
  const UnitFitness u{1.5, EvalStatus::killed_exploded, {0.5, 0.25}};
  EXPECT_EQ(component_row(u), (std::vector<double>{1.5, 0.5, 0.25, 2.0}));
}
