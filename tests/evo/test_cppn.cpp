// CPPN genome and neat-python 0.92 feed-forward semantics (docs/model.md §6.1).
#include "evo/cppn.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace softevo::evo {
namespace {

TEST(CppnActivation, ValuesMatchNeatPythonDefinitions) {
  // sigmoid: 1/(1+exp(-5z)); at z = 0.2 the argument is 1.
  EXPECT_DOUBLE_EQ(activate(Activation::sigmoid, 0.0), 0.5);
  EXPECT_DOUBLE_EQ(activate(Activation::sigmoid, 0.2), 1.0 / (1.0 + std::exp(-1.0)));
  EXPECT_DOUBLE_EQ(activate(Activation::sin, 0.1), std::sin(0.5));
  EXPECT_DOUBLE_EQ(activate(Activation::abs, -2.5), 2.5);
  EXPECT_DOUBLE_EQ(activate(Activation::square, -3.0), 9.0);
  EXPECT_DOUBLE_EQ(activate(Activation::exp, 1.0), std::exp(1.0));
  EXPECT_DOUBLE_EQ(activate(Activation::clamped, 0.3), 0.3);
  EXPECT_DOUBLE_EQ(activate(Activation::gauss, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(activate(Activation::gauss, 1.0), std::exp(-5.0));
  EXPECT_DOUBLE_EQ(activate(Activation::tanh, 0.4), std::tanh(1.0));
}

TEST(CppnActivation, ClampsAreApplied) {
  // sigmoid/sin/tanh clamp the scaled argument to [-60, 60]: z = 100 acts like 5z = 60.
  EXPECT_EQ(activate(Activation::sigmoid, -100.0), 1.0 / (1.0 + std::exp(60.0)));
  EXPECT_GT(activate(Activation::sigmoid, -100.0), 0.0);
  EXPECT_EQ(activate(Activation::sin, 100.0), std::sin(60.0));
  EXPECT_EQ(activate(Activation::sin, -100.0), std::sin(-60.0));
  EXPECT_EQ(activate(Activation::sin, 12.0), std::sin(60.0));  // 5*12 = 60: at the clamp
  EXPECT_NE(activate(Activation::sin, 11.0), std::sin(60.0));
  EXPECT_EQ(activate(Activation::exp, 1000.0), std::exp(60.0));
  EXPECT_EQ(activate(Activation::exp, -1000.0), std::exp(-60.0));
  EXPECT_EQ(activate(Activation::clamped, 7.0), 1.0);
  EXPECT_EQ(activate(Activation::clamped, -7.0), -1.0);
  // gauss clamps z to [-3.4, 3.4] before squaring.
  EXPECT_EQ(activate(Activation::gauss, 50.0), std::exp(-5.0 * (3.4 * 3.4)));
  EXPECT_EQ(activate(Activation::gauss, -50.0), std::exp(-5.0 * (3.4 * 3.4)));
  EXPECT_EQ(activate(Activation::tanh, 1e6), std::tanh(60.0));
  // abs and square are unclamped.
  EXPECT_EQ(activate(Activation::square, 1e3), 1e6);
  EXPECT_EQ(activate(Activation::abs, -1e9), 1e9);
}

TEST(CppnActivation, NamesRoundTripAndBadNameIsNamed) {
  for (auto a : {Activation::sigmoid, Activation::sin, Activation::abs, Activation::square,
                 Activation::exp, Activation::clamped, Activation::gauss, Activation::tanh})
    EXPECT_EQ(activation_from_string(to_string(a)), a);
  EXPECT_STREQ(to_string(Activation::gauss), "gauss");
  try {
    activation_from_string("relu");
    FAIL() << "relu accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("relu"), std::string::npos);
  }
}

// Genome with the 4 outputs (clamped, bias 0) and optional hidden nodes.
CppnGenome make_genome(std::vector<NodeGene> hidden = {}) {
  CppnGenome g;
  for (int k = 0; k < 4; ++k) g.nodes.push_back(NodeGene{k, 0.0, 1.0, Activation::clamped});
  for (const auto& h : hidden) g.nodes.push_back(h);
  return g;
}

std::vector<double> run(const CppnGenome& g, std::array<double, 4> in) {
  FeedForwardNetwork net(g);
  return net.activate(std::span<const double>(in));
}

TEST(FeedForwardNetwork, NodeValueIsActOfBiasPlusResponseTimesSum) {
  CppnGenome g = make_genome();
  g.nodes[0] = NodeGene{0, 0.25, 0.5, Activation::square};
  g.connections = {{-1, 0, 2.0, true}, {-2, 0, -1.0, true}};
  // square(0.25 + 0.5*(2*0.3 - 1*0.1)) = square(0.5) = 0.25
  const auto out = run(g, {0.3, 0.1, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(out[0], 0.25);
}

TEST(FeedForwardNetwork, OutputsWithoutEnabledInputsStayZeroNotActOfBias) {
  CppnGenome g = make_genome();
  for (auto& n : g.nodes) n = NodeGene{n.key, 0.7, 1.0, Activation::exp};  // exp(0.7) != 0
  g.connections = {{-1, 0, 1.0, true}, {-1, 1, 1.0, false}};
  const auto out = run(g, {0.5, 0.0, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(out[0], std::exp(1.2));
  EXPECT_EQ(out[1], 0.0);  // only incoming connection disabled
  EXPECT_EQ(out[2], 0.0);  // no connection at all
  EXPECT_EQ(out[3], 0.0);
}

TEST(FeedForwardNetwork, OutputBehindUncomputableHiddenNodeStaysZero) {
  // Hidden 10's only input is disabled, so 10 never enters a layer and neither does output 1,
  // although output 1 also has an enabled connection from an input.
  CppnGenome g = make_genome({NodeGene{10, 0.3, 1.0, Activation::exp}});
  g.nodes[1].bias = 0.4;
  g.connections = {
      {-1, 10, 1.0, false}, {10, 1, 1.0, true}, {-2, 1, 1.0, true}, {-3, 0, 1.0, true}};
  const auto out = run(g, {0.1, 0.2, 0.3, 0.0});
  EXPECT_EQ(out[1], 0.0);
  EXPECT_DOUBLE_EQ(out[0], 0.3);
}

TEST(FeedForwardNetwork, HiddenChainAndUnreachableHiddenNode) {
  // -1 -> 10 (abs) -> 0; hidden 11 has an input but no path to an output: not evaluated.
  CppnGenome g = make_genome(
      {NodeGene{10, -1.0, 1.0, Activation::abs}, NodeGene{11, 0.0, 1.0, Activation::exp}});
  g.connections = {{-1, 10, 2.0, true}, {10, 0, 0.5, true}, {-1, 11, 1.0, true}};
  FeedForwardNetwork net(g);
  EXPECT_EQ(net.evaluation_order(), (std::vector<int>{10, 0}));
  const std::array<double, 4> in{0.2, 0, 0, 0};
  const auto out = net.activate(std::span<const double>(in));
  EXPECT_DOUBLE_EQ(out[0], 0.5 * std::fabs(-1.0 + 2.0 * 0.2));
}

TEST(FeedForwardNetwork, OutputMayFeedAnotherNodeAndLayersFollowDependencies) {
  // Output 2 feeds output 0: 2 must be in an earlier layer.
  CppnGenome g = make_genome();
  g.connections = {{2, 0, 3.0, true}, {-1, 2, 0.1, true}};
  FeedForwardNetwork net(g);
  EXPECT_EQ(net.evaluation_order(), (std::vector<int>{2, 0}));
  const std::array<double, 4> in{1.0, 0, 0, 0};
  const auto out = net.activate(std::span<const double>(in));
  EXPECT_DOUBLE_EQ(out[2], 0.1);
  EXPECT_DOUBLE_EQ(out[0], 0.3);  // clamped(3 * 0.1)
}

TEST(FeedForwardNetwork, SumsInConnectionOrder) {
  // (1e16 + 1) - 1e16 = 0 left to right, but 1 in the other order: the connection list order
  // is the summation order (§6.1).
  CppnGenome g = make_genome();
  g.connections = {{-1, 0, 1e16, true}, {-2, 0, 1.0, true}, {-3, 0, -1e16, true}};
  EXPECT_EQ(run(g, {1, 1, 1, 0})[0], 0.0);
  std::swap(g.connections[1], g.connections[2]);
  EXPECT_EQ(run(g, {1, 1, 1, 0})[0], 1.0);
}

TEST(FeedForwardNetwork, RepeatedQueriesAreIndependentAndSizesChecked) {
  CppnGenome g = make_genome();
  g.connections = {{-4, 3, 1.0, true}};
  FeedForwardNetwork net(g);
  std::array<double, 4> in{0, 0, 0, 0.4}, out{};
  net.activate(in, out);
  EXPECT_DOUBLE_EQ(out[3], 0.4);
  in[3] = -0.2;
  net.activate(in, out);
  EXPECT_DOUBLE_EQ(out[3], -0.2);
  std::array<double, 3> short_in{};
  EXPECT_THROW(net.activate(short_in, out), std::invalid_argument);
}

TEST(CppnRecords, RoundTripAndSorting) {
  std::vector<CppnNodeRecord> nodes = {{12, 0.5, 1.0, "sin", "sum"},
                                       {0, -2.2, 1.0, "exp", "sum"},
                                       {1, 0.1, 1.0, "gauss", "sum"},
                                       {2, 0.2, 1.0, "square", "sum"},
                                       {3, 0.3, 1.0, "clamped", "sum"}};
  std::vector<CppnConnectionRecord> conns = {{-1, 12, -2.8, true}, {12, 0, 1.5, false}};
  const CppnGenome g = cppn_from_records(nodes, conns);
  ASSERT_EQ(g.nodes.size(), 5u);
  EXPECT_EQ(g.nodes.front().key, 0);
  EXPECT_EQ(g.nodes.back().key, 12);
  EXPECT_EQ(g.nodes.back().activation, Activation::sin);
  const auto back_nodes = cppn_node_records(g);
  const auto back_conns = cppn_connection_records(g);
  ASSERT_EQ(back_conns.size(), 2u);
  EXPECT_EQ(back_conns[0].in, -1);
  EXPECT_EQ(back_conns[0].weight, -2.8);
  EXPECT_FALSE(back_conns[1].enabled);
  EXPECT_EQ(back_nodes[0].activation, "exp");
  EXPECT_EQ(back_nodes[4].bias, 0.5);
  const CppnGenome again = cppn_from_records(back_nodes, back_conns);
  EXPECT_EQ(again.nodes.size(), g.nodes.size());
  EXPECT_EQ(again.connections.size(), g.connections.size());
}

TEST(CppnRecords, BadRecordsAreRejectedWithReason) {
  auto outputs = [] {
    std::vector<CppnNodeRecord> n;
    for (int k = 0; k < 4; ++k) n.push_back({k, 0.0, 1.0, "sigmoid", "sum"});
    return n;
  };
  auto expect_error = [](const std::vector<CppnNodeRecord>& n,
                         const std::vector<CppnConnectionRecord>& c, const std::string& needle) {
    try {
      cppn_from_records(n, c);
      ADD_FAILURE() << "accepted; expected error containing " << needle;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  auto n = outputs();
  n[2].aggregation = "product";
  expect_error(n, {}, "product");
  n = outputs();
  n[1].activation = "relu";
  expect_error(n, {}, "relu");
  n = outputs();
  n.pop_back();
  expect_error(n, {}, "output node 3");
  expect_error(outputs(), {{-5, 0, 1.0, true}}, "unknown source");
  expect_error(outputs(), {{-1, 7, 1.0, true}}, "unknown or input target");
  expect_error(outputs(), {{-1, 0, 1.0, true}, {-1, 0, 2.0, false}}, "duplicate");
  n = outputs();
  n.push_back(n[0]);
  expect_error(n, {}, "duplicate node key 0");
}

}  // namespace
}  // namespace softevo::evo
