// One generation's controller learning as work units (master/learning_rounds.hpp) and the run
// loop that schedules it (docs/model.md §8.11), without MPI: the evaluator is the stand-in of
// fake_run.hpp (fitness from the genome bytes), so a learning run takes milliseconds.
#include "master/learning_rounds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

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

TEST(LearningRun, ResumeAfterAStopInALearningRoundGivesTheUninterruptedArchive) {
  test::TmpDir dir;
  const Config config = learning_config();
  const std::string ref = dir.file("ref.h5"), out = dir.file("run.h5");
  ASSERT_EQ(run_once(config, ref, false), RunOutcome::complete);
  RunOptions options;
  options.out_path = out;
  PreparedRun run = prepare_run(config, options, 1);
  std::size_t evaluated = 0;
  LocalExecutor executor([&](const EvalRequest& request) {
    if (++evaluated == 20) {  // in generation 0's second learning round (6 born, 12 per round)
      request_stop(StopRequest::now);
      return EvalResult{};
    }
    return fake_evaluation(request);
  });
  ProgressReporter progress = ProgressReporter::silent();
  EXPECT_EQ(execute_run(run, executor, progress), RunOutcome::interrupted);
  clear_stop_request();
  run.lock.reset();
  EXPECT_EQ(Archive(out).info().generations_done, 0);
  ASSERT_EQ(run_once(config, out, true), RunOutcome::complete);
  EXPECT_EQ(fitness_digest_of(out), fitness_digest_of(ref));
  EXPECT_EQ(io::content_digest(Archive(out)), io::content_digest(Archive(ref)));
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
