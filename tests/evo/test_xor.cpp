// XOR experiment logic: fitness/solved criterion on hand-built networks and seeded runs.
#include "evo/xor.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace softevo::evo {
namespace {

CppnGenome xor_network() {
  // h = sigmoid(5 (4 x1 + 4 x2 - 6)) is AND; out = sigmoid(5 (4 x1 + 4 x2 - 8 h - 2)) is XOR.
  CppnGenome g;
  g.num_inputs = 2;
  g.num_outputs = 1;
  g.nodes = {{0, -2.0, 1.0, Activation::sigmoid}, {1, -6.0, 1.0, Activation::sigmoid}};
  g.connections = {{-1, 1, 4.0, true},
                   {-2, 1, 4.0, true},
                   {-1, 0, 4.0, true},
                   {-2, 0, 4.0, true},
                   {1, 0, -8.0, true}};
  return g;
}

TEST(Xor, HandBuiltSolutionIsSolvedAndOrIsNot) {
  const XorScore s = evaluate_xor(xor_network());
  EXPECT_TRUE(s.solved);
  EXPECT_GT(s.fitness, 3.99);
  CppnGenome or_net;
  or_net.num_inputs = 2;
  or_net.num_outputs = 1;
  or_net.nodes = {{0, -0.5, 1.0, Activation::sigmoid}};
  or_net.connections = {{-1, 0, 1.0, true}, {-2, 0, 1.0, true}};
  const XorScore o = evaluate_xor(or_net);
  EXPECT_FALSE(o.solved);
  // Outputs sigmoid(-2.5), sigmoid(2.5) twice, sigmoid(7.5): fitness 4 - SSE.
  const auto sig = [](double z) { return 1.0 / (1.0 + std::exp(-5.0 * z)); };
  const double sse = std::pow(sig(-0.5), 2) + 2 * std::pow(1 - sig(0.5), 2) + std::pow(sig(1.5), 2);
  EXPECT_NEAR(o.fitness, 4.0 - sse, 1e-12);
  // Disabling the hidden path breaks the solution.
  CppnGenome broken = xor_network();
  broken.connections[4].enabled = false;
  EXPECT_FALSE(evaluate_xor(broken).solved);
}

TEST(Xor, ParamsAreThePaperValues) {
  const EvoParams p = xor_params();
  EXPECT_EQ(p.neat.pop_size, 150);
  EXPECT_EQ(p.neat.compatibility_threshold, 3.0);
  EXPECT_EQ(p.neat.node_add_prob, 0.03);
  EXPECT_EQ(p.neat.conn_add_prob, 0.05);
  EXPECT_EQ(p.neat.weight_mutate_rate, 0.8);
  EXPECT_EQ(p.num_inputs, 2);
  EXPECT_EQ(p.num_outputs, 1);
  EXPECT_FALSE(p.with_controller);
  ASSERT_EQ(p.activation_options.size(), 1u);
  EXPECT_EQ(p.activation_options[0], Activation::sigmoid);
}

TEST(Xor, SeededRunsSolveAndAreReproducible) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const XorRun r = run_xor(seed, 300);
    EXPECT_TRUE(r.solved) << "seed " << seed;
    EXPECT_GE(r.generations, 1);
    // Spawn rounding lets the population size drift a little around 150 (neat-python).
    EXPECT_NEAR(static_cast<double>(r.evaluations) / r.generations, 150.0, 10.0);
    EXPECT_GE(r.hidden_nodes, 1);  // XOR is not linearly separable
    const XorRun again = run_xor(seed, 300);
    EXPECT_EQ(again.evaluations, r.evaluations);
    EXPECT_EQ(again.generations, r.generations);
  }
}

}  // namespace
}  // namespace softevo::evo
