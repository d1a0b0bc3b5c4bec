// Mutation operators (docs/model.md §8.7): neat-python 0.92 DefaultGenome.mutate for the CPPN
// (single_structural_mutation = False) and the thesis' additive self-adaptive mutation of the
// controller sub-genome. Every child is mutated (§8.5 step 5). All randomness from `rng`.
#pragma once

#include <vector>

#include "common/rng.hpp"
#include "evo/genome.hpp"
#include "evo/innovation.hpp"

namespace softevo::evo {

// --- Attribute mutations (neat-python 0.92 attributes.py) --------------------------------------
// FloatAttribute.mutate_value: r = U[0,1); r < rate -> clamp(v + N(0, power), lo, hi);
// r < rate + replace_rate -> fresh clamp(N(init_mean, init_stdev)); else unchanged.
struct FloatMutation {
  double rate, power, replace_rate, init_mean, init_stdev, lo, hi;
};
double mutate_float(double value, const FloatMutation& m, Rng& rng);
FloatMutation weight_mutation(const NeatConfig& c);
FloatMutation bias_mutation(const NeatConfig& c);
FloatMutation response_mutation(const NeatConfig& c);
// BoolAttribute.mutate_value (rate_to_true/false_add = 0): with probability `rate` the value is
// replaced by a random boolean, so it actually flips with probability rate/2.
bool mutate_enabled(bool value, double rate, Rng& rng);

// --- Structural CPPN mutations ----------------------------------------------------------------
// neat-python graphs.creates_cycle: would adding in->out close a directed cycle over the existing
// connections (enabled or not)? A self-loop counts as a cycle.
bool creates_cycle(const std::vector<ConnectionGene>& connections, int in, int out);
// Split a uniformly chosen connection (enabled or not): disable it, add node `new key` (fresh
// bias/activation), in->new with weight 1.0 and new->out with the old weight, both enabled.
// No-op without connections. Returns the new node key or -1.
int mutate_add_node(CppnGenome& g, const EvoParams& p, InnovationTracker& innovation, Rng& rng);
// out = uniform node (outputs + hidden), in = uniform from nodes + inputs; skipped if the
// connection exists, if both ends are outputs or (feed-forward) if it would create a cycle.
// Returns true when a connection was added. Repeated up to p.add_connection_attempts times until
// one succeeds (1 = neat-python).
bool mutate_add_connection(CppnGenome& g, const EvoParams& p, Rng& rng);
bool try_add_connection(CppnGenome& g, const EvoParams& p, Rng& rng);  // one attempt
// Remove a uniformly chosen connection (no-op without connections).
void mutate_delete_connection(CppnGenome& g, Rng& rng);
// Remove a uniformly chosen hidden node and every connection touching it (no-op without hidden
// nodes). Rate 0 in the thesis; here for completeness of neat-python's operator set.
void mutate_delete_node(CppnGenome& g, Rng& rng);

// DefaultGenome.mutate: independent structural draws (add node, delete node, add connection,
// delete connection, in this order), then every connection (weight, enabled), then every node
// (bias, response, activation).
void mutate_cppn(CppnGenome& g, const EvoParams& p, InnovationTracker& innovation, Rng& rng);

// §8.7 controller: for each vector in the order weights_hidden, weights_out, weights_recurrent,
// weights_recurrent_self, bias_hidden, bias_out, bias_context, weights_context, freq: first all
// step sizes sigma' = clip(sigma + N(0,1) sigma, -L, L), then all values
// w' = clip(w + N(0,1) sigma', -L, L); the frequency is then clamped to [freq_min, freq_max].
// No-op for a genome without controller.
void mutate_controller(Genome& g, const EvoParams& p, Rng& rng);
// The vector order of mutate_controller as canonical indices (§4.4 numbering - 1).
extern const std::array<int, kControllerVectorCount> kControllerMutationOrder;

// Both parts: CPPN first, then the controller.
void mutate(Genome& g, const EvoParams& p, InnovationTracker& innovation, Rng& rng);

}  // namespace softevo::evo
