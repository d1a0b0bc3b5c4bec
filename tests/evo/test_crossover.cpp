// Crossover (§8.6): whole-gene CPPN crossover and the controller methods.
#include "evo/crossover.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace softevo::evo {
namespace {

CppnGenome hand_genome(double w, double bias, bool enabled, bool extra) {
  CppnGenome g;
  g.num_inputs = 2;
  g.num_outputs = 1;
  g.nodes = {NodeGene{0, bias, 1.0, Activation::sigmoid}};
  g.connections = {ConnectionGene{-1, 0, w, enabled}, ConnectionGene{-2, 0, 2 * w, enabled}};
  if (extra) {
    g.nodes.push_back(NodeGene{1 + (w > 0 ? 0 : 1), bias, 1.0, Activation::gauss});
    const int k = g.nodes.back().key;
    g.connections.push_back(ConnectionGene{-1, k, w, true});
    g.connections.push_back(ConnectionGene{k, 0, w, true});
  }
  return g;
}

TEST(CrossoverCppn, FitterParentDecidesTheStructureTiesGoToTheSecondArgument) {
  const CppnGenome a = hand_genome(1.0, 0.5, true, true);     // hidden node 1
  const CppnGenome b = hand_genome(-1.0, -0.5, false, true);  // hidden node 2
  Rng rng(1);
  auto has_node = [](const CppnGenome& g, int k) { return g.find_node(k) != nullptr; };
  const CppnGenome c1 = crossover_cppn(a, 2.0, b, 1.0, rng);
  EXPECT_TRUE(has_node(c1, 1));
  EXPECT_FALSE(has_node(c1, 2));  // genes only in the weaker parent are dropped
  EXPECT_EQ(c1.connections.size(), 4u);
  const CppnGenome c2 = crossover_cppn(a, 1.0, b, 2.0, rng);
  EXPECT_TRUE(has_node(c2, 2));
  EXPECT_FALSE(has_node(c2, 1));
  const CppnGenome c3 = crossover_cppn(a, 1.0, b, 1.0, rng);  // tie -> b is parent1
  EXPECT_TRUE(has_node(c3, 2));
  EXPECT_FALSE(has_node(c3, 1));
  // Order of parent1's genes is kept.
  EXPECT_EQ(c2.connections[2].out, 2);
  EXPECT_EQ(c2.connections[3].in, 2);
}

TEST(CrossoverCppn, MatchingGenesAreInheritedWholeWithEqualProbability) {
  const CppnGenome a = hand_genome(1.0, 0.5, true, false);
  const CppnGenome b = hand_genome(-1.0, -0.5, false, false);
  Rng rng(2);
  const int n = 20000;
  int from_a = 0;
  for (int i = 0; i < n; ++i) {
    const CppnGenome c = crossover_cppn(a, 1.0, b, 0.0, rng);
    for (const ConnectionGene& g : c.connections) {
      // Whole gene: weight and enabled come from the same parent.
      ASSERT_TRUE((g.weight > 0 && g.enabled) || (g.weight < 0 && !g.enabled));
    }
    from_a += c.connections[0].weight > 0 ? 1 : 0;
    ASSERT_TRUE(c.nodes[0].bias == 0.5 || c.nodes[0].bias == -0.5);
  }
  EXPECT_NEAR(static_cast<double>(from_a) / n, 0.5, 3 * std::sqrt(0.25 / n));
}

Genome labelled(double base, const EvoParams& p) {
  // Values encode (parent, vector, index); step sizes the same plus 0.5 to check they travel
  // with their values.
  Genome g;
  Rng rng(0);
  random_controller(p, rng, g);
  auto v = vectors_of(g.controller);
  auto s = vectors_of(g.step_sizes);
  for (int k = 0; k < kControllerVectorCount; ++k)
    for (std::size_t i = 0; i < v[k]->size(); ++i) {
      (*v[k])[i] = base + 1000.0 * k + static_cast<double>(i);
      (*s[k])[i] = (*v[k])[i] + 0.5;
    }
  return g;
}

TEST(CrossoverController, OnePointPerLayerCutsEachVectorIndependently) {
  const EvoParams p = evo_params(Config{}, 0);
  const Genome a = labelled(0.0, p);
  const Genome b = labelled(100000.0, p);
  Rng rng(3);
  const int n = 20000;
  const std::size_t len_wh = a.controller.weights_hidden.size();  // 8
  const std::size_t len_bh = a.controller.bias_hidden.size();     // 4
  std::vector<int> cut_hist(len_wh + 1, 0);
  std::vector<std::vector<int>> joint(len_wh + 1, std::vector<int>(len_bh + 1, 0));
  int swaps = 0, freq_from_a = 0;
  for (int t = 0; t < n; ++t) {
    Genome c;
    crossover_controller(a, b, EvoParams::CrossoverMethod::one_point_per_layer, rng, c);
    std::array<int, kControllerVectorCount> cuts{};
    std::array<bool, kControllerVectorCount> a_first{};
    const auto v = vectors_of(c.controller);
    const auto s = vectors_of(c.step_sizes);
    for (int k = 0; k < kControllerVectorCount; ++k) {
      const auto& x = *v[k];
      // Structure: first[:p] + second[p:], one parent per side, same cut for step sizes.
      const bool starts_a = x[0] < 50000.0;
      std::size_t p_cut = x.size();
      for (std::size_t i = 0; i < x.size(); ++i) {
        ASSERT_EQ(std::fmod(x[i], 1000.0), static_cast<double>(i)) << "gene moved";
        ASSERT_EQ((*s[k])[i], x[i] + 0.5) << "step size separated from its gene";
        if ((x[i] < 50000.0) != starts_a && p_cut == x.size()) p_cut = i;
        if (p_cut < x.size()) {
          ASSERT_NE(x[i] < 50000.0, starts_a) << "two cuts";
        }
      }
      cuts[k] = static_cast<int>(p_cut);
      a_first[k] = starts_a;
    }
    // Cut p = len looks like "no cut" and p = 0 like the swapped parent with p = len; use the
    // position of the first switch, counting a full copy of the first parent as p = len.
    ++cut_hist[cuts[0]];
    ++joint[cuts[0]][cuts[1]];
    swaps += a_first[2] ? 0 : 1;
    freq_from_a += a.controller.freq[0] == c.controller.freq[0] ? 1 : 0;
  }
  // Observed switch position: p in 1..len-1 keep their probability 1/(len+1); p = 0 and p = len
  // both give an unswitched vector (counted as len): 2/(len+1).
  for (std::size_t k = 1; k < len_wh; ++k) {
    const double pk = 1.0 / (len_wh + 1);
    EXPECT_NEAR(cut_hist[k] / double(n), pk, 3 * std::sqrt(pk * (1 - pk) / n)) << "cut " << k;
  }
  EXPECT_EQ(cut_hist[0], 0);
  // Independence: the joint frequency of (cut in weights_hidden, cut in bias_hidden) factorises.
  double chi2 = 0.0;
  for (std::size_t i = 1; i <= len_wh; ++i)
    for (std::size_t j = 1; j <= len_bh; ++j) {
      const double pi = (i == len_wh ? 2.0 : 1.0) / (len_wh + 1);
      const double pj = (j == len_bh ? 2.0 : 1.0) / (len_bh + 1);
      const double e = n * pi * pj;
      chi2 += (joint[i][j] - e) * (joint[i][j] - e) / e;
    }
  // 8 x 4 table with fixed marginals: 31 degrees of freedom; the 99.9 % quantile is 61.1.
  EXPECT_LT(chi2, 61.1);
  EXPECT_NEAR(swaps / double(n), 0.5, 3 * std::sqrt(0.25 / n));        // role swap coin
  EXPECT_NEAR(freq_from_a / double(n), 0.5, 3 * std::sqrt(0.25 / n));  // freq: a coin flip
}

TEST(CrossoverController, RandomCarriesStepSizesAndOnePointCutsTheConcatenation) {
  const EvoParams p = evo_params(Config{}, 0);
  const Genome a = labelled(0.0, p);
  const Genome b = labelled(100000.0, p);
  Rng rng(4);
  int from_a = 0, genes = 0;
  for (int t = 0; t < 500; ++t) {
    Genome c;
    crossover_controller(a, b, EvoParams::CrossoverMethod::random, rng, c);
    const auto v = vectors_of(c.controller);
    const auto s = vectors_of(c.step_sizes);
    for (int k = 0; k < kControllerVectorCount; ++k)
      for (std::size_t i = 0; i < v[k]->size(); ++i) {
        ASSERT_EQ((*s[k])[i], (*v[k])[i] + 0.5);
        from_a += (*v[k])[i] < 50000.0 ? 1 : 0;
        ++genes;
      }
  }
  EXPECT_NEAR(from_a / double(genes), 0.5, 3 * std::sqrt(0.25 / genes));
  for (int t = 0; t < 500; ++t) {
    Genome c;
    crossover_controller(a, b, EvoParams::CrossoverMethod::one_point, rng, c);
    std::vector<bool> side;
    for (const auto* vec : vectors_of(c.controller))
      for (double x : *vec) side.push_back(x < 50000.0);
    int switches = 0;
    for (std::size_t i = 1; i < side.size(); ++i) switches += side[i] != side[i - 1] ? 1 : 0;
    ASSERT_LE(switches, 1) << "one cut across all vectors";
  }
}

TEST(CrossoverController, MismatchedParentsAreAnErrorAndNoControllerIsANoOp) {
  const EvoParams p = evo_params(Config{}, 0);
  Genome a = labelled(0.0, p);
  Genome b = labelled(1.0, p);
  b.controller.bias_out.pop_back();
  b.step_sizes.bias_out.pop_back();
  Rng rng(5);
  Genome c;
  EXPECT_THROW(crossover_controller(a, b, EvoParams::CrossoverMethod::one_point_per_layer, rng, c),
               std::invalid_argument);
  Genome plain_a, plain_b;
  plain_a.cppn = hand_genome(1.0, 0.0, true, false);
  plain_b.cppn = plain_a.cppn;
  const Genome child = crossover(plain_a, 1.0, plain_b, 0.0, p, rng);
  EXPECT_FALSE(child.has_controller());
}

}  // namespace
}  // namespace softevo::evo
