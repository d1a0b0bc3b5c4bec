// CPPN genome (node + connection genes) and its feed-forward evaluation with neat-python 0.92
// semantics (docs/model.md §6.1). Used by body development (§6) and by the NEAT operators.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/choice.hpp"
#include "common/robot.hpp"

namespace softevo::evo {

// The activation functions of neat-python 0.92 used by the thesis (§6.1). tanh is not in the
// thesis' activation_options but is accepted for tests and generic NEAT runs.
enum class Activation : std::uint8_t { sigmoid, sin, abs, square, exp, clamped, gauss, tanh };

}  // namespace softevo::evo
template <>
struct softevo::ChoiceNames<softevo::evo::Activation> {
  static constexpr std::array<const char*, 8> names = {"sigmoid", "sin",     "abs",   "square",
                                                       "exp",     "clamped", "gauss", "tanh"};
};
namespace softevo::evo {
// Throws std::invalid_argument naming the bad value.
Activation activation_from_string(const std::string& name);
// neat-python 0.92 definitions with their clamps (§6.1); z is the pre-activation.
double activate(Activation a, double z);

struct NodeGene {
  int key = 0;  // 0..num_outputs-1 = outputs, >= num_outputs = hidden
  double bias = 0.0;
  double response = 1.0;
  Activation activation = Activation::sigmoid;
  // Aggregation is always "sum" (the only one the thesis used).
};

struct ConnectionGene {
  int in = 0;  // input keys are -1..-num_inputs
  int out = 0;
  double weight = 0.0;
  bool enabled = true;
};

struct CppnGenome {
  int num_inputs = 4;           // keys -1..-num_inputs (x, y, z, d for bodies)
  int num_outputs = 4;          // keys 0..num_outputs-1 (presence, is_pneu, stiffness, sorting)
  std::vector<NodeGene> nodes;  // outputs and hidden nodes, sorted by key
  std::vector<ConnectionGene> connections;  // insertion order = summation order (§6.1)

  const NodeGene* find_node(int key) const;  // nullptr if absent
};

// Robot-file records (common/robot.hpp) <-> genome. Throws std::invalid_argument on a
// non-"sum" aggregation, unknown activation, duplicate node key or connection, a connection
// naming a node that does not exist, or missing output nodes.
CppnGenome cppn_from_records(const std::vector<CppnNodeRecord>& nodes,
                             const std::vector<CppnConnectionRecord>& connections,
                             int num_inputs = 4, int num_outputs = 4);
std::vector<CppnNodeRecord> cppn_node_records(const CppnGenome& genome);
std::vector<CppnConnectionRecord> cppn_connection_records(const CppnGenome& genome);

// neat-python 0.92 FeedForwardNetwork.create + activate (§6.1):
// * only enabled connections are used;
// * layers: from the input set S, repeatedly take the nodes that are the target of an enabled
//   connection from S, are required (have a path to an output) and have all enabled-incoming
//   sources in S;
// * value = act(bias + response * sum_i w_i v_i), summed left to right in connection order;
// * outputs (and nodes) that never enter a layer keep the value 0.0.
// Construction allocates; evaluation with a caller buffer does not.
class FeedForwardNetwork {
 public:
  explicit FeedForwardNetwork(const CppnGenome& genome);

  int num_inputs() const { return num_inputs_; }
  int num_outputs() const { return num_outputs_; }

  // Allocation-free: inputs.size() == num_inputs, outputs.size() == num_outputs.
  // Throws std::invalid_argument on a size mismatch.
  void activate(std::span<const double> inputs, std::span<double> outputs);
  std::vector<double> activate(std::span<const double> inputs);

  // Evaluation order (node keys), for tests and diagnostics.
  std::vector<int> evaluation_order() const;

 private:
  struct Term {
    int source;  // slot index into values_
    double weight;
  };
  struct Eval {
    int slot;  // slot index of the node being computed
    Activation activation;
    double bias;
    double response;
    int first_term;  // range into terms_
    int term_count;
    int key;
  };
  int num_inputs_ = 0;
  int num_outputs_ = 0;
  // Slots: [inputs -1..-n][outputs 0..m-1][hidden nodes in key order].
  std::vector<double> values_;
  std::vector<Eval> evals_;
  std::vector<Term> terms_;
};

}  // namespace softevo::evo
