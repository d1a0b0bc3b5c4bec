// Self-scheduling of one generation: unit order, results stored by id whatever the arrival
// order, the task's combination of units (§7.4 for the directed task), bookkeeping errors.
#include "master/scheduler.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace softevo::master {
namespace {

// The task of a config of kind `kind` with `directions` target directions.
struct TaskOf {
  explicit TaskOf(TaskKind kind, int directions = 5) {
    config.task.kind = kind;
    config.task.directions.assign(static_cast<std::size_t>(directions), 0.0);
    task = tasks::make_task(config);
  }
  Config config;
  std::unique_ptr<tasks::Task> task;
};
const TaskOf kGait(TaskKind::gait);

EvalResult result(std::int64_t id, int unit, double fitness, EvalStatus st = EvalStatus::ok) {
  EvalResult r;
  r.genome_id = id;
  r.unit = unit;
  r.fitness = fitness;
  r.status = st;
  r.wall_seconds = 1.0;
  r.voxels = 10;
  r.components.push_back({fitness, st, {0.0, fitness * 2, 0.0, 0.0, 0.0}});
  return r;
}

TEST(Scheduler, GaitHasOneUnitPerGenome) {
  GenerationScheduler s(0, {5, 3, 9}, *kGait.task);
  EXPECT_EQ(s.units_total(), 3u);
  std::vector<std::int64_t> ids;
  while (auto u = s.next()) {
    EXPECT_EQ(u->unit, 0);
    ids.push_back(u->genome_id);
  }
  EXPECT_EQ(ids, (std::vector<std::int64_t>{5, 3, 9}));
  EXPECT_FALSE(s.done());
}

TEST(Scheduler, PredictedCostsHandOutTheLongestFirstAndKeepTheOutcomes) {
  const std::vector<std::int64_t> ids = {4, 1, 7, 2};
  const TaskOf directed(TaskKind::directed, 2);
  const auto run = [&](const std::vector<double>& costs, std::vector<std::int64_t>* order) {
    GenerationScheduler s(0, ids, *directed.task, costs);
    std::vector<WorkUnit> units;
    while (auto u = s.next()) units.push_back(*u);
    for (const WorkUnit& u : units) {
      order->push_back(u.genome_id);
      s.complete(result(u.genome_id, u.unit, 0.25 * static_cast<double>(u.genome_id + u.unit)));
    }
    return s.outcomes();
  };
  std::vector<std::int64_t> fixed, longest_first;
  const std::vector<GenomeOutcome> a = run({}, &fixed);
  // Ties (4 and 2 cost 5) keep member order; a genome's units stay in task order.
  const std::vector<GenomeOutcome> b = run({5.0, 1.0, 9.0, 5.0}, &longest_first);
  EXPECT_EQ(fixed, (std::vector<std::int64_t>{4, 4, 1, 1, 7, 7, 2, 2}));
  EXPECT_EQ(longest_first, (std::vector<std::int64_t>{7, 7, 4, 4, 2, 2, 1, 1}));
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t m = 0; m < a.size(); ++m) {  // member order, whatever the hand-out order
    EXPECT_EQ(a[m].genome_id, ids[m]);
    EXPECT_EQ(b[m].genome_id, ids[m]);
    EXPECT_EQ(a[m].fitness, b[m].fitness);
  }
  EXPECT_THROW(GenerationScheduler(0, ids, *directed.task, {1.0, 2.0}), SchedulerError);
  EXPECT_THROW(GenerationScheduler(0, ids, *directed.task, {1.0, 2.0, 3.0, std::nan("")}),
               SchedulerError);
}

TEST(Scheduler, OutcomesDoNotDependOnArrivalOrder) {
  const std::vector<std::int64_t> ids = {4, 1, 7};
  std::vector<std::vector<GenomeOutcome>> all;
  for (unsigned seed : {1u, 2u, 3u}) {
    const TaskOf directed(TaskKind::directed, 5);
    GenerationScheduler s(2, ids, *directed.task);
    std::vector<WorkUnit> units;
    while (auto u = s.next()) units.push_back(*u);
    ASSERT_EQ(units.size(), 15u);
    std::mt19937 g(seed);
    std::shuffle(units.begin(), units.end(), g);
    for (const WorkUnit& u : units)
      s.complete(result(u.genome_id, u.unit, 0.1 * u.genome_id + u.unit));
    ASSERT_TRUE(s.done());
    all.push_back(s.outcomes());
  }
  for (std::size_t k = 1; k < all.size(); ++k)
    for (std::size_t m = 0; m < ids.size(); ++m) {
      EXPECT_EQ(all[k][m].fitness, all[0][m].fitness);
      EXPECT_EQ(all[k][m].genome_id, ids[m]);
    }
  // §7.4: F = sum over the directions in order.
  const double expect = ((((0.4 + 0.0) + 1.4) + 2.4) + 3.4) + 4.4;
  EXPECT_EQ(all[0][0].fitness, expect);
  EXPECT_EQ(all[0][0].components.size(), 5u);
  EXPECT_EQ(all[0][0].components[3].values[1], 2 * 3.4);  // distance
  EXPECT_EQ(all[0][0].wall_seconds, 5.0);
}

TEST(Scheduler, AnyUnitNotOkScoresZero) {
  const TaskOf directed(TaskKind::directed, 3);
  GenerationScheduler s(0, {1}, *directed.task);
  while (auto u = s.next())
    s.complete(result(1, u->unit, 5.0, u->unit == 1 ? EvalStatus::killed_flipped : EvalStatus::ok));
  const auto o = s.outcomes();
  EXPECT_EQ(o[0].fitness, 0.0);
  EXPECT_EQ(o[0].status, EvalStatus::killed_flipped);
  EXPECT_EQ(o[0].components[1].status, EvalStatus::killed_flipped);
  EXPECT_TRUE(s.failures().empty());  // a killed robot is not a failure
}

TEST(Scheduler, FailuresAreListed) {
  GenerationScheduler s(0, {1, 2}, *kGait.task);
  s.next();
  s.next();
  s.complete(result(1, 0, 0.0, EvalStatus::failed));
  s.complete(result(2, 0, 1.0));
  ASSERT_EQ(s.failures().size(), 1u);
  EXPECT_EQ(s.failures()[0]->genome_id, 1);
}

TEST(Scheduler, RejectsBookkeepingErrors) {
  EXPECT_THROW(GenerationScheduler(0, {1, 1}, *kGait.task), SchedulerError);
  const TaskOf no_directions(TaskKind::directed, 0);
  EXPECT_THROW(GenerationScheduler(0, {1}, *no_directions.task), SchedulerError);  // no unit
  GenerationScheduler s(0, {1, 2}, *kGait.task);
  EXPECT_THROW(s.complete(result(1, 0, 0.0)), SchedulerError);  // not handed out
  s.next();
  EXPECT_THROW(s.complete(result(3, 0, 0.0)), SchedulerError);  // unknown id
  EXPECT_THROW(s.complete(result(1, 1, 0.0)), SchedulerError);  // gait has one unit
  EXPECT_THROW(s.complete(result(1, -1, 0.0)), SchedulerError);
  s.complete(result(1, 0, 0.0));
  EXPECT_THROW(s.complete(result(1, 0, 0.0)), SchedulerError);  // duplicate
  EXPECT_THROW(s.outcomes(), SchedulerError);                   // not done
}

}  // namespace
}  // namespace softevo::master
