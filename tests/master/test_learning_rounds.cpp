// One generation's controller learning as work units (master/learning_rounds.hpp) and the run
// loop that schedules it (docs/model.md §8.11), without MPI: the evaluator is the stand-in of
// fake_run.hpp (fitness from the genome bytes), so a learning run takes milliseconds.
#include "master/learning_rounds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "master/signals.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/master/fake_run.hpp"

namespace softevo::master {
namespace {

using io::Archive;
using io::GenerationRecord;

Config learning_config(Inheritance inheritance = Inheritance::lamarckian) {
  Config c = small_config();
  c.learning.method = LearningMethod::es;
  c.learning.evaluations = 7;  // born + 3 iterations of 2
  c.learning.population = 2;
  c.learning.inheritance = inheritance;
  c.learning.step_size_factor = 0.5;  // exact in both directions: the stand-in hashes the bytes
  return c;
}

GenomeOutcome outcome(std::int64_t id, double fitness, EvalStatus status = EvalStatus::ok) {
  GenomeOutcome o;
  o.genome_id = id;
  o.fitness = fitness;
  o.status = status;
  o.wall_seconds = 1.0;
  return o;
}

TEST(GenerationLearning, RoundsOfCandidatesAdvanceEveryBodysStrategy) {
  const Config config = learning_config();
  const evo::EvoParams params = evo::evo_params(config, 0);
  Rng rng(1);
  std::vector<evo::Genome> genomes;
  for (int i = 0; i < 3; ++i) genomes.push_back(evo::random_genome(params, rng));
  const std::vector<evo::Genome> born = genomes;
  GenerationLearning learning(
      config, params, 4, {10, 11, 12}, genomes,
      {outcome(10, 1.0), outcome(11, 0.0, EvalStatus::invalid_body), outcome(12, 2.0)},
      {5.0, 0.0, 9.0});
  EXPECT_EQ(learning.iterations(), 3);
  EXPECT_EQ(learning.bodies_learning(), 2u);  // the invalid body does not learn
  std::vector<std::int64_t> ids;
  std::vector<double> costs;
  for (int it = 0; it < 3; ++it) {
    ASSERT_FALSE(learning.finished());
    learning.begin_iteration(ids, costs);
    ASSERT_EQ(ids, (std::vector<std::int64_t>{0, 1, 2, 3}));
    EXPECT_EQ(costs, (std::vector<double>{5.0, 5.0, 9.0, 9.0}));
    const EvalRequest r = learning.request(WorkUnit{2, 2, 0}, 0xabc);
    EXPECT_EQ(r.generation, 4);
    EXPECT_EQ(r.config_hash, 0xabcu);
    EXPECT_EQ(r.genome_id, 2);
    const evo::Genome candidate = evo::decode_genome(r.genome);  // body 12's first candidate
    EXPECT_EQ(evo::encode_genome(evo::Genome{candidate.cppn, {}, {}}),
              evo::encode_genome(evo::Genome{born[2].cppn, {}, {}}));
    // Body 10 gains in iteration 1 only (its second candidate); body 12 never (killed, worse).
    learning.end_iteration({outcome(0, it == 1 ? 0.5 : -1.0), outcome(1, it == 1 ? 3.0 : 0.2),
                            outcome(2, 7.0, EvalStatus::killed_flipped), outcome(3, 1.0)});
  }
  EXPECT_TRUE(learning.finished());
  EXPECT_THROW(learning.begin_iteration(ids, costs), std::logic_error);
  const std::vector<LearnedResult>& r = learning.results();
  EXPECT_EQ(r[0].learned.fitness, 3.0);
  EXPECT_EQ(r[0].learned.genome_id, 10);  // the body's id, not the round-local one
  EXPECT_EQ(r[0].born.fitness, 1.0);
  EXPECT_EQ(r[0].curve, (std::vector<double>{1.0, 1.0, 3.0, 3.0}));
  EXPECT_EQ(r[0].evaluations, 7);
  EXPECT_EQ(r[0].wall_seconds, 7.0);
  EXPECT_NE(evo::encode_genome(r[0].genome), evo::encode_genome(born[0]));
  EXPECT_EQ(r[1].evaluations, 1);
  EXPECT_EQ(r[1].curve, (std::vector<double>{0.0, 0.0, 0.0, 0.0}));
  EXPECT_EQ(evo::encode_genome(r[1].genome), evo::encode_genome(born[1]));
  EXPECT_EQ(r[2].learned.fitness, 2.0);
  EXPECT_EQ(evo::encode_genome(r[2].genome), evo::encode_genome(born[2]));
  EXPECT_EQ(learning.best_improvement(), 2.0);
  EXPECT_EQ(learning.mean_improvement(), 1.0);
}

// The 3 bodies of the test above after round 0, with outcome(id, fitness) for round-0 outcomes.
GenerationLearning three_bodies(const Config& config, const evo::EvoParams& params) {
  Rng rng(1);
  std::vector<evo::Genome> genomes;
  for (int i = 0; i < 3; ++i) genomes.push_back(evo::random_genome(params, rng));
  return GenerationLearning(
      config, params, 4, {10, 11, 12}, genomes,
      {outcome(10, 1.0), outcome(11, 0.0, EvalStatus::invalid_body), outcome(12, 2.0)},
      {5.0, 0.0, 9.0});
}

// Round `it`'s outcomes of three_bodies: body 10 gains in iteration 1, body 12 never.
std::vector<GenomeOutcome> round_outcomes(int it) {
  return {outcome(0, it == 1 ? 0.5 : -1.0), outcome(1, it == 1 ? 3.0 : 0.2),
          outcome(2, 7.0, EvalStatus::killed_flipped), outcome(3, 1.0)};
}

void run_round(GenerationLearning& learning, int it) {
  std::vector<std::int64_t> ids;
  std::vector<double> costs;
  learning.begin_iteration(ids, costs);
  learning.end_iteration(round_outcomes(it));
}

// The run's checkpoint within a learning generation: serialized after round 0 or any
// iteration, the learning continues from the bytes exactly as it would have (candidates sent,
// learned genomes, curves, evaluations, timings).
TEST(GenerationLearning, SerializedBetweenRoundsContinuesBitForBit) {
  const Config config = learning_config();
  const evo::EvoParams params = evo::evo_params(config, 0);
  for (int saved_after = 0; saved_after < 3; ++saved_after) {
    SCOPED_TRACE("saved after " + std::to_string(saved_after) + " iterations");
    GenerationLearning original = three_bodies(config, params);
    for (int it = 0; it < saved_after; ++it) run_round(original, it);
    GenerationLearning restored =
        GenerationLearning::deserialize(original.serialize(), config, params, 4);
    EXPECT_EQ(restored.ids(), (std::vector<std::int64_t>{10, 11, 12}));
    EXPECT_EQ(restored.iteration(), saved_after);
    EXPECT_EQ(restored.bodies_learning(), 2u);
    for (int it = saved_after; it < 3; ++it) {
      std::vector<std::int64_t> ids_o, ids_r;
      std::vector<double> costs_o, costs_r;
      original.begin_iteration(ids_o, costs_o);
      restored.begin_iteration(ids_r, costs_r);
      EXPECT_EQ(ids_r, ids_o);
      EXPECT_EQ(costs_r, costs_o);
      for (std::int64_t id : ids_o)
        EXPECT_EQ(restored.request(WorkUnit{0, id, 0}, 1).genome,
                  original.request(WorkUnit{0, id, 0}, 1).genome);
      original.end_iteration(round_outcomes(it));
      restored.end_iteration(round_outcomes(it));
    }
    ASSERT_TRUE(restored.finished());
    for (std::size_t m = 0; m < 3; ++m) {
      const LearnedResult &a = restored.results()[m], &b = original.results()[m];
      EXPECT_EQ(a.learned.fitness, b.learned.fitness);
      EXPECT_EQ(a.learned.genome_id, b.learned.genome_id);
      EXPECT_EQ(a.born.status, b.born.status);
      EXPECT_EQ(evo::encode_genome(a.genome), evo::encode_genome(b.genome));
      EXPECT_EQ(a.curve, b.curve);
      EXPECT_EQ(a.evaluations, b.evaluations);
      EXPECT_EQ(a.wall_seconds, b.wall_seconds);
    }
    EXPECT_EQ(restored.results()[0].learned.fitness, 3.0);  // it learned across the restore
  }
}

TEST(GenerationLearning, SerializedStateIsRefusedForAnotherGenerationOrConfig) {
  const Config config = learning_config();
  const evo::EvoParams params = evo::evo_params(config, 0);
  GenerationLearning learning = three_bodies(config, params);
  run_round(learning, 0);
  const std::vector<std::uint8_t> bytes = learning.serialize();
  EXPECT_THROW(GenerationLearning::deserialize(bytes, config, params, 5), std::invalid_argument);
  Config other = config;
  other.learning.population = 3;
  EXPECT_THROW(GenerationLearning::deserialize(bytes, other, params, 4), std::invalid_argument);
  other = config;
  other.learning.method = LearningMethod::none;
  EXPECT_THROW(GenerationLearning::deserialize(bytes, other, params, 4), std::invalid_argument);
  EXPECT_THROW(
      GenerationLearning::deserialize(std::span(bytes).first(bytes.size() - 1), config, params, 4),
      WireError);
  // Not while a round is in flight (its candidates are drawn from the saved generators).
  std::vector<std::int64_t> ids;
  std::vector<double> costs;
  learning.begin_iteration(ids, costs);
  EXPECT_THROW(learning.serialize(), std::logic_error);
  // A finished learning is never saved: its results go into the archive.
  learning.end_iteration(round_outcomes(1));
  run_round(learning, 2);
  ASSERT_TRUE(learning.finished());
  EXPECT_THROW(GenerationLearning::deserialize(learning.serialize(), config, params, 4),
               std::invalid_argument);
}

// Every row of every generation of a learning archive, with what the archive promises.
void expect_learning_rows(const std::string& path, const Config& config) {
  const Archive archive(path);
  const std::int64_t iterations =
      evo::learning_iterations(config.learning.evaluations, config.learning.population);
  std::size_t learned = 0, reused = 0;
  for (std::int64_t g : archive.generations()) {
    const GenerationRecord r = archive.generation(g);
    ASSERT_TRUE(r.has_learning()) << "generation " << g;
    ASSERT_EQ(r.learning_points, iterations + 1);
    for (std::size_t i = 0; i < r.size(); ++i) {
      EXPECT_GE(r.fitness[i], r.fitness_before[i]);
      EXPECT_EQ(r.learn_evaluations[i], config.learning.evaluations);  // 7 = 1 + 3 x 2
      const auto curve = r.learning_curve.begin() + static_cast<std::ptrdiff_t>(i * 4);
      EXPECT_EQ(curve[0], r.fitness_before[i]);
      EXPECT_EQ(curve[3], r.fitness[i]);
      EXPECT_TRUE(std::is_sorted(curve, curve + 4));
      // The learned robot evaluates to the archived fitness (the stand-in here, which hashes
      // the step sizes too: those of the evaluated candidate were the strategy's, x factor).
      const evo::Genome learned_genome = evo::decode_genome(r.learned_genome[i]);
      // A row whose genome is its born one was evaluated as born.
      evo::Genome evaluated = learned_genome;
      for (std::vector<double>* v : evo::vectors_of(evaluated.step_sizes))
        for (double& s : *v) s *= config.learning.step_size_factor;
      EvalRequest as_born, as_candidate;
      as_born.genome = r.learned_genome[i];
      as_candidate.genome = evo::encode_genome(evaluated);
      EXPECT_TRUE(fake_evaluation(as_born).fitness == r.fitness[i] ||
                  fake_evaluation(as_candidate).fitness == r.fitness[i])
          << "generation " << g << " id " << r.id[i];
      const evo::Genome genome = evo::decode_genome(r.genome[i]);
      EXPECT_EQ(evo::encode_genome(evo::Genome{learned_genome.cppn, {}, {}}),
                evo::encode_genome(evo::Genome{genome.cppn, {}, {}}));
      if (r.fitness[i] > r.fitness_before[i]) ++learned;
      if (r.reused_from[i] != io::kNotReused) ++reused;
    }
  }
  EXPECT_GT(learned, 0u);  // learning found better controllers
  EXPECT_GT(reused, 0u);   // elites kept their learned result
}

TEST(LearningRun, ArchivesTheLearnedResultOfEveryBody) {
  test::TmpDir dir;
  const Config config = learning_config();
  const std::string out = dir.file("learn.h5");
  ASSERT_EQ(run_once(config, out, false), RunOutcome::complete);
  expect_learning_rows(out, config);
}

TEST(LearningRun, ElitesKeepTheirLearnedResultAndNeverLearnAgain) {
  test::TmpDir dir;
  for (const Inheritance inheritance : {Inheritance::lamarckian, Inheritance::baldwinian}) {
    const Config config = learning_config(inheritance);
    const std::string out = dir.file(std::string(to_string(inheritance)) + ".h5");
    ASSERT_EQ(run_once(config, out, false), RunOutcome::complete);
    const Archive archive(out);
    std::size_t checked = 0;
    for (std::int64_t g = 1; g < config.run.generations; ++g) {
      const GenerationRecord prev = archive.generation(g - 1), cur = archive.generation(g);
      for (std::size_t i = 0; i < cur.size(); ++i) {
        if (cur.reused_from[i] == io::kNotReused) continue;
        const auto origin =
            std::find(prev.id.begin(), prev.id.end(), cur.reused_from[i]) - prev.id.begin();
        if (origin == static_cast<std::ptrdiff_t>(prev.size())) continue;  // within g
        // The reused row repeats its origin's learning, and the genome it carries is the learned
        // one (Lamarckian) or the one it was born with (Baldwinian).
        EXPECT_EQ(cur.fitness[i], prev.fitness[origin]);
        EXPECT_EQ(cur.fitness_before[i], prev.fitness_before[origin]);
        EXPECT_EQ(cur.learned_genome[i], prev.learned_genome[origin]);
        EXPECT_EQ(cur.genome[i], inheritance == Inheritance::lamarckian
                                     ? prev.learned_genome[origin]
                                     : prev.genome[origin]);
        ++checked;
      }
    }
    EXPECT_GT(checked, 0u) << to_string(inheritance);
  }
  EXPECT_NE(fitness_digest_of(dir.file("lamarckian.h5")),
            fitness_digest_of(dir.file("baldwinian.h5")));
}

// A new run of `config` into `out` stopped at its evaluation number `n` (from 1): by a
// stop-now request there (as SIGTERM makes), or with `kill` by a SIGKILL of the process.
RunOutcome run_stopped_at_evaluation(const Config& config, const std::string& out, std::size_t n,
                                     bool kill) {
  RunOptions options;
  options.out_path = out;
  PreparedRun run = prepare_run(config, options, 1);
  std::size_t evaluated = 0;
  LocalExecutor executor([&](const EvalRequest& request) {
    if (++evaluated == n) {
      if (kill) ::raise(SIGKILL);
      request_stop(StopRequest::now);
      return EvalResult{};
    }
    return fake_evaluation(request);
  });
  ProgressReporter progress = ProgressReporter::silent();
  const RunOutcome outcome = execute_run(run, executor, progress);
  clear_stop_request();
  return outcome;
}

TEST(LearningRun, ResumeAfterAStopInALearningRoundGivesTheUninterruptedArchive) {
  test::TmpDir dir;
  const Config config = learning_config();
  const std::string ref = dir.file("ref.h5"), out = dir.file("run.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  // In generation 0's second learning round (6 born, 12 per round).
  EXPECT_EQ(run_stopped_at_evaluation(config, out, 20, false), RunOutcome::interrupted);
  EXPECT_EQ(Archive(out).info().generations_done, 0);
  ASSERT_EQ(run_once(config, out, true), RunOutcome::complete);
  EXPECT_EQ(fitness_digest_of(out), fitness_digest_of(ref));
  EXPECT_EQ(io::content_digest(Archive(out)), io::content_digest(Archive(ref)));
}

// One run (or resume) of `config` into `out` with the stand-in evaluator: the work units it
// evaluated, and its console lines into `lines` when given.
std::size_t evaluations_of_run(const Config& config, const std::string& out, bool resume,
                               std::string* lines = nullptr) {
  RunOptions options;
  options.out_path = out;
  options.resume = resume;
  PreparedRun run = prepare_run(config, options, 1);
  std::size_t evaluated = 0;
  LocalExecutor executor([&](const EvalRequest& request) {
    ++evaluated;
    return fake_evaluation(request);
  });
  std::FILE* console = std::tmpfile();
  ProgressReporter progress(console, nullptr, nullptr, config.run.generations);
  const RunOutcome outcome = execute_run(run, executor, progress);
  EXPECT_EQ(outcome, RunOutcome::complete);
  std::rewind(console);
  for (int c = std::fgetc(console); lines != nullptr && c != EOF; c = std::fgetc(console))
    lines->push_back(static_cast<char>(c));
  std::fclose(console);
  return evaluated;
}

void expect_archives_equal(const std::string& out, const std::string& ref) {
  EXPECT_EQ(fitness_digest_of(out), fitness_digest_of(ref));
  EXPECT_EQ(io::content_digest(Archive(out)), io::content_digest(Archive(ref)));
  EXPECT_EQ(Archive(out).info().state, io::RunState::complete);
  ASSERT_TRUE(Archive(out).checkpoint().has_value());
  EXPECT_TRUE(Archive(out).checkpoint()->learning.empty());  // none after the last generation
}

// Generation 0 of learning_config: 6 born evaluations (round 0), then 6 bodies x 2 candidates
// per iteration, 3 iterations.
constexpr std::size_t kRound0Units = 6;
constexpr std::size_t kIterationUnits = 12;

// SIGKILL in the middle of generation 0's third round (round 0 and iterations 1-2 complete and
// checkpointed): --resume continues with iteration 3, evaluates none of the 30 units before
// it again, and writes the uninterrupted archive.
TEST(LearningRun, KillWithinALearningRoundResumesAfterTheLastCompletedRound) {
  test::TmpDir dir;
  const Config config = learning_config();
  const std::string ref = dir.file("ref.h5"), out = dir.file("run.h5");
  const std::size_t total = evaluations_of_run(config, ref, false);
  const std::size_t kill_at = kRound0Units + 2 * kIterationUnits + 5;
  ASSERT_TRUE(killed_in_child([&] { run_stopped_at_evaluation(config, out, kill_at, true); }));
  {
    const Archive killed(out);
    EXPECT_EQ(killed.info().generations_done, 0);
    ASSERT_TRUE(killed.checkpoint().has_value());
    EXPECT_EQ(killed.checkpoint()->generation, 0);
    EXPECT_FALSE(killed.checkpoint()->learning.empty());
  }
  std::string lines;
  EXPECT_EQ(evaluations_of_run(config, out, true, &lines),
            total - kRound0Units - 2 * kIterationUnits);
  EXPECT_NE(
      lines.find("generation 0: controller learning continues from the checkpoint at "
                 "iteration 3/3 (6 bodies; their born evaluations and iterations 1-2 restored)"),
      std::string::npos)
      << lines;
  expect_archives_equal(out, ref);
}

// A kill at every write step of the checkpoint after generation 0's round 0: before the new
// root is in place the resume starts the generation again, after it the born evaluations are
// kept; either way the archive is the uninterrupted one.
TEST(LearningRun, KillAtEveryWriteStepOfALearningCheckpoint) {
  test::TmpDir dir;
  Config config = learning_config();
  config.run.generations = 1;  // 22 runs: keep each short
  const std::string ref = dir.file("ref.h5"), out = dir.file("run.h5");
  const std::size_t total = evaluations_of_run(config, ref, false);
  // The run's write steps: the archive's creation (a root), then the learning checkpoints of
  // generation 0 (each a root), then its segment.
  std::vector<std::string> steps;
  const std::string count = dir.file("count.h5");
  run_once(config, count, false, [&](const std::string& step) { steps.push_back(step); });
  const auto created = std::find(steps.begin(), steps.end(), "root: fsync directory");
  ASSERT_NE(created, steps.end());
  const std::size_t first = static_cast<std::size_t>(created - steps.begin()) + 1;
  const auto checkpointed = std::find(steps.begin() + static_cast<std::ptrdiff_t>(first),
                                      steps.end(), "root: fsync directory");
  ASSERT_NE(checkpointed, steps.end());
  const std::size_t last = static_cast<std::size_t>(checkpointed - steps.begin());
  ASSERT_EQ(steps[first], "root: create");
  // create .. fsync directory, /checkpoint and the growth of the stop's reserved space included
  ASSERT_EQ(last - first, 11u);
  bool renamed = false;
  for (std::size_t k = first; k <= last; ++k) {
    SCOPED_TRACE("killed before step " + std::to_string(k) + " (" + steps[k] + ")");
    io::remove_archive(out);
    ASSERT_TRUE(killed_in_child([&] {
      std::size_t index = 0;
      run_once(config, out, false, [&](const std::string&) {
        if (index++ == k) ::raise(SIGKILL);
      });
    }));
    renamed = renamed || steps[k - 1] == "root: rename";
    EXPECT_EQ(evaluations_of_run(config, out, true), total - (renamed ? kRound0Units : 0));
    expect_archives_equal(out, ref);
  }
  EXPECT_TRUE(renamed);
}

// An archive of an older build (or of a layout the build cannot read) killed within a learning
// generation has a checkpoint without learning state: --resume learns that generation again
// from round 0, with the same bits. Generation 0's 42 units are kept in both cases.
TEST(LearningRun, ResumeOfACheckpointWithoutLearningStateLearnsTheGenerationAgain) {
  test::TmpDir dir;
  const Config config = learning_config();
  const std::string ref = dir.file("ref.h5"), out = dir.file("run.h5");
  const std::size_t total = evaluations_of_run(config, ref, false);
  const std::size_t generation0 = kRound0Units + 3 * kIterationUnits;
  // In generation 1's learning rounds.
  EXPECT_EQ(run_stopped_at_evaluation(config, out, generation0 + 10, false),
            RunOutcome::interrupted);
  io::RunInfo info = Archive(out).info();
  ASSERT_EQ(info.generations_done, 1);
  io::Checkpoint cp = *Archive(out).checkpoint();
  ASSERT_FALSE(cp.learning.empty());
  cp.learning.clear();  // as an older build wrote it
  io::update_checkpoint(out, info, cp);
  EXPECT_EQ(evaluations_of_run(config, out, true), total - generation0);
  expect_archives_equal(out, ref);
}

TEST(LearningRun, ConfigWithoutLearningKeepsItsTextAndHash) {
  Config config = small_config();
  const std::string text = canonical_text(config);
  EXPECT_EQ(text.find("[learning]"), std::string::npos);
  config.learning.inheritance = Inheritance::baldwinian;  // ignored while method = "none"
  EXPECT_EQ(canonical_text(config), text);
  EXPECT_NE(canonical_text(learning_config()).find("[learning]\nmethod = \"es\"\n"),
            std::string::npos);
}

}  // namespace
}  // namespace softevo::master
