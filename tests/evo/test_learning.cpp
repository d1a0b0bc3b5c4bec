// Controller learning of one body (evo/learning.hpp, docs/model.md §8.11): budget arithmetic,
// the candidates' construction, elitist selection, determinism, and that it learns.
#include "evo/learning.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "evo/mutation.hpp"
#include "evo/population.hpp"

namespace softevo::evo {
namespace {

EvoParams params() {
  return evo_params(Config{}, 0);
}

Genome born_genome(std::uint64_t seed) {
  Rng rng(seed);
  return random_genome(params(), rng);
}

// A smooth stand-in objective of the controller: the closer every weight is to 1, the better
// (0 at the optimum), so improvement can be measured without physics.
double distance_fitness(const Genome& g) {
  double f = 0.0;
  for (const std::vector<double>* v : vectors_of(g.controller))
    for (double w : *v) f -= (w - 1.0) * (w - 1.0);
  return f;
}

TEST(LearningBudget, IterationsFromEvaluationsAndLambda) {
  EXPECT_EQ(learning_iterations(101, 10), 10);
  EXPECT_EQ(learning_iterations(100, 10), 9);  // the born evaluation counts
  EXPECT_EQ(learning_iterations(11, 10), 1);
  EXPECT_EQ(learning_iterations(10, 10), 0);
  EXPECT_EQ(learning_iterations(201, 1), 200);
}

TEST(LearningSeed, DependsOnEveryIdAndDiffersFromTheTerrainStream) {
  EXPECT_NE(learning_seed(1, 2, 3), learning_seed(1, 2, 4));
  EXPECT_NE(learning_seed(1, 2, 3), learning_seed(1, 3, 3));
  EXPECT_NE(learning_seed(1, 2, 3), learning_seed(2, 2, 3));
  EXPECT_NE(learning_seed(1, 2, 3), derive_seed(1, 2, 3, -1));
  EXPECT_EQ(learning_seed(1, 2, 3), derive_seed(1, 2, 3, kLearningStream));
}

TEST(ControllerLearner, CandidatesKeepTheBodyAndFollowTheMutationOperator) {
  const Genome born = born_genome(3);
  ControllerLearner learner(born, {0.5, true}, 4, 5, 77);
  const std::vector<Genome> candidates = learner.propose(params());
  ASSERT_EQ(candidates.size(), 5u);
  // The same draws as mutate_controller on copies of the parent, candidate by candidate.
  Rng rng(77);
  for (const Genome& c : candidates) {
    Genome expected = born;
    mutate_controller(expected, params(), rng);
    EXPECT_EQ(encode_genome(c), encode_genome(expected));
    EXPECT_EQ(encode_genome(Genome{c.cppn, {}, {}}), encode_genome(Genome{born.cppn, {}, {}}));
    EXPECT_NE(c.controller.weights_out, born.controller.weights_out);
  }
  // A repeated propose() before tell() gives the same candidates (no new draws).
  EXPECT_EQ(encode_genome(learner.propose(params())[2]), encode_genome(candidates[2]));
}

TEST(ControllerLearner, StepSizeFactorScalesTheStrategysStepsNotTheGenomes) {
  const Genome born = born_genome(6);
  ControllerLearner learner(born, {0.0, true}, 2, 1, 8, 0.1);
  Genome scaled = born;
  for (std::vector<double>* v : vectors_of(scaled.step_sizes))
    for (double& s : *v) s *= 0.1;
  Rng rng(8);
  mutate_controller(scaled, params(), rng);
  const Genome candidate = learner.propose(params()).front();
  EXPECT_EQ(encode_genome(candidate), encode_genome(scaled));
  EXPECT_EQ(encode_genome(learner.best()), encode_genome(born));  // nothing taken yet
  learner.tell({{1.0, true}});
  const Genome learned = learner.best();
  EXPECT_EQ(learned.controller.weights_out, candidate.controller.weights_out);
  // Step sizes handed back in the genome's units.
  EXPECT_DOUBLE_EQ(learned.step_sizes.weights_out[0], candidate.step_sizes.weights_out[0] / 0.1);
}

TEST(ControllerLearner, ElitistSelectionNeverTakesAKilledOrWorseCandidate) {
  ControllerLearner learner(born_genome(4), {1.0, true}, 3, 3, 5);  // factor 1
  const Genome born = learner.best();
  learner.propose(params());
  // A killed candidate with a high score and an ok one below the parent: the parent stays.
  EXPECT_EQ(learner.tell({{9.0, false}, {0.5, true}, {0.9, true}}), -1);
  EXPECT_EQ(encode_genome(learner.best()), encode_genome(born));
  EXPECT_EQ(learner.best_score().fitness, 1.0);
  // The best ok candidate wins; ties go to the lower index; a tie with the parent moves.
  const std::vector<Genome> c2 = learner.propose(params());
  EXPECT_EQ(learner.tell({{1.0, true}, {2.0, true}, {2.0, true}}), 1);
  EXPECT_EQ(encode_genome(learner.best()), encode_genome(c2[1]));
  const std::vector<Genome> c3 = learner.propose(params());
  EXPECT_EQ(learner.tell({{2.0, true}, {1.5, true}, {0.0, false}}), 0);
  EXPECT_EQ(encode_genome(learner.best()), encode_genome(c3[0]));
  EXPECT_TRUE(learner.done());
  EXPECT_EQ(learner.evaluations(), 1 + 3 * 3);
  EXPECT_EQ(learner.curve(), (std::vector<double>{1.0, 1.0, 2.0, 2.0}));
  EXPECT_THROW(learner.propose(params()), std::logic_error);
}

TEST(ControllerLearner, RefusesBadInput) {
  EXPECT_THROW(ControllerLearner(Genome{}, {0.0, true}, 1, 1, 1), std::invalid_argument);
  EXPECT_THROW(ControllerLearner(born_genome(1), {0.0, true}, 1, 0, 1), std::invalid_argument);
  EXPECT_THROW(ControllerLearner(born_genome(1), {NAN, true}, 1, 1, 1), std::invalid_argument);
  EXPECT_THROW(ControllerLearner(born_genome(1), {0.0, true}, 1, 1, 1, 0.0), std::invalid_argument);
  ControllerLearner learner(born_genome(1), {0.0, true}, 2, 2, 1);
  EXPECT_THROW(learner.tell({{0.0, true}, {0.0, true}}), std::logic_error);
  learner.propose(params());
  EXPECT_THROW(learner.tell({{0.0, true}}), std::invalid_argument);
  EXPECT_THROW(learner.tell({{0.0, true}, {INFINITY, true}}), std::invalid_argument);
}

// Runs the strategy on the stand-in objective; returns the final best fitness.
double learn(const Genome& born, std::int64_t iterations, int lambda, std::uint64_t seed,
             std::vector<double>* curve = nullptr, double factor = 0.1) {
  ControllerLearner learner(born, {distance_fitness(born), true}, iterations, lambda, seed, factor);
  while (!learner.done()) {
    std::vector<CandidateScore> scores;
    for (const Genome& c : learner.propose(params())) scores.push_back({distance_fitness(c), true});
    learner.tell(scores);
  }
  if (curve != nullptr) *curve = learner.curve();
  return learner.best_score().fitness;
}

TEST(ControllerLearner, ImprovesAndIsDeterministic) {
  const Genome born = born_genome(11);
  const double before = distance_fitness(born);
  std::vector<double> curve;
  const double after = learn(born, 100, 10, 2024, &curve);
  // The self-adapted steps must take it well towards the optimum (0), from far away; the
  // genome's own step sizes (factor 1: evolution's, ~3 per gene) are far too large for that.
  EXPECT_LT(before, -500.0);
  EXPECT_GT(after, 0.75 * before) << "before " << before << " after " << after;
  EXPECT_GT(after, learn(born, 100, 10, 2024, nullptr, 1.0) + 100.0);
  ASSERT_EQ(curve.size(), 101u);
  for (std::size_t i = 1; i < curve.size(); ++i) EXPECT_GE(curve[i], curve[i - 1]);
  EXPECT_EQ(after, learn(born, 100, 10, 2024));  // bit for bit
  EXPECT_NE(after, learn(born, 100, 10, 2025));  // the seed matters
}

// One iteration on the stand-in objective; returns the index told back.
int step(ControllerLearner& learner) {
  std::vector<CandidateScore> scores;
  for (const Genome& c : learner.propose(params())) scores.push_back({distance_fitness(c), true});
  return learner.tell(scores);
}

// A run's checkpoint within a learning generation: a learner saved after some iterations and
// loaded again continues exactly as the original (candidates, selection, curve, learned genome).
TEST(ControllerLearner, SavedAndLoadedContinuesBitForBit) {
  const Genome born = born_genome(12);
  ControllerLearner original(born, {distance_fitness(born), true}, 6, 4, 31, 0.1);
  step(original);
  step(original);
  WireWriter w;
  original.save(w);
  WireReader r(w.data(), "learner");
  ControllerLearner loaded = ControllerLearner::load(r);
  r.finish();
  EXPECT_EQ(loaded.iteration(), 2);
  EXPECT_EQ(loaded.curve(), original.curve());
  while (!original.done()) {
    const std::vector<Genome> expected = original.propose(params());
    const std::vector<Genome> got = loaded.propose(params());
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t k = 0; k < got.size(); ++k)
      EXPECT_EQ(encode_genome(got[k]), encode_genome(expected[k]));
    EXPECT_EQ(step(loaded), step(original));
  }
  EXPECT_TRUE(loaded.done());
  EXPECT_EQ(loaded.curve(), original.curve());
  EXPECT_EQ(loaded.evaluations(), original.evaluations());
  EXPECT_EQ(encode_genome(loaded.best()), encode_genome(original.best()));
  EXPECT_GT(original.best_score().fitness, distance_fitness(born));  // it did move
  // Nothing taken: the born genome comes back bit for bit (not rescaled by the factor).
  ControllerLearner unmoved(born, {1e9, true}, 3, 2, 5, 0.3);
  step(unmoved);
  WireWriter u;
  unmoved.save(u);
  WireReader ur(u.data(), "learner");
  EXPECT_EQ(encode_genome(ControllerLearner::load(ur).best()), encode_genome(born));
}

TEST(ControllerLearner, SaveRefusesPendingCandidatesAndLoadRefusesBadState) {
  const Genome born = born_genome(13);
  ControllerLearner learner(born, {0.0, true}, 3, 2, 7);
  learner.propose(params());
  WireWriter pending;
  EXPECT_THROW(learner.save(pending), std::logic_error);
  learner.tell({{1.0, true}, {0.0, true}});
  WireWriter w;
  learner.save(w);
  std::vector<std::uint8_t> bytes = w.data();
  {
    WireReader truncated(std::span<const std::uint8_t>(bytes).first(bytes.size() - 1), "learner");
    EXPECT_THROW(ControllerLearner::load(truncated), WireError);
  }
  // The iteration (after the curve's count and points, from the end) beyond the iterations.
  std::vector<std::uint8_t> beyond = bytes;
  const std::size_t iteration_at = beyond.size() - 8 * (1 + learner.curve().size()) - 8;
  beyond[iteration_at] = 9;
  WireReader bad(beyond, "learner");
  EXPECT_THROW(ControllerLearner::load(bad), WireError);
}

TEST(PopulationAdoptController, TakesTheLearnedControllerOfTheSameBodyOnly) {
  Config config;
  config.body.lattice = {5, 5, 5};
  config.neat.pop_size = 6;
  Population pop = Population::create(config, 0, 3);
  const Individual first = pop.members().front();
  ControllerLearner learner(first.genome, {0.0, true}, 1, 1, 9);
  const Genome learned = learner.propose(params()).front();
  pop.adopt_controller(first.id, learned);
  EXPECT_EQ(encode_genome(pop.members().front().genome), encode_genome(learned));
  EXPECT_THROW(pop.adopt_controller(-5, learned), std::invalid_argument);
  EXPECT_THROW(pop.adopt_controller(pop.members()[1].id, learned), std::invalid_argument);
}

}  // namespace
}  // namespace softevo::evo
