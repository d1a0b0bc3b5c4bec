// Mutation operators (§8.7): rates, clamps, structural invariants, controller self-adaptation.
#include "evo/mutation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

namespace softevo::evo {
namespace {

EvoParams params() {
  return evo_params(Config{}, 0);
}

// Binomial check: `hits` of `n` trials agree with probability p within 3 standard errors.
void expect_rate(int hits, int n, double p, const char* what) {
  const double se = std::sqrt(p * (1 - p) / n);
  EXPECT_NEAR(static_cast<double>(hits) / n, p, 3 * se) << what;
}

bool acyclic(const CppnGenome& g) {
  for (const ConnectionGene& c : g.connections) {
    std::vector<ConnectionGene> others;
    for (const ConnectionGene& o : g.connections)
      if (&o != &c) others.push_back(o);
    if (creates_cycle(others, c.in, c.out)) return false;
  }
  return true;
}

TEST(MutationStructure, CreatesCycleOnHandMadeGraphs) {
  // -1 -> 0, -1 -> 4, 4 -> 5, 5 -> 0 (disabled counts too).
  std::vector<ConnectionGene> c = {
      {-1, 0, 1.0, true}, {-1, 4, 1.0, true}, {4, 5, 1.0, false}, {5, 0, 1.0, true}};
  EXPECT_TRUE(creates_cycle(c, 5, 4));   // 4 -> 5 -> 4
  EXPECT_TRUE(creates_cycle(c, 0, 4));   // 4 -> 5 -> 0 -> 4
  EXPECT_TRUE(creates_cycle(c, 4, 4));   // self loop
  EXPECT_FALSE(creates_cycle(c, 4, 0));  // parallel path
  EXPECT_FALSE(creates_cycle(c, -1, 5));
}

TEST(MutationStructure, AddNodeSplitsAConnection) {
  const EvoParams p = params();
  Rng rng(1);
  CppnGenome g = random_cppn(p, rng);
  InnovationTracker innovation(4);
  const CppnGenome before = g;
  const int key = mutate_add_node(g, p, innovation, rng);
  EXPECT_EQ(key, 4);
  ASSERT_EQ(g.nodes.size(), 5u);
  EXPECT_EQ(g.nodes.back().key, 4);
  ASSERT_EQ(g.connections.size(), 18u);
  int disabled = -1;
  for (std::size_t i = 0; i < 16; ++i)
    if (!g.connections[i].enabled) disabled = static_cast<int>(i);
  ASSERT_GE(disabled, 0);
  const ConnectionGene& old = g.connections[disabled];
  EXPECT_EQ(old.weight, before.connections[disabled].weight);
  EXPECT_EQ(g.connections[16].in, old.in);
  EXPECT_EQ(g.connections[16].out, 4);
  EXPECT_EQ(g.connections[16].weight, 1.0);
  EXPECT_EQ(g.connections[17].in, 4);
  EXPECT_EQ(g.connections[17].out, old.out);
  EXPECT_EQ(g.connections[17].weight, old.weight);
  EXPECT_TRUE(g.connections[16].enabled && g.connections[17].enabled);
  // Keys come from the global counter: a second genome gets the next key.
  CppnGenome h = random_cppn(p, rng);
  EXPECT_EQ(mutate_add_node(h, p, innovation, rng), 5);
  CppnGenome empty = random_cppn(p, rng);
  empty.connections.clear();
  EXPECT_EQ(mutate_add_node(empty, p, innovation, rng), -1);  // no-op without connections
}

TEST(MutationStructure, RandomStructuralMutationsKeepTheNetworkLegal) {
  EvoParams p = params();
  p.neat.node_add_prob = 0.3;
  p.neat.conn_add_prob = 0.5;
  p.neat.conn_delete_prob = 0.1;
  Rng rng(2);
  InnovationTracker innovation(4);
  for (int run = 0; run < 50; ++run) {
    CppnGenome g = random_cppn(p, rng);
    for (int step = 0; step < 60; ++step) {
      mutate_cppn(g, p, innovation, rng);
      std::set<std::pair<int, int>> seen;
      for (const ConnectionGene& c : g.connections) {
        ASSERT_TRUE(seen.insert({c.in, c.out}).second) << "duplicate connection";
        ASSERT_GE(c.out, 0) << "connection into an input";
        ASSERT_FALSE(c.in >= 0 && c.in < 4 && c.out < 4) << "output -> output";
        ASSERT_TRUE(c.in < 0 || g.find_node(c.in));
        ASSERT_TRUE(g.find_node(c.out));
      }
      for (std::size_t i = 1; i < g.nodes.size(); ++i)
        ASSERT_LT(g.nodes[i - 1].key, g.nodes[i].key);
    }
    EXPECT_TRUE(acyclic(g));
  }
}

TEST(MutationStructure, DeleteConnectionRemovesOne) {
  const EvoParams p = params();
  Rng rng(4);
  CppnGenome g = random_cppn(p, rng);
  mutate_delete_connection(g, rng);
  EXPECT_EQ(g.connections.size(), 15u);
  CppnGenome empty;
  mutate_delete_connection(empty, rng);  // no-op
  EXPECT_TRUE(empty.connections.empty());
}

TEST(MutationRates, StructuralRatesOver100000Draws) {
  // Every event of mutate_cppn shows in the genome: add node adds a node, add connection adds a
  // connection (when legal), delete connection removes one. add node 0.05 is exactly observable.
  const EvoParams p = params();
  Rng rng(12345);
  InnovationTracker innovation(4);
  const CppnGenome base = random_cppn(p, rng);
  const int n = 100000;
  int node_added = 0, conn_deleted_or_added = 0;
  for (int i = 0; i < n; ++i) {
    CppnGenome g = base;
    mutate_cppn(g, p, innovation, rng);
    node_added += g.nodes.size() == 5 ? 1 : 0;
    // Without add node, the connection count changes by +1 (add) or -1 (delete).
    if (g.nodes.size() == 4 && g.connections.size() != 16) ++conn_deleted_or_added;
  }
  expect_rate(node_added, n, 0.05, "node_add_prob");
  // The base genome is fully connected input->output with no hidden node, so add connection
  // (drawn before delete connection) never succeeds: output->output and duplicates are refused.
  // Without add node the only change is delete connection: P = (1 - 0.05) x 0.03.
  expect_rate(conn_deleted_or_added, n, 0.95 * 0.03, "conn_delete_prob");
}

TEST(MutationRates, WeightBiasEnabledAndActivationRates) {
  const EvoParams p = params();
  Rng rng(77);
  InnovationTracker innovation(4);
  EvoParams q = p;
  q.neat.node_add_prob = q.neat.conn_add_prob = q.neat.conn_delete_prob = 0.0;
  int weights_changed = 0, weights = 0, flips = 0, bias_changed = 0, nodes = 0, act_changed = 0;
  for (int i = 0; i < 10000; ++i) {
    const CppnGenome base = random_cppn(q, rng);
    CppnGenome g = base;
    mutate_cppn(g, q, innovation, rng);
    for (std::size_t k = 0; k < g.connections.size(); ++k) {
      weights_changed += g.connections[k].weight != base.connections[k].weight ? 1 : 0;
      flips += g.connections[k].enabled != base.connections[k].enabled ? 1 : 0;
      ++weights;
    }
    for (std::size_t k = 0; k < g.nodes.size(); ++k) {
      bias_changed += g.nodes[k].bias != base.nodes[k].bias ? 1 : 0;
      act_changed += g.nodes[k].activation != base.nodes[k].activation ? 1 : 0;
      EXPECT_EQ(g.nodes[k].response, 1.0);
      ++nodes;
    }
  }
  expect_rate(weights_changed, weights, 0.5, "weight_mutate_rate");
  expect_rate(flips, weights, 0.005, "enabled flip = 0.01 x 1/2");
  expect_rate(bias_changed, nodes, 0.5, "bias_mutate_rate");
  expect_rate(act_changed, nodes, 0.01 * 6.0 / 7.0, "activation change = 0.01 x 6/7");
}

TEST(MutationRates, PerturbedWeightsAndBiasesStayInRange) {
  EvoParams p = params();
  p.neat.weight_mutate_power = 1.0;  // large steps to hit the clamps often
  p.neat.bias_mutate_power = 1.0;
  Rng rng(8);
  InnovationTracker innovation(4);
  CppnGenome g = random_cppn(p, rng);
  int at_bound = 0;
  for (int i = 0; i < 5000; ++i) {
    mutate_cppn(g, p, innovation, rng);
    for (const ConnectionGene& c : g.connections) {
      ASSERT_GE(c.weight, -3.0);
      ASSERT_LE(c.weight, 3.0);
      at_bound += std::fabs(c.weight) == 3.0 ? 1 : 0;
    }
    for (const NodeGene& n : g.nodes) {
      ASSERT_GE(n.bias, -3.0);
      ASSERT_LE(n.bias, 3.0);
    }
  }
  EXPECT_GT(at_bound, 0);  // the clamp was exercised
}

TEST(MutationRates, FloatReplaceRate) {
  FloatMutation m{0.2, 0.5, 0.3, 10.0, 0.0, -100.0, 100.0};  // replacement gives exactly 10
  Rng rng(5);
  int replaced = 0, perturbed = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double v = mutate_float(0.0, m, rng);
    replaced += v == 10.0 ? 1 : 0;
    perturbed += (v != 10.0 && v != 0.0) ? 1 : 0;
  }
  expect_rate(replaced, n, 0.3, "replace_rate");
  expect_rate(perturbed, n, 0.2, "mutate_rate");
}

TEST(MutationController, ExactFormulaAndOrder) {
  // Replay the draws: order weights_hidden, weights_out, weights_recurrent,
  // weights_recurrent_self, bias_hidden, bias_out, bias_context, weights_context, freq; per
  // vector all step sizes first, then all values.
  const EvoParams p = params();
  Rng init(21);
  Genome g = random_genome(p, init);
  const Genome before = g;
  Rng rng(99);
  Rng replay = rng;
  mutate_controller(g, p, rng);
  const std::array<int, 9> order = {0, 2, 4, 5, 1, 3, 7, 6, 8};
  auto v_before = vectors_of(before.controller);
  auto s_before = vectors_of(before.step_sizes);
  auto v_after = vectors_of(g.controller);
  auto s_after = vectors_of(g.step_sizes);
  for (int v : order) {
    std::vector<double> sigma = *s_before[v];
    for (double& s : sigma) s = std::clamp(s + replay.normal() * s, -5.0, 5.0);
    std::vector<double> w = *v_before[v];
    for (std::size_t i = 0; i < w.size(); ++i)
      w[i] = std::clamp(w[i] + replay.normal() * sigma[i], -5.0, 5.0);
    if (v == 8) w[0] = std::clamp(w[0], 1.0, 5.0);
    EXPECT_EQ(sigma, *s_after[v]) << kControllerVectorNames[v];
    EXPECT_EQ(w, *v_after[v]) << kControllerVectorNames[v];
  }
  EXPECT_EQ(rng.state(), replay.state());  // no other draws
}

TEST(MutationController, ClipsFreezesAndClampsFrequency) {
  const EvoParams p = params();
  Rng rng(31);
  Genome g = random_genome(p, rng);
  g.step_sizes.bias_out[3] = 0.0;  // sigma = 0 freezes the gene forever
  const double frozen = g.controller.bias_out[3];
  bool negative_sigma = false;
  for (int i = 0; i < 2000; ++i) {
    mutate_controller(g, p, rng);
    for (int v = 0; v < kControllerVectorCount; ++v) {
      for (double x : *vectors_of(g.controller)[v]) {
        ASSERT_GE(x, v == kFreqVector ? 1.0 : -5.0);
        ASSERT_LE(x, 5.0);
      }
      for (double s : *vectors_of(g.step_sizes)[v]) {
        ASSERT_GE(s, -5.0);
        ASSERT_LE(s, 5.0);
        negative_sigma = negative_sigma || s < 0.0;
      }
    }
  }
  EXPECT_EQ(g.controller.bias_out[3], frozen);
  EXPECT_TRUE(negative_sigma);  // additive self-adaptation lets sigma change sign (§8.7)
  Genome plain;
  plain.cppn = g.cppn;
  Rng r2(1);
  const Rng::State s = r2.state();
  mutate_controller(plain, p, r2);  // no controller: no draws
  EXPECT_EQ(r2.state(), s);
}

}  // namespace
}  // namespace softevo::evo
