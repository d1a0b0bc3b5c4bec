// Genome distance and speciation (§8.4) on hand-made genomes.
#include "evo/speciation.hpp"

#include <gtest/gtest.h>

namespace softevo::evo {
namespace {

CppnGenome genome_a() {
  CppnGenome a;
  a.num_inputs = 2;
  a.num_outputs = 1;
  a.nodes = {{0, 0.5, 1.0, Activation::sigmoid}, {1, 0.0, 1.0, Activation::gauss}};
  a.connections = {{-1, 0, 1.0, true}, {-2, 0, 2.0, true}, {-1, 1, 0.5, true}};
  return a;
}

CppnGenome genome_b() {
  CppnGenome b;
  b.num_inputs = 2;
  b.num_outputs = 1;
  b.nodes = {{0, -0.5, 1.0, Activation::sin}, {2, 0.3, 1.0, Activation::abs}};
  b.connections = {{-1, 0, 0.0, false}, {-2, 0, 2.0, true}, {-2, 2, 1.0, true}, {2, 0, 1.0, true}};
  return b;
}

TEST(Distance, HandComputedNeatPython) {
  const NeatConfig c;  // weight coefficient 1.0, disjoint coefficient 2.0
  // Nodes: homologous 0: |0.5 - -0.5| + 0 + 1 (activation) = 2; disjoint 1 and 2 -> 2.
  //   (2 + 2*2) / max(2, 2) = 3.
  // Connections: (-1,0): |1 - 0| + 1 (enabled) = 2; (-2,0): 0; disjoint (-1,1), (-2,2), (2,0).
  //   (2 + 2*3) / max(3, 4) = 2.   Total 5.
  EXPECT_DOUBLE_EQ(genome_distance(genome_a(), genome_b(), c), 5.0);
  EXPECT_DOUBLE_EQ(genome_distance(genome_b(), genome_a(), c), 5.0);
  EXPECT_EQ(genome_distance(genome_a(), genome_a(), c), 0.0);
  NeatConfig half = c;
  half.compatibility_weight_coefficient = 0.5;  // (1 + 4)/2 + (1 + 6)/4 = 4.25
  EXPECT_DOUBLE_EQ(genome_distance(genome_a(), genome_b(), half), 4.25);
  CppnGenome empty_a, empty_b;
  EXPECT_EQ(genome_distance(empty_a, empty_b, c), 0.0);  // both parts absent
}

TEST(Distance, HandComputedPaperFormula) {
  const NeatConfig c;
  // 3 disjoint connections / N = 1 (fewer than 20 genes) x 2.0 = 6; mean |dw| over matching
  // connections (1, 0) and node 0 bias (1.0): 2/3, x 1.0.
  EXPECT_NEAR(genome_distance(genome_a(), genome_b(), c, DistanceMode::neat_paper), 6.0 + 2.0 / 3,
              1e-15);
}

CppnGenome cluster(double w, double jitter) {
  CppnGenome g;
  g.nodes = {{0, 0.0, 1.0, Activation::sigmoid},
             {1, 0.0, 1.0, Activation::sigmoid},
             {2, 0.0, 1.0, Activation::sigmoid},
             {3, 0.0, 1.0, Activation::sigmoid}};
  for (int i = 1; i <= 4; ++i)
    for (int o = 0; o < 4; ++o) g.connections.push_back({-i, o, w + jitter, true});
  return g;
}

TEST(Speciation, TwoClustersGiveTwoSpeciesAndHistoryIsKept) {
  const NeatConfig c;  // threshold 3.5
  InnovationTracker innovation(4);
  // Cluster distance: 16 x |2 - -2| / 16 = 4 > 3.5; inside a cluster <= 0.2.
  std::vector<CppnGenome> g = {cluster(-2, 0.0), cluster(2, 0.1), cluster(-2, 0.2), cluster(2, 0.0),
                               cluster(2, 0.2)};
  std::vector<SpeciationInput> in;
  for (int i = 0; i < 5; ++i) in.push_back({10 + i, &g[i]});
  std::vector<Species> species;
  const auto ids = speciate(species, in, 0, c, innovation);
  ASSERT_EQ(species.size(), 2u);
  // Ascending id order: genome 10 founds species 1, genome 11 species 2.
  EXPECT_EQ(ids, (std::vector<std::int64_t>{1, 2, 1, 2, 2}));
  EXPECT_EQ(species[0].members, (std::vector<std::int64_t>{10, 12}));
  EXPECT_EQ(species[1].members, (std::vector<std::int64_t>{11, 13, 14}));
  EXPECT_EQ(species[1].created, 0);
  species[1].fitness_history = {1.0, 2.0};
  species[1].last_improved = 7;
  // Next generation: the genome closest to the old representative (cluster(2, 0.1)) becomes the
  // new representative, even across the cluster; new genomes join by threshold.
  std::vector<CppnGenome> h = {cluster(2, 0.25), cluster(-2, 0.05), cluster(2, 0.1),
                               cluster(10, 0.0)};
  std::vector<SpeciationInput> in2;
  for (int i = 0; i < 4; ++i) in2.push_back({20 + i, &h[i]});
  const auto ids2 = speciate(species, in2, 3, c, innovation);
  ASSERT_EQ(species.size(), 3u);
  EXPECT_EQ(species[0].members.front(), 21);  // closest to cluster(-2, 0)
  EXPECT_EQ(species[1].members.front(), 22);  // exactly the old representative
  EXPECT_EQ(species[1].fitness_history, (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(species[1].last_improved, 7);
  EXPECT_EQ(ids2[0], 2);
  EXPECT_EQ(ids2[3], 3);  // cluster(10): distance 8 from everything -> new species id 3
  EXPECT_EQ(species[2].created, 3);
  EXPECT_EQ(species[2].last_improved, 3);
}

TEST(Speciation, ThresholdIsStrictAndExtraSpeciesDie) {
  NeatConfig c;
  InnovationTracker innovation(1);
  CppnGenome a;
  a.num_outputs = 1;
  a.nodes = {{0, 0.0, 1.0, Activation::sigmoid}};
  a.connections = {{-1, 0, 0.0, true}};
  CppnGenome b = a;
  b.connections[0].weight = 3.5;  // distance exactly 3.5: not < 3.5
  std::vector<SpeciationInput> in = {{1, &a}, {2, &b}};
  std::vector<Species> species;
  speciate(species, in, 0, c, innovation);
  EXPECT_EQ(species.size(), 2u);
  c.compatibility_threshold = 3.5000001;
  std::vector<Species> species2;
  speciate(species2, in, 0, c, innovation);
  EXPECT_EQ(species2.size(), 1u);
  // Two species, one genome left: the second species gets no representative and is dropped.
  std::vector<SpeciationInput> one = {{5, &a}};
  speciate(species, one, 1, c, innovation);
  ASSERT_EQ(species.size(), 1u);
  EXPECT_EQ(species[0].members, (std::vector<std::int64_t>{5}));
}

}  // namespace
}  // namespace softevo::evo
