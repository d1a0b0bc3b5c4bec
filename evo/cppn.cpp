#include "evo/cppn.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace softevo::evo {

namespace {

double clamp(double v, double lo, double hi) {
  return std::max(lo, std::min(hi, v));
}

}  // namespace

Activation activation_from_string(const std::string& name) {
  if (const auto a = choice_from_string<Activation>(name)) return *a;
  throw std::invalid_argument("unknown CPPN activation function '" + name +
                              "' (expected sigmoid, sin, abs, square, exp, clamped, gauss, tanh)");
}

double activate(Activation a, double z) {
  // neat-python 0.92 activations.py (§6.1). clamp = std::max(lo, std::min(hi, v)) behaves like
  // Python's max(lo, min(hi, v)) also for NaN (both keep the first argument): NaN -> hi.
  switch (a) {
    case Activation::sigmoid:  // 1/(1+exp(-clamp(5z,-60,60)))
      return 1.0 / (1.0 + std::exp(-clamp(5.0 * z, -60.0, 60.0)));
    case Activation::sin:  // sin(clamp(5z,-60,60))
      return std::sin(clamp(5.0 * z, -60.0, 60.0));
    case Activation::abs:
      return std::fabs(z);
    case Activation::square:
      return z * z;
    case Activation::exp:  // exp(clamp(z,-60,60))
      return std::exp(clamp(z, -60.0, 60.0));
    case Activation::clamped:
      return clamp(z, -1.0, 1.0);
    case Activation::gauss: {  // exp(-5 clamp(z,-3.4,3.4)^2)
      const double c = clamp(z, -3.4, 3.4);
      return std::exp(-5.0 * (c * c));
    }
    case Activation::tanh:  // tanh(clamp(2.5z,-60,60))
      return std::tanh(clamp(2.5 * z, -60.0, 60.0));
  }
  return 0.0;
}

const NodeGene* CppnGenome::find_node(int key) const {
  auto it = std::lower_bound(nodes.begin(), nodes.end(), key,
                             [](const NodeGene& n, int k) { return n.key < k; });
  return it != nodes.end() && it->key == key ? &*it : nullptr;
}

