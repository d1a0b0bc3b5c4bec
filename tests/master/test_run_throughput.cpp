// Throughput of the run loop (master/run.hpp) without MPI, with the stand-in evaluator of
// fake_run.hpp: reused results mark their rows and leave every digest as it was, the hand-out
// order changes nothing, a --resume rebuilds the same reuse, and several runs in one pool
// (execute_runs) write the archives of the runs alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "io/archive.hpp"
#include "master/run.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/master/fake_run.hpp"

namespace softevo::master {
namespace {

using io::Archive;
using io::GenerationRecord;

RunOptions options_for(const std::string& out, bool reuse, bool longest_first) {
  RunOptions o;
  o.out_path = out;
  o.reuse_results = reuse;
  o.longest_first = longest_first;
  return o;
}

// Counts the evaluations the stand-in evaluator is asked for.
struct CountingEvaluator {
  int* count;
  EvalResult operator()(const EvalRequest& request) const {
    ++*count;
    return fake_evaluation(request);
  }
};

int run_counting(const Config& config, const RunOptions& options) {
  int count = 0;
  PreparedRun run = prepare_run(config, options, 1);
  LocalExecutor executor(CountingEvaluator{&count});
  ProgressReporter progress = ProgressReporter::silent();
  EXPECT_EQ(execute_run(run, executor, progress), RunOutcome::complete);
  return count;
}

std::string content_digest_of(const std::string& path) {
  return hash_hex(io::content_digest(Archive(path)));
}

std::vector<std::vector<std::int64_t>> reused_columns(const std::string& path) {
  const Archive a(path);
  std::vector<std::vector<std::int64_t>> out;
  for (std::int64_t g : a.generations()) out.push_back(a.generation(g).reused_from);
  return out;
}

Config throughput_config() {
  Config c = small_config();
  c.run.generations = 5;
  c.neat.pop_size = 8;
  return c;
}

TEST(RunThroughput, ReusedRowsAreMarkedAndTheDigestsStayAsTheyWere) {
  const test::TmpDir dir;
  const Config config = throughput_config();
  const std::string all = dir.file("all.h5"), reused = dir.file("reused.h5");
  const int simulated_all = run_counting(config, options_for(all, false, false));
  const int simulated = run_counting(config, options_for(reused, true, true));
  EXPECT_EQ(fitness_digest_of(reused), fitness_digest_of(all));
  EXPECT_EQ(content_digest_of(reused), content_digest_of(all));

  const Archive a(reused);
  std::int64_t marked = 0;
  std::vector<std::int64_t> evaluated_ids;  // rows of every generation so far that were simulated
  for (std::int64_t g : a.generations()) {
    const GenerationRecord r = a.generation(g);
    ASSERT_EQ(r.reused_from.size(), r.size());
    EXPECT_EQ(r.evaluations, static_cast<std::int64_t>(r.size()));  // all units, reused too
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (r.reused_from[i] == io::kNotReused) {
        evaluated_ids.push_back(r.id[i]);
        EXPECT_GE(r.worker_rank[i], 0);
        continue;
      }
      ++marked;
      EXPECT_EQ(r.wall_seconds[i], 0.0);
      EXPECT_EQ(r.worker_rank[i], -1);
      // It points at a row that was simulated, in this generation or an earlier one.
      EXPECT_NE(std::find(evaluated_ids.begin(), evaluated_ids.end(), r.reused_from[i]),
                evaluated_ids.end())
          << "generation " << g << " id " << r.id[i] << " reused_from " << r.reused_from[i];
    }
    if (g > 0) {
      EXPECT_GT(std::count_if(r.reused_from.begin(), r.reused_from.end(),
                              [](std::int64_t f) { return f != io::kNotReused; }),
                0)
          << "generation " << g << ": the elites carried over were simulated again";
    }
  }
  EXPECT_EQ(simulated + marked, simulated_all);
  // The archive without reuse marks nothing.
  for (const std::vector<std::int64_t>& column : reused_columns(all))
    for (std::int64_t f : column) EXPECT_EQ(f, io::kNotReused);
}

// With a ground drawn per generation an evaluation depends on the generation too (docs/model.md
// §2.8a "Seeds and resampling"): the stand-in evaluator here adds the generation to the fitness.
// A carried-over elite is evaluated again on the new ground, so the run with reuse gives the
// digests of the run that evaluates everything, and no row reuses an earlier generation's.
struct PerGenerationGroundEvaluator {
  EvalResult operator()(const EvalRequest& request) const {
    EvalResult r = fake_evaluation(request);
    r.fitness += static_cast<double>(request.generation);
    for (UnitFitness& u : r.components) {
      u.fitness = r.fitness;
      std::fill(u.values.begin(), u.values.end(), r.fitness);
    }
    return r;
  }
};

TEST(RunThroughput, AGroundDrawnPerGenerationIsNeverReusedAcrossGenerations) {
  const test::TmpDir dir;
  Config config = throughput_config();
  config.terrain.kind = GroundKind::heightfield;
  config.terrain.resample = TerrainResample::per_generation;
  const std::string all = dir.file("all.h5"), reused = dir.file("reused.h5");
  for (const auto& [out, reuse] : {std::pair{all, false}, std::pair{reused, true}}) {
    PreparedRun run = prepare_run(config, options_for(out, reuse, true), 1);
    LocalExecutor executor(PerGenerationGroundEvaluator{});
    ProgressReporter progress = ProgressReporter::silent();
    ASSERT_EQ(execute_run(run, executor, progress), RunOutcome::complete);
  }
  EXPECT_EQ(fitness_digest_of(reused), fitness_digest_of(all));
  EXPECT_EQ(content_digest_of(reused), content_digest_of(all));
  const Archive a(reused);
  for (std::int64_t g : a.generations()) {
    const GenerationRecord r = a.generation(g);
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (r.reused_from[i] == io::kNotReused) continue;
      EXPECT_NE(std::find(r.id.begin(), r.id.end(), r.reused_from[i]), r.id.end())
          << "generation " << g << " id " << r.id[i] << " reuses " << r.reused_from[i]
          << ", a row of an earlier generation and its ground";
    }
  }
}

