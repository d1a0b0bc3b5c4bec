// Stagnation, spawn allocation, tournament and reproduction (§8.5).
#include "evo/reproduction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace softevo::evo {
namespace {

TEST(Spawn, RoundHalfEvenLikePython3) {
  EXPECT_EQ(round_half_even(0.5), 0);
  EXPECT_EQ(round_half_even(1.5), 2);
  EXPECT_EQ(round_half_even(2.5), 2);
  EXPECT_EQ(round_half_even(-0.5), 0);
  EXPECT_EQ(round_half_even(-1.5), -2);
  EXPECT_EQ(round_half_even(-2.5), -2);
  EXPECT_EQ(round_half_even(2.4999999), 2);
  EXPECT_EQ(round_half_even(2.5000001), 3);
  EXPECT_EQ(round_half_even(-7.5), -8);
  EXPECT_EQ(round_half_even(7.0), 7);
}

TEST(Spawn, ComputeSpawnAgainstHandValues) {
  // Values worked by hand and checked with neat-python 0.92's compute_spawn in Python 3.
  // s = 10, 40; d = -7.5, 7.5 -> round -8, 8 (ties to even) -> 17, 33.
  EXPECT_EQ(compute_spawn({0.2, 0.8}, {25, 25}, 50, 2), (std::vector<std::int64_t>{17, 33}));
  // s = 15, 15, 20; d = 2.5, -2.5, 0 -> round 2, -2 (ties to even), 0 -> 12, 18, 20.
  EXPECT_EQ(compute_spawn({0.3, 0.3, 0.4}, {10, 20, 20}, 50, 2),
            (std::vector<std::int64_t>{12, 18, 20}));
  // min size and normalisation: 2, 2, 48 -> x 50/52 -> 1.92, 1.92, 46.15 -> max(2, .) 2, 2, 46.
  EXPECT_EQ(compute_spawn({0.0, 0.0, 1.0}, {2, 2, 46}, 50, 2),
            (std::vector<std::int64_t>{2, 2, 46}));
  // sum af = 0: s = min size; d = -4, -19 -> 6, 21 -> x 50/27 -> 11.1, 38.9 -> 11, 39.
  EXPECT_EQ(compute_spawn({0.0, 0.0}, {10, 40}, 50, 2), (std::vector<std::int64_t>{11, 39}));
  EXPECT_EQ(compute_spawn({0.1, 0.25, 0.65}, {7, 30, 13}, 50, 2),
            (std::vector<std::int64_t>{6, 21, 23}));
  // d = 12, 11 -> 13, 14 -> x 50/27 -> 24.07, 25.93 -> 24, 26.
  EXPECT_EQ(compute_spawn({0.5, 0.5}, {1, 3}, 50, 2), (std::vector<std::int64_t>{24, 26}));
}

Species make_species(std::int64_t id, std::vector<std::int64_t> members,
                     std::vector<double> history, std::int64_t last_improved) {
  Species s;
  s.id = id;
  s.members = std::move(members);
  s.fitness_history = std::move(history);
  s.last_improved = last_improved;
  return s;
}

TEST(Stagnation, StaleSpeciesGoButTheBestIsProtected) {
  NeatConfig c;  // max_stagnation 15, species_elitism 1
  std::vector<Species> sp = {make_species(1, {1}, {5.0}, 0), make_species(2, {2}, {9.0}, 0),
                             make_species(3, {3}, {1.0}, 10)};
  std::unordered_map<std::int64_t, double> f = {{1, 4.0}, {2, 8.0}, {3, 2.0}};
  const auto r = update_stagnation(sp, f, 20, c);
  // Ascending fitness: species 3 (2.0, improved now), 1 (4.0 stale 20), 2 (8.0 stale, best).
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].species_index, 2u);
  EXPECT_FALSE(r[0].stagnant);
  EXPECT_EQ(sp[2].last_improved, 20);
  EXPECT_EQ(r[1].species_index, 0u);
  EXPECT_TRUE(r[1].stagnant);
  EXPECT_EQ(r[2].species_index, 1u);
  EXPECT_FALSE(r[2].stagnant);  // best species: protected by species_elitism
  EXPECT_EQ(sp[0].fitness_history, (std::vector<double>{5.0, 4.0}));
  EXPECT_EQ(sp[1].fitness, 8.0);
  // Stale for exactly 14 generations: not yet stagnant.
  std::vector<Species> sp2 = {make_species(1, {1}, {5.0}, 6), make_species(2, {2}, {}, 0)};
  const auto r2 = update_stagnation(sp2, f, 20, c);
  EXPECT_FALSE(r2[0].stagnant);         // species 1: 4.0, 20 - 6 = 14 < 15
  EXPECT_EQ(sp2[1].last_improved, 20);  // empty history: any fitness improves
}

