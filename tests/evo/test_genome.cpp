// Genome: controller shape, initialisation (§8.2), canonical encoding, robot-file conversion.
#include "evo/genome.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "common/wire.hpp"

namespace softevo::evo {
namespace {

Config default_config() {
  return Config{};
}

TEST(GenomeShape, GeneCountsOfTheFourExperiments) {
  // §4.4: 4 n_in + 133 genes for n_in = 2 / 12 / 3 / 13 (no task input: gait; one: directed).
  Config c;
  c.task.control = ControlLoop::open;
  EXPECT_EQ(controller_shape(c, 0).gene_count(), 141u);
  c.task.control = ControlLoop::closed;
  EXPECT_EQ(controller_shape(c, 0).gene_count(), 181u);
  c.task.control = ControlLoop::open;
  EXPECT_EQ(controller_shape(c, 1).gene_count(), 145u);
  c.task.control = ControlLoop::closed;
  EXPECT_EQ(controller_shape(c, 1).gene_count(), 185u);
  const auto len = controller_shape(c, 1).lengths();
  EXPECT_EQ(len[0], 13u * 4);  // weights_hidden
  EXPECT_EQ(len[2], 4u * 20);  // weights_out
  EXPECT_EQ(len[8], 1u);       // freq
}

TEST(GenomeParams, BadActivationNamesAreErrorsNamingTheKey) {
  Config c;
  c.neat.activation_options = {"sigmoid", "relu"};
  try {
    evo_params(c, 0);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("neat.activation_options"), std::string::npos);
  }
}

TEST(GenomeInit, CppnHasOutputsAndFullInputOutputConnectivity) {
  const EvoParams p = evo_params(default_config(), 0);
  Rng rng(7);
  const CppnGenome g = random_cppn(p, rng);
  ASSERT_EQ(g.nodes.size(), 4u);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(g.nodes[k].key, k);
  ASSERT_EQ(g.connections.size(), 16u);
  // neat-python compute_full_connections: inputs outer (-1, -2, ...), outputs inner.
  for (int i = 0; i < 4; ++i)
    for (int o = 0; o < 4; ++o) {
      EXPECT_EQ(g.connections[i * 4 + o].in, -(i + 1));
      EXPECT_EQ(g.connections[i * 4 + o].out, o);
      EXPECT_TRUE(g.connections[i * 4 + o].enabled);
    }
}

TEST(GenomeInit, ValuesAreClampedGaussiansAndActivationsUniform) {
  const EvoParams p = evo_params(default_config(), 0);
  Rng rng(11);
  std::map<Activation, int> counts;
  double sum = 0.0, sum2 = 0.0;
  int n = 0, clamped = 0;
  const int genomes = 20000;
  for (int k = 0; k < genomes; ++k) {
    const CppnGenome g = random_cppn(p, rng);
    for (const NodeGene& node : g.nodes) {
      EXPECT_GE(node.bias, -3.0);
      EXPECT_LE(node.bias, 3.0);
      EXPECT_EQ(node.response, 1.0);  // response_init_stdev = 0
      ++counts[node.activation];
    }
    for (const ConnectionGene& c : g.connections) {
      ASSERT_GE(c.weight, -3.0);
      ASSERT_LE(c.weight, 3.0);
      clamped += std::fabs(c.weight) == 3.0 ? 1 : 0;
      sum += c.weight;
      sum2 += c.weight * c.weight;
      ++n;
    }
  }
  // N(0,1) clamped at +-3: mean 0, variance 0.9946, P(|x| >= 3) = 0.0027.
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.0, 3.0 / std::sqrt(n));
  EXPECT_NEAR(sum2 / n, 0.9946, 0.01);
  const double p_clamp = 0.0027;
  EXPECT_NEAR(static_cast<double>(clamped) / n, p_clamp, 3 * std::sqrt(p_clamp / n));
  ASSERT_EQ(counts.size(), 7u);  // the 7 thesis options, never tanh
  const double expected = genomes * 4 / 7.0;
  const double se = std::sqrt(genomes * 4 * (1 / 7.0) * (6 / 7.0));
  for (const auto& [act, c] : counts) EXPECT_NEAR(c, expected, 3 * se) << to_string(act);
}

