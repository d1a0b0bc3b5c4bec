// master/progress.hpp: what a generation line says (fitness with its unit, every status count,
// elapsed time), when a generation is flagged, and when the live line is shown.
#include "master/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>

namespace softevo::master {
namespace {

GenerationSummary summary_of(StatusCounts counts, double max_abs_ok_fitness) {
  GenerationSummary s;
  s.generation = 3;
  s.best = 1.5;
  s.mean = 0.25;
  s.species = 2;
  s.evaluations = 12;
  s.eval_wall_seconds = 4.0;
  s.status_counts = counts;
  s.max_abs_ok_fitness = max_abs_ok_fitness;
  s.fitness_unit = "cm";
  return s;
}

StatusCounts counts(std::int64_t ok, std::int64_t flipped, std::int64_t exploded,
                    std::int64_t diverged, std::int64_t failed, std::int64_t timeout = 0,
                    std::int64_t invalid = 0) {
  return {ok, flipped, exploded, diverged, failed, timeout, invalid};
}

TEST(Progress, TheGenerationLineCountsEveryStatusAndNamesTheFitnessUnit) {
  const std::string line = generation_line(summary_of(counts(9, 1, 2, 0, 0), 1.5), 10, 75.0, 150.0);
  EXPECT_NE(line.find("gen      3/10"), std::string::npos) << line;
  EXPECT_NE(line.find("best     1.5000 cm"), std::string::npos) << line;
  EXPECT_NE(line.find("mean     0.2500 cm"), std::string::npos) << line;
  EXPECT_NE(line.find("ok 9, flipped 1, exploded 2, diverged 0, failed 0"), std::string::npos)
      << line;
  EXPECT_EQ(line.find("timeout"), std::string::npos) << line;  // shown only when it occurs
  EXPECT_NE(line.find("elapsed 1m15s"), std::string::npos) << line;
  EXPECT_NE(line.find("ETA 2m30s"), std::string::npos) << line;
  EXPECT_NE(line.find("eval/s    3.00"), std::string::npos) << line;
}

TEST(Progress, ReusedUnitsAreCountedWhenThereAreAny) {
  GenerationSummary s = summary_of(counts(12, 0, 0, 0, 0), 1.5);
  EXPECT_EQ(generation_line(s, 10, 1.0, 1.0).find("reused"), std::string::npos);
  s.reused = 4;
  const std::string line = generation_line(s, 10, 1.0, 1.0);
  EXPECT_NE(line.find("  reused 4"), std::string::npos) << line;
}

TEST(Progress, LearningIsReportedWhenBodiesLearned) {
  GenerationSummary s = summary_of(counts(12, 0, 0, 0, 0), 1.5);
  EXPECT_EQ(generation_line(s, 10, 1.0, 1.0).find("learned"), std::string::npos);
  s.learned_bodies = 12;
  s.learning_iterations = 10;
  s.learning_gain_mean = 0.5;
  s.learning_gain_best = 2.0;
  const std::string line = generation_line(s, 10, 1.0, 1.0);
  EXPECT_NE(line.find("  learned 12 x 10 it, gain mean +0.5000 cm best +2.0000 cm"),
            std::string::npos)
      << line;
}

// The live line names the learning round, its bodies and the gain so far.
TEST(Progress, TheLiveLineNamesTheLearningRound) {
  std::FILE* live = std::tmpfile();
  ASSERT_NE(live, nullptr);
  ProgressReporter reporter(nullptr, live, nullptr, 10);
  reporter.generation_started(4, 20);
  reporter.learning_started(LearningProgress{3, 10, 7, 0.25, 1.5});
  reporter.unit_done(0, 70);
  std::rewind(live);
  std::string text;
  for (int c = std::fgetc(live); c != EOF; c = std::fgetc(live))
    text.push_back(static_cast<char>(c));
  std::fclose(live);
  EXPECT_NE(text.find("gen 4 learn 3/10 (7 bodies): 0/70 evaluations"), std::string::npos) << text;
  EXPECT_NE(text.find("gain mean +0.25 best +1.5"), std::string::npos) << text;
  // Round 0 (the bodies as born) had the generation's plain line.
  EXPECT_LT(text.find("gen 4: 0/20 evaluations"), text.find("learn")) << text;
}

TEST(Progress, RareStatusesAreCountedWhenTheyOccur) {
  EXPECT_EQ(status_counts_text(counts(1, 0, 0, 0, 0, 2, 3)),
            "ok 1, flipped 0, exploded 0, diverged 0, failed 0, timeout 2, invalid body 3");
}

TEST(Progress, AWhollyKilledGenerationIsFlagged) {
  const std::string w = generation_warning(summary_of(counts(0, 10, 2, 0, 0), 0.0));
  EXPECT_NE(w.find("generation 3: all 12 robots were killed"), std::string::npos) << w;
  EXPECT_NE(w.find("flipped 10, exploded 2"), std::string::npos) << w;
}

TEST(Progress, AGenerationInWhichNothingMovedIsFlagged) {
  const std::string w = generation_warning(summary_of(counts(12, 0, 0, 0, 0), 0.0));
  EXPECT_NE(w.find("none of the 12 robots that finished moved"), std::string::npos) << w;
  EXPECT_NE(w.find("0 cm"), std::string::npos) << w;
}

TEST(Progress, AnOrdinaryGenerationIsNotFlagged) {
  EXPECT_EQ(generation_warning(summary_of(counts(11, 1, 0, 0, 0), 0.01)), "");
  EXPECT_EQ(generation_warning(summary_of(counts(0, 0, 0, 0, 0), 0.0)), "");  // nothing evaluated
}

TEST(Progress, ProgressModesParse) {
  EXPECT_EQ(parse_progress_mode("auto"), ProgressMode::automatic);
  EXPECT_EQ(parse_progress_mode("always"), ProgressMode::always);
  EXPECT_EQ(parse_progress_mode("never"), ProgressMode::never);
  EXPECT_EQ(parse_progress_mode("sometimes"), std::nullopt);
}

TEST(Progress, AutoShowsTheLiveLineToAPersonOnly) {
  std::map<std::string, std::string> vars;
  const auto env = [&vars](const char* name) -> const char* {
    const auto it = vars.find(name);
    return it == vars.end() ? nullptr : it->second.c_str();
  };
  const auto live = [&](StreamKind kind) {
    return show_live_line(ProgressMode::automatic, kind, env);
  };
  EXPECT_TRUE(live(StreamKind::terminal));
  EXPECT_FALSE(live(StreamKind::pipe));   // a pipe to no launcher: another program reads it
  EXPECT_FALSE(live(StreamKind::other));  // a file
  vars["OMPI_COMM_WORLD_SIZE"] = "3";     // mpirun forwards rank 0's stderr to its terminal
  EXPECT_TRUE(live(StreamKind::pipe));
  EXPECT_FALSE(live(StreamKind::other));  // mpirun ... 2> log
  vars.clear();
  vars["SLURM_STEP_ID"] = "0";  // srun
  EXPECT_TRUE(live(StreamKind::pipe));
  vars["ENVIRONMENT"] = "BATCH";  // inside sbatch: the output is a log file
  EXPECT_FALSE(live(StreamKind::pipe));
  vars.clear();
  vars["PMIX_RANK"] = "0";
  vars["PBS_ENVIRONMENT"] = "PBS_BATCH";
  EXPECT_FALSE(live(StreamKind::pipe));
  EXPECT_TRUE(show_live_line(ProgressMode::always, StreamKind::other, env));
  EXPECT_FALSE(show_live_line(ProgressMode::never, StreamKind::terminal, env));
}

}  // namespace
}  // namespace softevo::master
