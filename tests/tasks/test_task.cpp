// The Task seam (tasks/task.hpp): the registry, the default combination of units (§7.4),
// combine_units, the score so far of a live view and steering.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "physics/model.hpp"
#include "physics/state.hpp"
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

namespace {

// A 3 x 2 x 1 block with a one-cell chamber, moved rigidly: frame f turns it by 0.01 f rad and
// shifts it by (1 mm, 0.5 mm) per frame.
struct MovedBlock {
  physics::Model model;
  physics::State state;
  std::vector<physics::Vec3> rest;
  explicit MovedBlock(const Config& config) {
    BodyPlan plan;
    plan.lattice = {3, 2, 1};
    plan.voxel_size = 0.01;
    for (int k = 1; k <= 10; ++k) plan.materials.push_back({1.0e4 * k, 1000.0});
    plan.cells.assign(6, 5);
    plan.cells[plan.cell_index(1, 0, 0)] = 11;
    model = physics::build_model(plan, config.physics);
    state = physics::initial_state(model);
    rest.assign(state.pos.begin(), state.pos.end());
  }
  void place(int frame) {
    const double a = 0.01 * frame, c = std::cos(a), s = std::sin(a);
    for (std::size_t v = 0; v < rest.size(); ++v) {
      const physics::Vec3& p = rest[v];
      state.pos[v] = physics::Vec3(c * p.x() - s * p.y() + 0.001 * frame,
                                   s * p.x() + c * p.y() + 0.0005 * frame, p.z());
    }
  }
};

// The config of `kind` with one target direction [deg] (used by the directed task only).
Config task_config(TaskKind kind, double direction_deg) {
  Config c;
  c.task.kind = kind;
  c.task.directions = {direction_deg};
  return c;
}

std::uint64_t bits(double x) {
  return std::bit_cast<std::uint64_t>(x);
}

}  // namespace

// What a live view shows (UnitScore::so_far) is what finish would give on the same state, and
// asking for it changes nothing: a score asked every frame finishes with the bits of one never
// asked.
TEST(Task, ScoreSoFarIsWhatFinishWouldGiveAndChangesNothing) {
  for (TaskKind kind : task_kinds()) {
    const Config c = task_config(kind, 30.0);
    const auto task = make_task(c);
    MovedBlock block(c);
    const auto asked = task->start_unit(0, block.model);
    const auto quiet = task->start_unit(0, block.model);
    const int frames = 150;
    UnitFitness at_end;
    for (int f = 0; f < frames; ++f) {
      block.place(f);
      asked->observe(f, block.model, block.state);
      quiet->observe(f, block.model, block.state);
      at_end = asked->so_far(block.model, block.state);
      (void)asked->so_far(block.model, block.state);
    }
    const UnitFitness a = asked->finish(block.model, block.state);
    const UnitFitness q = quiet->finish(block.model, block.state);
    EXPECT_EQ(bits(a.fitness), bits(q.fitness)) << to_string(kind);
    EXPECT_EQ(bits(at_end.fitness), bits(q.fitness)) << to_string(kind);
    ASSERT_EQ(a.values.size(), task->component_names().size()) << to_string(kind);
    ASSERT_EQ(at_end.values.size(), q.values.size()) << to_string(kind);
    for (std::size_t i = 0; i < q.values.size(); ++i) {
      EXPECT_EQ(bits(a.values[i]), bits(q.values[i])) << to_string(kind) << " component " << i;
      EXPECT_EQ(bits(at_end.values[i]), bits(q.values[i])) << to_string(kind) << " component " << i;
    }
    EXPECT_NE(q.fitness, 0.0) << to_string(kind) << ": the moved block scores nothing";
  }
}

// Only a task with a target direction can be steered; a steered directed unit senses and is
// scored towards the new target.
TEST(Task, OnlyADirectedUnitSteersAndItsScoreFollows) {
  for (TaskKind kind : task_kinds()) {
    const Config c = task_config(kind, 0.0);
    const auto task = make_task(c);
    MovedBlock block(c);
    const auto score = task->start_unit(0, block.model);
    if (!task->steerable()) {
      EXPECT_THROW(score->steer(90.0), std::logic_error) << to_string(kind);
      continue;
    }
    EXPECT_EQ(task->controller_input_names(), std::vector<std::string>{"direction_sensor"});
    const UnitFitness before = score->so_far(block.model, block.state);
    EXPECT_EQ(before.values.at(0), 0.0);  // direction_deg
    score->steer(90.0);
    for (int f = 0; f < 60; ++f) {
      block.place(f);
      score->observe(f, block.model, block.state);
    }
    const UnitFitness steered = score->so_far(block.model, block.state);
    EXPECT_EQ(steered.values.at(0), 90.0);
    // Moved 2.95 cm along +y: the distance along the steered target (+y), not along x.
    EXPECT_GT(steered.values.at(1), 2.0);
    EXPECT_LT(steered.values.at(1), 3.5);
  }
}
