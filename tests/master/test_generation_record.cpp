// A finished generation's archive rows (master/generation_record.hpp): rows in id order, each
// from its own evaluation, an earlier generation's result or a same-generation twin's; the
// group attributes, the stats row and the progress summary made from them.
#include "master/generation_record.hpp"

#include <gtest/gtest.h>

#include <memory>

namespace softevo::master {
namespace {

using Bytes = std::vector<std::uint8_t>;

// A gait generation of four members, in population order ids 23, 20, 22, 21: 20 has genome A,
// which generation 4 evaluated as id 7; 21 and 23 share genome D (21, the lower id, is
// evaluated); 22 has genome E.
struct Fixture {
  Fixture() {
    task = tasks::make_task(config);
    for (std::int64_t id : {23, 20, 22, 21}) {
      evo::Individual m;
      m.id = id;
      m.parent1 = id - 10;
      m.species = id % 2;
      members.push_back(m);
    }
    encoded = {Bytes{9}, Bytes{1, 2}, Bytes{8}, Bytes{9}};
    io::GenerationRecord earlier;
    earlier.generation = 4;
    earlier.id = {7};
    earlier.genome = {Bytes{1, 2}};
    earlier.status = {static_cast<std::uint8_t>(EvalStatus::ok)};
    earlier.fitness = {1.25};
    earlier.voxels = {30};
    earlier.chambers = {1};
    earlier.units = 1;
    earlier.component_columns = tasks::component_columns(*task);
    earlier.components = {1.25, 0.5, 0.0};
    memory.remember(earlier);
    plan = plan_reuse({23, 20, 22, 21}, encoded, &memory);
    // plan.evaluate = members 2 (id 22) and 3 (id 21).
    evaluated = {outcome(22, 3.0, EvalStatus::ok, 2.0), outcome(21, -4.0, EvalStatus::ok, 5.0)};
  }
  static GenomeOutcome outcome(std::int64_t id, double fitness, EvalStatus status, double seconds) {
    GenomeOutcome o;
    o.genome_id = id;
    o.status = status;
    o.fitness = fitness;
    o.components = {UnitFitness{fitness, status, {fitness * 2}}};
    o.voxels = 40;
    o.chambers = 2;
    o.wall_seconds = seconds;
    o.worker_rank = 3;
    return o;
  }
  io::GenerationRecord record() const {
    return generation_record(GenerationInputs{.generation = 5,
                                              .task = *task,
                                              .members = members,
                                              .encoded = encoded,
                                              .plan = plan,
                                              .evaluated = evaluated,
                                              .learned = nullptr,
                                              .species_count = 2,
                                              .eval_wall_seconds = 4.0});
  }
  Config config;
  std::unique_ptr<tasks::Task> task;
  std::vector<evo::Individual> members;
  std::vector<Bytes> encoded;
  ResultMemory memory;
  ReusePlan plan;
  std::vector<GenomeOutcome> evaluated;
};

TEST(GenerationRecord, RowsAreInIdOrderWithTheirParentsAndGenomes) {
  const Fixture f;
  ASSERT_EQ(f.plan.evaluate, (std::vector<std::size_t>{2, 3}));
  const io::GenerationRecord rec = f.record();
  EXPECT_NO_THROW(rec.check());
  EXPECT_EQ(rec.generation, 5);
  EXPECT_EQ(rec.id, (std::vector<std::int64_t>{20, 21, 22, 23}));
  EXPECT_EQ(rec.parent1, (std::vector<std::int64_t>{10, 11, 12, 13}));
  EXPECT_EQ(rec.species, (std::vector<std::int64_t>{0, 1, 0, 1}));
  EXPECT_EQ(rec.genome, (std::vector<Bytes>{Bytes{1, 2}, Bytes{9}, Bytes{8}, Bytes{9}}));
  EXPECT_EQ(rec.component_columns, tasks::component_columns(*f.task));
}

TEST(GenerationRecord, EachRowComesFromWhereItsResultWasEvaluated) {
  const io::GenerationRecord rec = Fixture().record();
  // 20: generation 4's id 7; 21, 22: evaluated now; 23: a copy of 21.
  EXPECT_EQ(rec.reused_from, (std::vector<std::int64_t>{7, io::kNotReused, io::kNotReused, 21}));
  EXPECT_EQ(rec.fitness, (std::vector<double>{1.25, -4.0, 3.0, -4.0}));
  EXPECT_EQ(rec.voxels, (std::vector<std::int32_t>{30, 40, 40, 40}));
  // A reused row did not spend the time nor run on a rank.
  EXPECT_EQ(rec.wall_seconds, (std::vector<double>{0.0, 5.0, 2.0, 0.0}));
  EXPECT_EQ(rec.worker_rank, (std::vector<std::int32_t>{-1, 3, 3, -1}));
  EXPECT_EQ(rec.components,
            (std::vector<double>{1.25, 0.5, 0.0, -4.0, -8.0, 0.0, 3.0, 6.0, 0.0, -4.0, -8.0, 0.0}));
  EXPECT_FALSE(rec.has_learning());
}

TEST(GenerationRecord, GroupAttributesCountEveryRowReusedOrNot) {
  const io::GenerationRecord rec = Fixture().record();
  EXPECT_EQ(rec.best, 3.0);
  EXPECT_DOUBLE_EQ(rec.mean, (1.25 - 4.0 + 3.0 - 4.0) / 4);
  EXPECT_EQ(rec.species_count, 2);
  EXPECT_EQ(rec.evaluations, 4);  // 4 rows x 1 gait unit, reused ones included
  EXPECT_EQ(rec.eval_wall_seconds, 4.0);
}

TEST(GenerationRecord, ReproductionSeesEveryRowInIdOrder) {
  io::GenerationRecord rec = Fixture().record();
  rec.status[2] = static_cast<std::uint8_t>(EvalStatus::killed_flipped);
  const std::vector<evo::Evaluation> e = evaluations(rec);
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(e[1].id, 21);
  EXPECT_EQ(e[1].fitness, -4.0);
  EXPECT_FALSE(e[1].killed);
  EXPECT_TRUE(e[2].killed);
}

TEST(GenerationRecord, StatsRowAndSummaryCountSimulatedUnitsOnly) {
  const Fixture f;
  const io::GenerationRecord rec = f.record();
  const GenerationWork work{.simulated_units = 2, .reused_units = 2};
  const io::StatsRow stats = stats_row(rec, work);
  EXPECT_EQ(stats.generation, 5.0);
  EXPECT_EQ(stats.best, 3.0);
  EXPECT_EQ(stats.species_count, 2.0);
  EXPECT_EQ(stats.evaluations_per_second, 0.5);  // 2 units in 4 s
  io::GenerationRecord instant = rec;
  instant.eval_wall_seconds = 0.0;
  EXPECT_EQ(stats_row(instant, work).evaluations_per_second, 0.0);

  const GenerationSummary s = generation_summary(rec, *f.task, work, 6.0, nullptr);
  EXPECT_EQ(s.generation, 5);
  EXPECT_EQ(s.evaluations, 2);
  EXPECT_EQ(s.reused, 2);
  EXPECT_EQ(s.generation_seconds, 6.0);
  EXPECT_EQ(s.fitness_unit, f.task->fitness_unit());
  EXPECT_EQ(s.status_counts[static_cast<std::size_t>(EvalStatus::ok)], 4);
  EXPECT_EQ(s.max_abs_ok_fitness, 4.0);
  EXPECT_EQ(s.learned_bodies, 0);
}

}  // namespace
}  // namespace softevo::master
