#include "evo/mutation.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace softevo::evo {

const std::array<int, kControllerVectorCount> kControllerMutationOrder = {
    0,  // weights_hidden
    2,  // weights_out
    4,  // weights_recurrent
    5,  // weights_recurrent_self
    1,  // bias_hidden
    3,  // bias_out
    7,  // bias_context
    6,  // weights_context
    8,  // freq
};

double mutate_float(double value, const FloatMutation& m, Rng& rng) {
  const double r = rng.uniform();
  if (r < m.rate) return std::clamp(value + m.power * rng.normal(), m.lo, m.hi);
  if (r < m.replace_rate + m.rate)
    return init_clamped_gaussian(m.init_mean, m.init_stdev, m.lo, m.hi, rng);
  return value;
}

FloatMutation weight_mutation(const NeatConfig& c) {
  return {c.weight_mutate_rate, c.weight_mutate_power, c.weight_replace_rate, c.weight_init_mean,
          c.weight_init_stdev,  c.weight_min_value,    c.weight_max_value};
}
FloatMutation bias_mutation(const NeatConfig& c) {
  return {c.bias_mutate_rate, c.bias_mutate_power, c.bias_replace_rate, c.bias_init_mean,
          c.bias_init_stdev,  c.bias_min_value,    c.bias_max_value};
}
FloatMutation response_mutation(const NeatConfig& c) {
  return {c.response_mutate_rate, c.response_mutate_power, c.response_replace_rate,
          c.response_init_mean,   c.response_init_stdev,   c.response_min_value,
          c.response_max_value};
}

bool mutate_enabled(bool value, double rate, Rng& rng) {
  if (rate > 0.0 && rng.uniform() < rate) return rng.uniform() < 0.5;
  return value;
}

bool creates_cycle(const std::vector<ConnectionGene>& connections, int in, int out) {
  // Forward reachability from `out`: the new edge closes a cycle iff `in` is reachable.
  if (in == out) return true;
  std::unordered_set<int> visited{out};
  while (true) {
    int added = 0;
    for (const ConnectionGene& c : connections) {
      if (visited.count(c.in) && !visited.count(c.out)) {
        if (c.out == in) return true;
        visited.insert(c.out);
        ++added;
      }
    }
    if (added == 0) return false;
  }
}

namespace {

void insert_node(CppnGenome& g, const NodeGene& n) {
  auto it = std::lower_bound(g.nodes.begin(), g.nodes.end(), n.key,
                             [](const NodeGene& a, int k) { return a.key < k; });
  if (it != g.nodes.end() && it->key == n.key)
    throw std::logic_error("add node: node key " + std::to_string(n.key) +
                           " already exists (node-key counter out of step with the genome)");
  g.nodes.insert(it, n);
}

}  // namespace

bool try_add_connection(CppnGenome& g, const EvoParams& p, Rng& rng);

int mutate_add_node(CppnGenome& g, const EvoParams& p, InnovationTracker& innovation, Rng& rng) {
  if (g.connections.empty()) return -1;  // structural_mutation_surer = False
  const std::size_t split = rng.uniform_int(g.connections.size());
  const int key = innovation.new_node_key();
  insert_node(g, new_node_gene(key, p, rng));
  ConnectionGene& old = g.connections[split];
  old.enabled = false;
  const int in = old.in;
  const int out = old.out;
  const double weight = old.weight;
  // in -> new with weight 1 and new -> out with the old weight keep the signal path roughly
  // as before (exactly for a linear activation).
  g.connections.push_back(ConnectionGene{in, key, 1.0, true});
  g.connections.push_back(ConnectionGene{key, out, weight, true});
  return key;
}

bool mutate_add_connection(CppnGenome& g, const EvoParams& p, Rng& rng) {
  for (int attempt = 0; attempt < std::max(1, p.add_connection_attempts); ++attempt)
    if (try_add_connection(g, p, rng)) return true;
  return false;
}

