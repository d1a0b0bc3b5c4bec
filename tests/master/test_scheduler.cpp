// Self-scheduling of one generation: unit order, results stored by id whatever the arrival
// order, §7.4 combination of directions, bookkeeping errors.
#include "master/scheduler.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace softevo::master {
namespace {

EvalResult result(std::int64_t id, int dir, double fitness, EvalStatus st = EvalStatus::ok) {
  EvalResult r;
  r.genome_id = id;
  r.direction_index = dir;
  r.fitness = fitness;
  r.status = st;
  r.wall_seconds = 1.0;
  r.voxels = 10;
  DirectionComponents c;
  c.distance = fitness * 2;
  r.components.push_back(c);
  return r;
}

TEST(Scheduler, GaitHasOneUnitPerGenome) {
  GenerationScheduler s(0, {5, 3, 9}, 0);
  EXPECT_EQ(s.units_total(), 3u);
  std::vector<std::int64_t> ids;
  while (auto u = s.next()) {
    EXPECT_EQ(u->direction_index, -1);
    ids.push_back(u->genome_id);
  }
  EXPECT_EQ(ids, (std::vector<std::int64_t>{5, 3, 9}));
  EXPECT_FALSE(s.done());
}

TEST(Scheduler, OutcomesDoNotDependOnArrivalOrder) {
  const std::vector<std::int64_t> ids = {4, 1, 7};
  std::vector<std::vector<GenomeOutcome>> all;
  for (unsigned seed : {1u, 2u, 3u}) {
    GenerationScheduler s(2, ids, 5);
    std::vector<WorkUnit> units;
    while (auto u = s.next()) units.push_back(*u);
    ASSERT_EQ(units.size(), 15u);
    std::mt19937 g(seed);
    std::shuffle(units.begin(), units.end(), g);
    for (const WorkUnit& u : units)
      s.complete(result(u.genome_id, u.direction_index, 0.1 * u.genome_id + u.direction_index));
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
  EXPECT_EQ(all[0][0].components[3].distance, 2 * 3.4);
  EXPECT_EQ(all[0][0].wall_seconds, 5.0);
}

TEST(Scheduler, AnyDirectionNotOkScoresZero) {
  GenerationScheduler s(0, {1}, 3);
  while (auto u = s.next())
    s.complete(result(1, u->direction_index, 5.0,
                      u->direction_index == 1 ? EvalStatus::killed_flipped : EvalStatus::ok));
  const auto o = s.outcomes();
  EXPECT_EQ(o[0].fitness, 0.0);
  EXPECT_EQ(o[0].status, EvalStatus::killed_flipped);
  EXPECT_EQ(o[0].components[1].status, EvalStatus::killed_flipped);
  EXPECT_TRUE(s.failures().empty());  // a killed robot is not a failure
}

TEST(Scheduler, FailuresAreListed) {
  GenerationScheduler s(0, {1, 2}, 0);
  s.next();
  s.next();
  s.complete(result(1, -1, 0.0, EvalStatus::failed));
  s.complete(result(2, -1, 1.0));
  ASSERT_EQ(s.failures().size(), 1u);
  EXPECT_EQ(s.failures()[0]->genome_id, 1);
}

TEST(Scheduler, RejectsBookkeepingErrors) {
  EXPECT_THROW(GenerationScheduler(0, {1, 1}, 0), SchedulerError);
  GenerationScheduler s(0, {1, 2}, 0);
  EXPECT_THROW(s.complete(result(1, -1, 0.0)), SchedulerError);  // not handed out
  s.next();
  EXPECT_THROW(s.complete(result(3, -1, 0.0)), SchedulerError);  // unknown id
  EXPECT_THROW(s.complete(result(1, 0, 0.0)), SchedulerError);   // gait has no direction
  s.complete(result(1, -1, 0.0));
  EXPECT_THROW(s.complete(result(1, -1, 0.0)), SchedulerError);  // duplicate
  EXPECT_THROW(s.outcomes(), SchedulerError);                    // not done
}

}  // namespace
}  // namespace softevo::master