TEST(GenomeInit, ControllerFollowsSection82) {
  const EvoParams p = evo_params(default_config(), 0);
  Rng rng(3);
  double sum2 = 0.0;
  int n = 0, at_limit = 0;
  double freq_sum = 0.0;
  const int genomes = 2000;
  for (int k = 0; k < genomes; ++k) {
    Genome g;
    random_controller(p, rng, g);
    check_controller_shape(g, p.shape);
    const auto values = vectors_of(g.controller);
    const auto steps = vectors_of(g.step_sizes);
    for (int v = 0; v < kControllerVectorCount; ++v) {
      for (std::size_t i = 0; i < values[v]->size(); ++i) {
        const double x = (*values[v])[i];
        if (v == kFreqVector) {
          EXPECT_GE(x, 1.0);
          EXPECT_LT(x, 5.0);
          EXPECT_EQ((*steps[v])[i], 0.2);
          freq_sum += x;
        } else {
          ASSERT_GE(x, -5.0);
          ASSERT_LE(x, 5.0);
          EXPECT_EQ((*steps[v])[i], 3.0);
          sum2 += x * x;
          at_limit += std::fabs(x) == 5.0 ? 1 : 0;
          ++n;
        }
      }
    }
  }
  // N(0, 3^2) clipped at +-5: P(|x| >= 5) = 2 (1 - Phi(5/3)) = 0.0956.
  EXPECT_NEAR(static_cast<double>(at_limit) / n, 0.0956, 3 * std::sqrt(0.0956 * 0.9044 / n));
  // E[min(x^2, 25)] = 9 (P(|z| < c) - 2 c phi(c)) + 25 P(|z| > c), c = 5/3: 7.547.
  EXPECT_NEAR(sum2 / n, 7.547, 0.1);
  EXPECT_NEAR(freq_sum / genomes, 3.0, 3 * std::sqrt(16.0 / 12.0 / genomes));  // U(1,5)
}

Genome sample_genome(std::uint64_t seed) {
  const EvoParams p = evo_params(default_config(), 0);
  Rng rng(seed);
  Genome g = random_genome(p, rng);
  g.cppn.nodes.push_back(NodeGene{7, -0.25, 1.0, Activation::gauss});
  g.cppn.connections.push_back(ConnectionGene{-2, 7, 0.5, false});
  g.cppn.connections.push_back(ConnectionGene{7, 1, -1.5, true});
  return g;
}

bool same_genome(const Genome& a, const Genome& b) {
  return encode_genome(a) == encode_genome(b);
}

TEST(GenomeEncoding, RoundTripIsExactAndCanonical) {
  const Genome g = sample_genome(5);
  const auto bytes = encode_genome(g);
  const Genome back = decode_genome(bytes);
  EXPECT_EQ(encode_genome(back), bytes);
  ASSERT_EQ(back.cppn.connections.size(), g.cppn.connections.size());
  EXPECT_EQ(back.cppn.connections.back().weight, -1.5);
  EXPECT_FALSE(back.cppn.connections[16].enabled);
  EXPECT_EQ(back.cppn.nodes.back().activation, Activation::gauss);
  EXPECT_EQ(back.controller.weights_out, g.controller.weights_out);
  EXPECT_EQ(back.step_sizes.freq, g.step_sizes.freq);
  // A genome without controller (plain NEAT) also round-trips.
  Genome plain;
  plain.cppn = g.cppn;
  EXPECT_FALSE(decode_genome(encode_genome(plain)).has_controller());
  EXPECT_FALSE(same_genome(plain, g));
}

