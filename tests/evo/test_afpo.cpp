// AFPO (docs/model.md §8.12.3): Pareto ranks, survivors and age rules on hand-made cases whose
// answers are worked out in the comments, and the strategy's contract (tell, state round trip).
#include "evo/afpo.hpp"

#include <gtest/gtest.h>

#include <set>

#include "common/wire.hpp"
#include "evo/development.hpp"

namespace softevo::evo {
namespace {

TEST(AfpoPareto, RanksOfAHandMadeSet) {
  // (fitness, age):  A (5, 3)  B (4, 1)  C (3, 0)  D (4, 2)  E (2, 2)  F (5, 3)
  // Rank 0: A (best fitness; F equals it, equal points do not dominate), B (A is older),
  //         C (youngest), F.
  // Rank 1: D (4, 2), dominated by B (4 >= 4, 1 < 2).
  // Rank 2: E (2, 2), dominated by B, C and D: without rank 0, still by D.
  const std::vector<double> fitness = {5, 4, 3, 4, 2, 5};
  const std::vector<std::int64_t> age = {3, 1, 0, 2, 2, 3};
  EXPECT_EQ(pareto_ranks(fitness, age), (std::vector<std::int64_t>{0, 0, 0, 1, 2, 0}));
}

TEST(AfpoPareto, YoungAndWeakSurvivesOldAndStrong) {
  // A newcomer (age 0) with the lowest fitness is on the front: no one is younger.
  const std::vector<double> fitness = {10, 9, 8, 0.5};
  const std::vector<std::int64_t> age = {5, 5, 5, 0};
  EXPECT_EQ(pareto_ranks(fitness, age), (std::vector<std::int64_t>{0, 1, 2, 0}));
  // Two survivors of four: the front (ids 1 and 4), whatever their fitness.
  EXPECT_EQ(afpo_survivors(fitness, age, {1, 2, 3, 4}, 2), (std::vector<std::size_t>{0, 3}));
}

TEST(AfpoPareto, SurvivorsFillFromTheNextFrontByFitnessThenAgeThenId) {
  // Front 0: index 0 (9, 0) dominates the rest. Front 1: indices 1 and 2, both (5, 1): equal
  // points. Front 2: index 3 (4, 1), dominated by them. Three survivors: 0, then front 1 whole.
  // Two survivors: 0 and the lower id of the tied front 1 (id 7 of index 2, below id 8).
  const std::vector<double> fitness = {9, 5, 5, 4};
  const std::vector<std::int64_t> age = {0, 1, 1, 1};
  const std::vector<std::int64_t> id = {3, 8, 7, 9};
  EXPECT_EQ(pareto_ranks(fitness, age), (std::vector<std::int64_t>{0, 1, 1, 2}));
  EXPECT_EQ(afpo_survivors(fitness, age, id, 3), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(afpo_survivors(fitness, age, id, 2), (std::vector<std::size_t>{0, 2}));
  // (6, 2), (7, 3), (9, 4) trade fitness for age: all rank 0; one survivor is the fittest.
  EXPECT_EQ(afpo_survivors({6, 7, 9}, {2, 3, 4}, {1, 2, 3}, 1), (std::vector<std::size_t>{2}));
}

TEST(AfpoAgeRules, LineageInheritsBodyRestartsOnANewBody) {
  EXPECT_EQ(offspring_age(AfpoAge::lineage, 4, false), 4);
  EXPECT_EQ(offspring_age(AfpoAge::lineage, 4, true), 4);  // evosoro: the lineage's age
  EXPECT_EQ(offspring_age(AfpoAge::body, 4, false), 4);    // same body: same age
  EXPECT_EQ(offspring_age(AfpoAge::body, 4, true), 0);     // a new body starts young
}

Config afpo_config(AfpoAge rule) {
  Config c;
  c.search.strategy = SearchKind::afpo;
  c.afpo.age = rule;
  c.body.lattice = {4, 4, 4};
  c.neat.pop_size = 5;
  return c;
}

std::vector<Evaluation> score(const SearchStrategy& s) {
  std::vector<Evaluation> out;
  for (const Individual& m : s.ask())
    out.push_back({m.id,
                   static_cast<double>(m.genome.cppn.connections.size()) +
                       0.1 * m.genome.cppn.connections.front().weight,
                   false});
  return out;
}

TEST(AfpoStrategy, AGenerationKeepsPopSizeSurvivorsAddsOffspringAndOneNewcomer) {
  Afpo a = Afpo::create(afpo_config(AfpoAge::lineage), 2, 7);
  ASSERT_EQ(a.ask().size(), 5u);
  EXPECT_EQ(a.ages(), (std::vector<std::int64_t>(5, 0)));
  std::set<std::int64_t> first;
  for (const Individual& m : a.ask()) first.insert(m.id);
  a.tell(score(a));
  // 5 survivors (all of generation 0), 4 offspring, 1 newcomer.
  ASSERT_EQ(a.ask().size(), 10u);
  std::size_t survivors = 0, newcomers = 0;
  for (std::size_t i = 0; i < a.ask().size(); ++i) {
    const Individual& m = a.ask()[i];
    if (first.count(m.id)) {
      ++survivors;
      EXPECT_EQ(a.ages()[i], 1);  // one generation older
    } else if (m.parent1 < 0) {
      ++newcomers;
      EXPECT_EQ(a.ages()[i], 0);
    } else {
      EXPECT_EQ(a.ages()[i], 1);  // lineage: the parent's age
      EXPECT_TRUE(first.count(m.parent1));
    }
  }
  EXPECT_EQ(survivors, 5u);
  EXPECT_EQ(newcomers, 1u);
  EXPECT_EQ(a.report().strategy, "afpo");
  EXPECT_EQ(a.report().rows.rows(), 5u);
  a.tell(score(a));
  EXPECT_EQ(a.ask().size(), 10u);  // 5 of 10 survive
}

TEST(AfpoStrategy, BodyRuleRestartsTheAgeOfOffspringWithANewBody) {
  // Under "body" an offspring's age is 0 or its parent's, and 0 exactly when its body differs.
  Afpo a = Afpo::create(afpo_config(AfpoAge::body), 2, 11);
  a.tell(score(a));
  a.tell(score(a));
  const BodyConfig body = afpo_config(AfpoAge::body).body;
  std::size_t checked = 0;
  for (std::size_t i = 0; i < a.ask().size(); ++i) {
    const Individual& m = a.ask()[i];
    if (m.parent1 < 0) continue;
    for (std::size_t j = 0; j < a.ask().size(); ++j) {
      if (a.ask()[j].id != m.parent1) continue;
      const DevelopedBody pb = develop_body(a.ask()[j].genome.cppn, body);
      const DevelopedBody cb = develop_body(m.genome.cppn, body);
      const bool changed = pb.plan.cells != cb.plan.cells || pb.plan.lattice != cb.plan.lattice;
      EXPECT_EQ(a.ages()[i], changed ? 0 : a.ages()[j]) << "member " << m.id;
      ++checked;
    }
  }
  EXPECT_GT(checked, 0u);
}

TEST(AfpoStrategy, StateRoundTripContinuesIdentically) {
  const Config c = afpo_config(AfpoAge::body);
  Afpo a = Afpo::create(c, 2, 3);
  a.tell(score(a));
  Afpo b = Afpo::deserialize(a.serialize(), c, 2);
  EXPECT_EQ(b.serialize(), a.serialize());
  a.tell(score(a));
  b.tell(score(b));
  EXPECT_EQ(b.serialize(), a.serialize());
}

TEST(AfpoStrategy, BadResultsLeaveTheStrategyUnchanged) {
  Afpo a = Afpo::create(afpo_config(AfpoAge::lineage), 2, 3);
  const std::vector<std::uint8_t> before = a.serialize();
  std::vector<Evaluation> r = score(a);
  r.pop_back();
  EXPECT_THROW(a.tell(r), std::invalid_argument);
  EXPECT_EQ(a.serialize(), before);
}

}  // namespace
}  // namespace softevo::evo