CppnGenome cppn_from_records(const std::vector<CppnNodeRecord>& nodes,
                             const std::vector<CppnConnectionRecord>& connections, int num_inputs,
                             int num_outputs) {
  if (num_inputs < 1 || num_outputs < 1)
    throw std::invalid_argument("CPPN: num_inputs and num_outputs must be positive");
  CppnGenome g;
  g.num_inputs = num_inputs;
  g.num_outputs = num_outputs;
  for (const auto& r : nodes) {
    const std::string where = "CPPN node " + std::to_string(r.key);
    if (r.key < 0)
      throw std::invalid_argument(where + ": node keys must be >= 0 (inputs are implicit)");
    if (r.aggregation != "sum")
      throw std::invalid_argument(where + ": aggregation '" + r.aggregation +
                                  "' is not supported (only 'sum')");
    Activation act;
    try {
      act = activation_from_string(r.activation);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
    g.nodes.push_back(NodeGene{r.key, r.bias, r.response, act});
  }
  std::sort(g.nodes.begin(), g.nodes.end(),
            [](const NodeGene& a, const NodeGene& b) { return a.key < b.key; });
  for (std::size_t i = 1; i < g.nodes.size(); ++i)
    if (g.nodes[i].key == g.nodes[i - 1].key)
      throw std::invalid_argument("CPPN: duplicate node key " + std::to_string(g.nodes[i].key));
  for (int k = 0; k < num_outputs; ++k)
    if (!g.find_node(k))
      throw std::invalid_argument("CPPN: output node " + std::to_string(k) + " is missing");
  auto known = [&](int key) { return (key < 0 && key >= -num_inputs) || g.find_node(key); };
  for (const auto& c : connections) {
    const std::string where =
        "CPPN connection (" + std::to_string(c.in) + ", " + std::to_string(c.out) + ")";
    if (!known(c.in)) throw std::invalid_argument(where + ": unknown source node");
    if (c.out < 0 || !g.find_node(c.out))
      throw std::invalid_argument(where + ": unknown or input target node");
    for (const auto& e : g.connections)
      if (e.in == c.in && e.out == c.out) throw std::invalid_argument(where + ": duplicate");
    g.connections.push_back(ConnectionGene{c.in, c.out, c.weight, c.enabled});
  }
  return g;
}

std::vector<CppnNodeRecord> cppn_node_records(const CppnGenome& genome) {
  std::vector<CppnNodeRecord> out;
  out.reserve(genome.nodes.size());
  for (const auto& n : genome.nodes)
    out.push_back(CppnNodeRecord{n.key, n.bias, n.response, to_string(n.activation), "sum"});
  return out;
}

std::vector<CppnConnectionRecord> cppn_connection_records(const CppnGenome& genome) {
  std::vector<CppnConnectionRecord> out;
  out.reserve(genome.connections.size());
  for (const auto& c : genome.connections)
    out.push_back(CppnConnectionRecord{c.in, c.out, c.weight, c.enabled});
  return out;
}

FeedForwardNetwork::FeedForwardNetwork(const CppnGenome& genome)
    : num_inputs_(genome.num_inputs), num_outputs_(genome.num_outputs) {
  if (num_inputs_ < 1 || num_outputs_ < 1)
    throw std::invalid_argument("FeedForwardNetwork: num_inputs and num_outputs must be positive");
  // Slot layout: [inputs -1..-n][outputs 0..m-1][hidden nodes in key order].
  std::vector<int> hidden_keys;
  for (const auto& n : genome.nodes) {
    if (n.key < 0)
      throw std::invalid_argument("FeedForwardNetwork: negative node key " + std::to_string(n.key));
    if (n.key >= num_outputs_) hidden_keys.push_back(n.key);
  }
  std::sort(hidden_keys.begin(), hidden_keys.end());
  const int slots = num_inputs_ + num_outputs_ + static_cast<int>(hidden_keys.size());
  auto slot_of = [&](int key) -> int {
    if (key < 0) return key >= -num_inputs_ ? -key - 1 : -1;
    if (key < num_outputs_) return num_inputs_ + key;
    auto it = std::lower_bound(hidden_keys.begin(), hidden_keys.end(), key);
    return it != hidden_keys.end() && *it == key
               ? num_inputs_ + num_outputs_ + static_cast<int>(it - hidden_keys.begin())
               : -1;
  };
  auto key_of = [&](int slot) -> int {
    if (slot < num_inputs_) return -slot - 1;
    if (slot < num_inputs_ + num_outputs_) return slot - num_inputs_;
    return hidden_keys[static_cast<std::size_t>(slot - num_inputs_ - num_outputs_)];
  };

  // Enabled connections as slot pairs, in genome order (summation order, §6.1).
  struct Link {
    int in, out;
    double weight;
  };
  std::vector<Link> links;
  for (const auto& c : genome.connections) {
    if (!c.enabled) continue;
    const int a = slot_of(c.in), b = slot_of(c.out);
    if (a < 0 || b < 0 || c.out < 0)
      throw std::invalid_argument("FeedForwardNetwork: connection (" + std::to_string(c.in) + ", " +
                                  std::to_string(c.out) + ") names an unknown node");
    links.push_back(Link{a, b, c.weight});
  }
  for (int k = 0; k < num_outputs_; ++k)
    if (!genome.find_node(k))
      throw std::invalid_argument("FeedForwardNetwork: output node " + std::to_string(k) +
                                  " is missing");

  auto is_input = [&](int slot) { return slot < num_inputs_; };

  // neat-python graphs.required_for_output: nodes with a path to an output.
  std::vector<char> required(static_cast<std::size_t>(slots), 0), in_s(required);
  for (int k = 0; k < num_outputs_; ++k) required[num_inputs_ + k] = in_s[num_inputs_ + k] = 1;
  for (;;) {
    std::vector<int> t;
    for (const auto& l : links)
      if (in_s[l.out] && !in_s[l.in] && std::find(t.begin(), t.end(), l.in) == t.end())
        t.push_back(l.in);
    if (t.empty()) break;
    bool any_layer_node = false;
    for (int n : t)
      if (!is_input(n)) {
        required[n] = 1;
        any_layer_node = true;
      }
    if (!any_layer_node) break;
    for (int n : t) in_s[n] = 1;
  }

  // neat-python graphs.feed_forward_layers.
  std::fill(in_s.begin(), in_s.end(), 0);
  for (int i = 0; i < num_inputs_; ++i) in_s[i] = 1;
  std::vector<std::vector<int>> layers;
  for (;;) {
    std::vector<int> layer;
    for (const auto& l : links) {
      const int n = l.out;
      if (!in_s[l.in] || in_s[n] || !required[n]) continue;
      if (std::find(layer.begin(), layer.end(), n) != layer.end()) continue;
      bool all_inputs_ready = true;
      for (const auto& m : links)
        if (m.out == n && !in_s[m.in]) all_inputs_ready = false;
      if (all_inputs_ready) layer.push_back(n);
    }
    if (layer.empty()) break;
    // Nodes of one layer do not depend on each other; sort by key for a canonical order.
    std::sort(layer.begin(), layer.end(), [&](int a, int b) { return key_of(a) < key_of(b); });
    for (int n : layer) in_s[n] = 1;
    layers.push_back(std::move(layer));
  }

  for (const auto& layer : layers)
    for (int n : layer) {
      const NodeGene* gene = genome.find_node(key_of(n));
      Eval e{n, gene->activation, gene->bias, gene->response, static_cast<int>(terms_.size()),
             0, gene->key};
      for (const auto& l : links)
        if (l.out == n) terms_.push_back(Term{l.in, l.weight});
      e.term_count = static_cast<int>(terms_.size()) - e.first_term;
      evals_.push_back(e);
    }
  values_.assign(static_cast<std::size_t>(slots), 0.0);
}

void FeedForwardNetwork::activate(std::span<const double> inputs, std::span<double> outputs) {
  if (inputs.size() != static_cast<std::size_t>(num_inputs_) ||
      outputs.size() != static_cast<std::size_t>(num_outputs_))
    throw std::invalid_argument(
        "FeedForwardNetwork::activate: expected " + std::to_string(num_inputs_) + " inputs and " +
        std::to_string(num_outputs_) + " outputs, got " + std::to_string(inputs.size()) + " and " +
        std::to_string(outputs.size()));
  // Non-input values persist between queries like neat's `values` dict: nodes that are never
  // evaluated stay 0.0 (§6.1) and evaluated nodes are overwritten before they are read.
  for (int i = 0; i < num_inputs_; ++i) values_[static_cast<std::size_t>(i)] = inputs[i];
  for (const Eval& e : evals_) {
    // §6.1: value = act(bias + response * sum_i w_i v_i), Python left-to-right sum from 0.
    double s = 0.0;
    for (int t = e.first_term; t < e.first_term + e.term_count; ++t) {
      const Term& term = terms_[static_cast<std::size_t>(t)];
      s += values_[static_cast<std::size_t>(term.source)] * term.weight;
    }
    values_[static_cast<std::size_t>(e.slot)] =
        evo::activate(e.activation, e.bias + e.response * s);
  }
  for (int k = 0; k < num_outputs_; ++k)
    outputs[k] = values_[static_cast<std::size_t>(num_inputs_ + k)];
}

std::vector<double> FeedForwardNetwork::activate(std::span<const double> inputs) {
  std::vector<double> out(static_cast<std::size_t>(num_outputs_));
  activate(inputs, out);
  return out;
}

std::vector<int> FeedForwardNetwork::evaluation_order() const {
  std::vector<int> keys;
  keys.reserve(evals_.size());
  for (const Eval& e : evals_) keys.push_back(e.key);
  return keys;
}

}  // namespace softevo::evo