TEST(Tournament, SizeTwoPicksTheBetterOfTwoDraws) {
  Rng rng(1);
  const std::vector<double> f = {0.0, 1.0};
  const int n = 100000;
  int best = 0;
  for (int i = 0; i < n; ++i) best += tournament(f, 2, rng) == 1 ? 1 : 0;
  // P(best) = 1 - P(both draws pick index 0) = 3/4.
  EXPECT_NEAR(best / double(n), 0.75, 3 * std::sqrt(0.75 * 0.25 / n));
  const std::vector<double> ties = {1.0, 1.0, 1.0};
  int first = 0;
  for (int i = 0; i < n; ++i) first += tournament(ties, 2, rng) == 0 ? 1 : 0;
  // Ties never replace: the first draw wins, uniform 1/3.
  EXPECT_NEAR(first / double(n), 1.0 / 3, 3 * std::sqrt(2.0 / 9 / n));
}

TEST(Reproduce, ElitesSpawnAndParentsStayInsideTheSpecies) {
  EvoParams p = evo_params(Config{}, 0);
  p.neat.pop_size = 20;
  Rng rng(3);
  InnovationTracker innovation(4);
  std::vector<ScoredIndividual> members;
  for (int i = 0; i < 12; ++i) {
    ScoredIndividual m;
    m.individual.id = innovation.new_genome_id();
    m.individual.genome = random_genome(p, rng);
    m.fitness = i < 8 ? 1.0 + i : 0.5 * i;
    members.push_back(m);
  }
  // Species 7 = ids 1..8 (fitness 1..8), species 9 = ids 9..12 (4, 4.5, 5, 5.5).
  std::vector<Species> sp = {make_species(7, {1, 2, 3, 4, 5, 6, 7, 8}, {}, 0),
                             make_species(9, {9, 10, 11, 12}, {}, 0)};
  const auto next = reproduce(sp, members, 0, p, innovation, rng);
  // Spawn, in ascending species fitness (9 then 7): min 1, max 8, range 7;
  // af = (4.75 - 1)/7 = 0.5357, (4.5 - 1)/7 = 0.5; s = 10.34, 9.66; d = 3.17, 0.83 -> 4 + 3 = 7,
  // 8 + 1 = 9; normalised x 20/16: 8.75, 11.25 -> 9, 11.
  ASSERT_EQ(next.size(), 20u);
  // Species order is now ascending fitness: 9 (5.5) then 7 (8).
  ASSERT_EQ(sp.size(), 2u);
  EXPECT_EQ(sp[0].id, 9);
  EXPECT_EQ(sp[1].id, 7);
  EXPECT_TRUE(sp[0].members.empty());
  EXPECT_EQ(next[0].id, 12);  // elite of species 9, unchanged
  EXPECT_EQ(encode_genome(next[0].genome), encode_genome(members[11].individual.genome));
  EXPECT_EQ(next[9].id, 8);  // elite of species 7 after its 9 - 1 children
  std::set<std::int64_t> ids;
  for (std::size_t i = 0; i < next.size(); ++i) {
    EXPECT_TRUE(ids.insert(next[i].id).second);
    if (i == 0 || i == 9) continue;
    EXPECT_GT(next[i].id, 12);  // fresh ids
    const std::int64_t lo = i < 9 ? 9 : 1, hi = i < 9 ? 12 : 8;
    EXPECT_GE(next[i].parent1, lo);
    EXPECT_LE(next[i].parent1, hi);
    EXPECT_GE(next[i].parent2, lo);
    EXPECT_LE(next[i].parent2, hi);
  }
}

}  // namespace
}  // namespace softevo::evo
