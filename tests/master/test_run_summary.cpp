// The summary of a run archive that `softevo info` prints (master/run_summary.hpp): stats,
// digests, statuses in EvalStatus order, the champion of the last generation, and what is left
// empty when a part cannot be read.
#include "master/run_summary.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "tests/io/tmp_dir.hpp"
#include "tests/master/fake_run.hpp"

namespace softevo::master {
namespace {

std::int64_t total(const std::vector<StatusCount>& counts) {
  std::int64_t n = 0;
  for (const StatusCount& c : counts) n += c.count;
  return n;
}

TEST(RunSummary, SummarisesACompleteRun) {
  test::TmpDir dir(true);
  const std::string out = dir.file("run.h5");
  const Config config = small_config();  // 6 members, 4 generations, gait
  ASSERT_EQ(run_once(config, out, false), RunOutcome::complete);
  const RunSummary s = summarize_run(out);
  EXPECT_EQ(s.info.state, io::RunState::complete);
  EXPECT_EQ(s.info.generations_done, 4);
  EXPECT_TRUE(s.check.ok()) << s.check.describe(out);
  EXPECT_FALSE(s.lock_holder);
  EXPECT_FALSE(s.state_note);
  EXPECT_EQ(s.fitness_unit, "cm");
  ASSERT_EQ(s.stats.size(), 4u);
  EXPECT_EQ(s.fitness_digest, fitness_digest_of(out));
  EXPECT_EQ(s.content_digest.size(), 16u);
  EXPECT_EQ(s.checkpoint_generation, 4);
  EXPECT_EQ(s.config_text, io::Archive(out).config_text());
  EXPECT_FALSE(s.learning);

  // Statuses: every EvalStatus in order, zeros included; 6 robots in each of 4 generations.
  ASSERT_EQ(s.statuses.size(), static_cast<std::size_t>(EvalStatus::invalid_body) + 1);
  EXPECT_EQ(s.statuses.front().status, "ok");
  EXPECT_EQ(s.statuses.back().status, to_string(EvalStatus::invalid_body));
  EXPECT_EQ(total(s.statuses), 24);
  EXPECT_EQ(total(s.last_generation_statuses), 6);

  // The champion is the best row of the last generation.
  const io::GenerationRecord last = io::Archive(out).generation(3);
  ASSERT_TRUE(s.champion);
  EXPECT_EQ(s.champion->generation, 3);
  EXPECT_EQ(s.champion->fitness, *std::max_element(last.fitness.begin(), last.fitness.end()));
  EXPECT_EQ(s.champion->fitness, s.stats.back().best);
  EXPECT_EQ(s.champion->status, "ok");
  EXPECT_FALSE(s.champion->fitness_before);
}

TEST(RunSummary, LearningTotalsCountOnlyBodiesEvaluatedInTheirGeneration) {
  io::GenerationRecord r;
  r.id = {1, 2, 3};
  r.fitness = {5.0, 3.0, 9.0};
  r.fitness_before = {4.0, 3.5, 1.0};
  r.learn_evaluations = {10, 10, 10};
  r.reused_from = {io::kNotReused, io::kNotReused, 7};  // 3 learned in an earlier generation
  r.learning_points = 4;
  LearningTotals t;
  EXPECT_EQ(t.mean_gain(), 0.0);
  t.add(r);
  EXPECT_EQ(t.bodies, 2);
  EXPECT_EQ(t.evaluations, 20);
  EXPECT_EQ(t.iterations, 3);
  EXPECT_EQ(t.gain_best, 1.0);
  EXPECT_EQ(t.mean_gain(), 0.25);  // (1.0 - 0.5) / 2
}

TEST(RunSummary, AMissingArchiveIsAnError) {
  test::TmpDir dir;
  EXPECT_THROW(summarize_run(dir.file("none.h5")), io::ArchiveError);
}

}  // namespace
}  // namespace softevo::master