// Re-encode a genome with a raw payload edit applied through the writer.
std::vector<std::uint8_t> frame(const WireWriter& w) {
  return frame_message(MessageKind::genome, w.data());
}

TEST(GenomeEncoding, MalformedBytesAreRejectedWithClearErrors) {
  const Genome g = sample_genome(6);
  auto bytes = encode_genome(g);
  // Truncated and oversized.
  std::vector<std::uint8_t> truncated(bytes.begin(), bytes.end() - 3);
  EXPECT_THROW(decode_genome(truncated), WireError);
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_THROW(decode_genome(longer), WireError);

  auto expect_error = [](const Genome& bad, const std::string& needle) {
    WireWriter w;
    write_genome_payload(w, bad);
    try {
      decode_genome(frame(w));
      ADD_FAILURE() << "accepted a genome with " << needle;
    } catch (const WireError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  Genome bad = g;
  std::swap(bad.cppn.nodes[0], bad.cppn.nodes[1]);
  expect_error(bad, "strictly increasing");
  bad = g;
  bad.cppn.nodes.erase(bad.cppn.nodes.begin() + 2);
  expect_error(bad, "output node 2 is missing");
  bad = g;
  bad.cppn.connections.push_back(bad.cppn.connections[0]);
  expect_error(bad, "duplicate connection");
  bad = g;
  bad.cppn.connections.push_back(ConnectionGene{-9, 0, 1.0, true});
  expect_error(bad, "unknown source node");
  bad = g;
  bad.cppn.connections.push_back(ConnectionGene{0, 42, 1.0, true});
  expect_error(bad, "unknown or input target");
  bad = g;
  bad.cppn.connections[3].weight = std::nan("");
  expect_error(bad, "not finite");
  bad = g;
  bad.controller.bias_out.pop_back();
  bad.step_sizes.bias_out.pop_back();
  expect_error(bad, "weights_out");  // 19 outputs no longer match weights_out
  bad = g;
  bad.step_sizes.freq.clear();
  expect_error(bad, "freq");
  // An unknown activation code: patch the byte of the first node's activation.
  // Offset: 16 header + 4 + 4 + 8 (count) + 4 (key) + 8 + 8 = 52.
  auto patched = bytes;
  patched[52] = 9;
  EXPECT_THROW(decode_genome(patched), WireError);
  // A wrong message kind.
  WireWriter w;
  write_genome_payload(w, g);
  EXPECT_THROW(decode_genome(frame_message(MessageKind::population, w.data())), WireError);
}

TEST(GenomeRobotFile, RecordsAndControllerSpecRoundTrip) {
  Config c;
  c.task.control = ControlLoop::closed;
  const EvoParams p = evo_params(c, 1);  // one task input (the directed task's)
  Rng rng(9);
  const Genome g = random_genome(p, rng);
  const ControllerSpec spec = to_controller_spec(g, c, 1);
  EXPECT_TRUE(spec.closed_loop);
  EXPECT_TRUE(spec.directed);
  EXPECT_EQ(spec.input_count(), 13);
  EXPECT_EQ(spec.outputs, 20);
  EXPECT_EQ(spec.frequency(), g.controller.freq[0]);
  const RobotGenomeRecord rec = to_genome_record(g, c);
  EXPECT_EQ(rec.distance_input, c.body.distance_input);
  EXPECT_EQ(rec.nodes.size(), 4u);
  const Genome back = genome_from_robot(rec, spec);
  EXPECT_TRUE(same_genome(back, g));
  // A controller of another shape does not fit the config.
  Config other;
  EXPECT_THROW(to_controller_spec(g, other, 1), std::invalid_argument);
  EXPECT_THROW(to_controller_spec(g, c, 0), std::invalid_argument);
  // A robot file records at most one task input.
  EXPECT_THROW(to_controller_spec(g, c, 2), std::invalid_argument);
}

}  // namespace
}  // namespace softevo::evo