bool try_add_connection(CppnGenome& g, const EvoParams& p, Rng& rng) {
  // possible_outputs = node keys (dict order = key order); possible_inputs = those + input keys
  // -1, -2, ... (neat-python config.input_keys order).
  const std::size_t n_nodes = g.nodes.size();
  if (n_nodes == 0) return false;
  const int out = g.nodes[rng.uniform_int(n_nodes)].key;
  const std::size_t pick = rng.uniform_int(n_nodes + static_cast<std::size_t>(g.num_inputs));
  const int in = pick < n_nodes ? g.nodes[pick].key : -static_cast<int>(pick - n_nodes) - 1;
  for (const ConnectionGene& c : g.connections)
    if (c.in == in && c.out == out) return false;  // exists (structural_mutation_surer = False)
  const bool in_is_output = in >= 0 && in < g.num_outputs;
  const bool out_is_output = out < g.num_outputs;
  if (in_is_output && out_is_output) return false;
  if (p.feed_forward && creates_cycle(g.connections, in, out)) return false;
  const NeatConfig& c = p.neat;
  const double w = init_clamped_gaussian(c.weight_init_mean, c.weight_init_stdev,
                                         c.weight_min_value, c.weight_max_value, rng);
  g.connections.push_back(ConnectionGene{in, out, w, true});
  return true;
}

void mutate_delete_connection(CppnGenome& g, Rng& rng) {
  if (g.connections.empty()) return;
  const std::size_t i = rng.uniform_int(g.connections.size());
  g.connections.erase(g.connections.begin() + static_cast<std::ptrdiff_t>(i));
}

void mutate_delete_node(CppnGenome& g, Rng& rng) {
  std::vector<std::size_t> hidden;
  for (std::size_t i = 0; i < g.nodes.size(); ++i)
    if (g.nodes[i].key >= g.num_outputs) hidden.push_back(i);
  if (hidden.empty()) return;
  const std::size_t idx = hidden[rng.uniform_int(hidden.size())];
  const int key = g.nodes[idx].key;
  std::erase_if(g.connections,
                [key](const ConnectionGene& c) { return c.in == key || c.out == key; });
  g.nodes.erase(g.nodes.begin() + static_cast<std::ptrdiff_t>(idx));
}

void mutate_cppn(CppnGenome& g, const EvoParams& p, InnovationTracker& innovation, Rng& rng) {
  const NeatConfig& c = p.neat;
  if (rng.uniform() < c.node_add_prob) mutate_add_node(g, p, innovation, rng);
  if (rng.uniform() < c.node_delete_prob) mutate_delete_node(g, rng);
  if (rng.uniform() < c.conn_add_prob) mutate_add_connection(g, p, rng);
  if (rng.uniform() < c.conn_delete_prob) mutate_delete_connection(g, rng);
  const FloatMutation wm = weight_mutation(c);
  for (ConnectionGene& e : g.connections) {
    e.weight = mutate_float(e.weight, wm, rng);
    e.enabled = mutate_enabled(e.enabled, c.enabled_mutate_rate, rng);
  }
  const FloatMutation bm = bias_mutation(c);
  const FloatMutation rm = response_mutation(c);
  const bool activation_mutates = c.activation_mutate_rate > 0.0 && !p.activation_options.empty();
  for (NodeGene& n : g.nodes) {
    n.bias = mutate_float(n.bias, bm, rng);
    n.response = mutate_float(n.response, rm, rng);
    if (activation_mutates && rng.uniform() < c.activation_mutate_rate)
      n.activation = p.activation_options[rng.uniform_int(p.activation_options.size())];
  }
}

void mutate_controller(Genome& g, const EvoParams& p, Rng& rng) {
  if (!g.has_controller()) return;
  auto values = vectors_of(g.controller);
  auto steps = vectors_of(g.step_sizes);
  const double limit = p.controller.gene_limit;
  for (int v : kControllerMutationOrder) {
    std::vector<double>& sigma = *steps[v];
    std::vector<double>& w = *values[v];
    // §8.7: additive self-adaptation, sigma' = sigma + N(0,1) sigma (not log-normal, no tau);
    // sigma may become negative (acts like |sigma|) and 0 freezes the gene forever.
    for (double& s : sigma) s = std::clamp(s + rng.normal() * s, -limit, limit);
    for (std::size_t i = 0; i < w.size(); ++i)
      w[i] = std::clamp(w[i] + rng.normal() * sigma[i], -limit, limit);
    if (v == kFreqVector)
      for (double& f : w) f = std::clamp(f, p.controller.freq_min, p.controller.freq_max);
  }
}

void mutate(Genome& g, const EvoParams& p, InnovationTracker& innovation, Rng& rng) {
  mutate_cppn(g.cppn, p, innovation, rng);
  mutate_controller(g, p, rng);
}

}  // namespace softevo::evo