TEST(RunThroughput, TheHandOutOrderChangesNoBit) {
  const test::TmpDir dir;
  Config config = throughput_config();
  config.task.kind = TaskKind::directed;  // several units per genome
  const std::string fixed = dir.file("fixed.h5"), longest = dir.file("longest.h5");
  run_counting(config, options_for(fixed, true, false));
  run_counting(config, options_for(longest, true, true));
  EXPECT_EQ(fitness_digest_of(fixed), fitness_digest_of(longest));
  EXPECT_EQ(content_digest_of(fixed), content_digest_of(longest));
  EXPECT_EQ(reused_columns(fixed), reused_columns(longest));
}

TEST(RunThroughput, ResumeRebuildsTheReuseOfTheUninterruptedRun) {
  const test::TmpDir dir;
  const Config config = throughput_config();
  const std::string ref = dir.file("ref.h5"), out = dir.file("out.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  // A full disk at the segment of generation 3: generations 0-2 stay, --resume continues.
  int updates = 0;
  EXPECT_THROW(run_once(config, out, false,
                        [&](const std::string& step) {
                          if (step == "segment: create" && ++updates == 4)
                            throw std::system_error(ENOSPC, std::generic_category(), step);
                        }),
               RunError);
  ASSERT_EQ(Archive(out).info().generations_done, 3);
  ASSERT_EQ(run_once(config, out, true), RunOutcome::complete);
  EXPECT_EQ(fitness_digest_of(out), fitness_digest_of(ref));
  EXPECT_EQ(content_digest_of(out), content_digest_of(ref));
  EXPECT_EQ(reused_columns(out), reused_columns(ref));
}

TEST(RunThroughput, SeveralRunsInOnePoolWriteTheArchivesOfTheRunsAlone) {
  const test::TmpDir dir;
  std::vector<Config> configs;
  for (std::int64_t seed : {11, 12, 13}) {
    Config c = throughput_config();
    c.run.seed = seed;
    c.run.generations = 3 + seed % 2;  // runs of different lengths
    configs.push_back(c);
  }
  std::vector<PreparedRun> runs;
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const std::string alone = dir.file("alone-" + std::to_string(i) + ".h5");
    ASSERT_EQ(run_once(configs[i], alone, false), RunOutcome::complete);
    RunOptions o;
    o.out_path = dir.file("pooled-" + std::to_string(i) + ".h5");
    runs.push_back(prepare_run(configs[i], o, 1));
  }
  std::vector<PreparedRun*> pointers;
  std::vector<ProgressReporter> reporters(runs.size(), ProgressReporter::silent());
  std::vector<ProgressReporter*> progress;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    pointers.push_back(&runs[i]);
    progress.push_back(&reporters[i]);
  }
  LocalExecutor executor(fake_evaluation);
  const std::vector<RunOutcome> outcomes = execute_runs(pointers, executor, progress);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    EXPECT_EQ(outcomes[i], RunOutcome::complete);
    const std::string alone = dir.file("alone-" + std::to_string(i) + ".h5");
    const std::string pooled = dir.file("pooled-" + std::to_string(i) + ".h5");
    EXPECT_EQ(fitness_digest_of(pooled), fitness_digest_of(alone)) << i;
    EXPECT_EQ(content_digest_of(pooled), content_digest_of(alone)) << i;
    EXPECT_EQ(reused_columns(pooled), reused_columns(alone)) << i;
  }
  EXPECT_THROW(execute_runs(pointers, executor, {}), std::invalid_argument);
}

}  // namespace
}  // namespace softevo::master
