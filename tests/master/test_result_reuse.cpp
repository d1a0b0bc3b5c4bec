// Reuse of earlier results (master/result_reuse.hpp): what is remembered from an archived
// generation, which members reuse what, and that failed or timed-out results are simulated again.
#include "master/result_reuse.hpp"

#include <gtest/gtest.h>

namespace softevo::master {
namespace {

using Bytes = std::vector<std::uint8_t>;

// A gait generation of three rows: ids 10, 11, 12 with genomes A, B, C.
io::GenerationRecord generation(std::vector<EvalStatus> status) {
  io::GenerationRecord r;
  r.generation = 3;
  r.id = {10, 11, 12};
  r.genome = {Bytes{1, 2}, Bytes{3}, Bytes{4, 5, 6}};
  r.units = 1;
  r.component_columns = {"fitness", "distance", "status"};
  for (std::size_t i = 0; i < 3; ++i) {
    r.status.push_back(static_cast<std::uint8_t>(status[i]));
    r.fitness.push_back(status[i] == EvalStatus::ok ? 1.5 + static_cast<double>(i) : 0.0);
    r.voxels.push_back(100 + static_cast<std::int32_t>(i));
    r.chambers.push_back(2);
    r.components.insert(r.components.end(), {r.fitness.back(), 7.0 + static_cast<double>(i),
                                             static_cast<double>(status[i])});
  }
  return r;
}

TEST(ResultReuse, OnlyResultsThatDependOnTheInputsAloneAreReused) {
  EXPECT_TRUE(reusable(EvalStatus::ok));
  EXPECT_TRUE(reusable(EvalStatus::killed_flipped));
  EXPECT_TRUE(reusable(EvalStatus::diverged));
  EXPECT_TRUE(reusable(EvalStatus::invalid_body));
  EXPECT_FALSE(reusable(EvalStatus::failed));
  EXPECT_FALSE(reusable(EvalStatus::timeout));
  ResultMemory memory;
  memory.remember(generation({EvalStatus::ok, EvalStatus::timeout, EvalStatus::killed_exploded}));
  EXPECT_EQ(memory.size(), 2u);
  EXPECT_EQ(memory.find(Bytes{3}), nullptr);  // timed out: simulated again
  const ReusableResult* a = memory.find(Bytes{1, 2});
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->origin_id, 10);
  EXPECT_EQ(a->fitness, 1.5);
  EXPECT_EQ(a->voxels, 100);
  EXPECT_EQ(a->components, (std::vector<double>{1.5, 7.0, 0.0}));
  const ReusableResult* c = memory.find(Bytes{4, 5, 6});
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->status, static_cast<std::uint8_t>(EvalStatus::killed_exploded));
  EXPECT_EQ(memory.find(Bytes{4, 5}), nullptr);  // bytes compared exactly
}

TEST(ResultReuse, AReusedRowPointsAtTheRowThatWasEvaluated) {
  io::GenerationRecord r = generation({EvalStatus::ok, EvalStatus::ok, EvalStatus::ok});
  r.reused_from = {io::kNotReused, 4, io::kNotReused};  // 11 reused id 4 of an older generation
  ResultMemory memory;
  memory.remember(r);
  EXPECT_EQ(memory.find(Bytes{3})->origin_id, 4);
  EXPECT_EQ(memory.find(Bytes{1, 2})->origin_id, 10);
  // The next remember() forgets the previous generation.
  memory.remember(generation({EvalStatus::failed, EvalStatus::failed, EvalStatus::failed}));
  EXPECT_EQ(memory.size(), 0u);
}

TEST(ResultReuse, PlanEvaluatesEachNewGenomeOnceAtItsLowestId) {
  ResultMemory memory;
  memory.remember(generation({EvalStatus::ok, EvalStatus::ok, EvalStatus::ok}));
  // Members: 20 = A (elite: known), 22 = D, 21 = D (duplicate, lower id), 23 = E, 24 = D.
  const std::vector<std::int64_t> ids = {20, 22, 21, 23, 24};
  const std::vector<Bytes> genomes = {Bytes{1, 2}, Bytes{9}, Bytes{9}, Bytes{8}, Bytes{9}};
  const ReusePlan plan = plan_reuse(ids, genomes, &memory);
  EXPECT_EQ(plan.evaluate, (std::vector<std::size_t>{2, 3}));  // 21 and 23, member order
  EXPECT_EQ(plan.reused(), 3u);
  EXPECT_EQ(plan.source[0].kind, ResultSource::Kind::earlier_generation);
  EXPECT_EQ(plan.source[0].origin_id, 10);
  EXPECT_EQ(plan.source[0].earlier->fitness, 1.5);
  for (std::size_t m : {1u, 4u}) {
    EXPECT_EQ(plan.source[m].kind, ResultSource::Kind::same_generation);
    EXPECT_EQ(plan.source[m].member, 2u);
    EXPECT_EQ(plan.source[m].origin_id, 21);
  }
  EXPECT_EQ(plan.source[2].origin_id, io::kNotReused);
  // Without a memory (reuse off) every member is evaluated, duplicates too.
  const ReusePlan all = plan_reuse(ids, genomes, nullptr);
  EXPECT_EQ(all.evaluate.size(), 5u);
  EXPECT_EQ(all.reused(), 0u);
  EXPECT_THROW(plan_reuse({1}, {}, &memory), std::invalid_argument);
}

// A ground drawn per generation differs from the remembered generation's: the elite is evaluated
// again, while equal genomes of one generation (one ground) still share a result. A ground per
// evaluation differs between genome ids: nothing is shared. One ground per run: everything is.
TEST(ResultReuse, TheGroundLimitsWhatIsShared) {
  ResultMemory memory;
  memory.remember(generation({EvalStatus::ok, EvalStatus::ok, EvalStatus::ok}));
  const std::vector<std::int64_t> ids = {20, 22, 21};
  const std::vector<Bytes> genomes = {Bytes{1, 2}, Bytes{9}, Bytes{9}};
  TerrainConfig ground;
  ground.kind = GroundKind::heightfield;
  auto scope = [&](TerrainResample resample) {
    ground.resample = resample;
    return reuse_scope(ground);
  };
  const ReusePlan per_run = plan_reuse(ids, genomes, &memory, scope(TerrainResample::per_run));
  EXPECT_EQ(per_run.evaluate, (std::vector<std::size_t>{2}));
  const ReusePlan per_generation =
      plan_reuse(ids, genomes, &memory, scope(TerrainResample::per_generation));
  EXPECT_EQ(per_generation.evaluate, (std::vector<std::size_t>{0, 2}));
  EXPECT_EQ(per_generation.source[0].kind, ResultSource::Kind::evaluated);
  EXPECT_EQ(per_generation.source[0].origin_id, io::kNotReused);
  EXPECT_EQ(per_generation.source[1].kind, ResultSource::Kind::same_generation);
  EXPECT_EQ(per_generation.source[1].origin_id, 21);
  const ReusePlan per_evaluation =
      plan_reuse(ids, genomes, &memory, scope(TerrainResample::per_evaluation));
  EXPECT_EQ(per_evaluation.evaluate, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(per_evaluation.reused(), 0u);
  // Flat ground draws nothing: all is shared whatever resample says.
  ground.kind = GroundKind::flat;
  EXPECT_EQ(plan_reuse(ids, genomes, &memory, scope(TerrainResample::per_evaluation)).evaluate,
            (std::vector<std::size_t>{2}));
}

}  // namespace
}  // namespace softevo::master
