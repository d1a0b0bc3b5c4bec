#include "evo/genome.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/wire.hpp"

namespace softevo::evo {

const std::array<const char*, kControllerVectorCount> kControllerVectorNames = {
    "weights_hidden",         "bias_hidden",     "weights_out",  "bias_out", "weights_recurrent",
    "weights_recurrent_self", "weights_context", "bias_context", "freq"};

std::array<std::size_t, kControllerVectorCount> ControllerShape::lengths() const {
  const auto ni = static_cast<std::size_t>(inputs);
  const auto h = static_cast<std::size_t>(hidden);
  const auto no = static_cast<std::size_t>(outputs);
  // §4.4 table, rows 1..9.
  return {ni * h, h, h * no, no, h * h, h, h, h, 1};
}

std::size_t ControllerShape::gene_count() const {
  std::size_t n = 0;
  for (std::size_t len : lengths()) n += len;
  return n;
}

std::array<std::vector<double>*, kControllerVectorCount> vectors_of(ControllerVectors& v) {
  return {&v.weights_hidden,  &v.bias_hidden,       &v.weights_out,
          &v.bias_out,        &v.weights_recurrent, &v.weights_recurrent_self,
          &v.weights_context, &v.bias_context,      &v.freq};
}

std::array<const std::vector<double>*, kControllerVectorCount> vectors_of(
    const ControllerVectors& v) {
  return {&v.weights_hidden,  &v.bias_hidden,       &v.weights_out,
          &v.bias_out,        &v.weights_recurrent, &v.weights_recurrent_self,
          &v.weights_context, &v.bias_context,      &v.freq};
}

ControllerShape controller_shape(const Config& config, int task_inputs) {
  ControllerShape s;
  s.inputs = controller_input_count(task_inputs, config.task.control == ControlLoop::closed,
                                    config.controller.oscillator_inputs);
  s.hidden = static_cast<int>(config.controller.hidden);
  s.outputs = static_cast<int>(2 * config.body.max_chambers);  // inlet + outlet per chamber (§4.5)
  return s;
}

EvoParams evo_params(const Config& config, int task_inputs) {
  EvoParams p;
  p.neat = config.neat;
  // learning.body_mutate_power_factor (1 unless learning is on): the body's mutation strength
  // the thesis cut 20-fold for the sake of inherited controllers (docs/model.md §8.11).
  p.neat.weight_mutate_power *= config.learning.body_mutate_power_factor;
  p.neat.bias_mutate_power *= config.learning.body_mutate_power_factor;
  p.num_inputs = 4;   // x, y, z, d (§6.2)
  p.num_outputs = 4;  // presence, is_pneu, stiffness, sorting (§6.3)
  p.feed_forward = true;
  for (const std::string& name : config.neat.activation_options) {
    try {
      p.activation_options.push_back(activation_from_string(name));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("neat.activation_options: ") + e.what());
    }
  }
  if (p.activation_options.empty())
    throw std::invalid_argument("neat.activation_options: must not be empty");
  if (config.neat.activation_default == "random") {
    p.activation_random = true;
  } else {
    p.activation_random = false;
    try {
      p.activation_default = activation_from_string(config.neat.activation_default);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("neat.activation_default: ") + e.what());
    }
  }
  p.with_controller = true;
  p.shape = controller_shape(config, task_inputs);
  p.controller = config.controller;
  p.crossover_method = config.controller.crossover_method;
  p.mutate_only_probability = 0.0;  // §8.5 step 5
  return p;
}

// ---------------------------------------------------------------------------------------------
// Initialisation

double init_clamped_gaussian(double mean, double stdev, double lo, double hi, Rng& rng) {
  // neat-python 0.92 FloatAttribute.init_value (init_type gaussian): clamp(gauss(mean, stdev)).
  const double v = mean + stdev * rng.normal();
  return std::max(lo, std::min(hi, v));
}

NodeGene new_node_gene(int key, const EvoParams& p, Rng& rng) {
  // DefaultNodeGene attribute order: bias, response, activation (aggregation is always sum).
  NodeGene n;
  n.key = key;
  const NeatConfig& c = p.neat;
  n.bias = init_clamped_gaussian(c.bias_init_mean, c.bias_init_stdev, c.bias_min_value,
                                 c.bias_max_value, rng);
  n.response = init_clamped_gaussian(c.response_init_mean, c.response_init_stdev,
                                     c.response_min_value, c.response_max_value, rng);
  if (p.activation_random) {
    n.activation = p.activation_options[rng.uniform_int(p.activation_options.size())];
  } else {
    n.activation = p.activation_default;
  }
  return n;
}

CppnGenome random_cppn(const EvoParams& p, Rng& rng) {
  CppnGenome g;
  g.num_inputs = p.num_inputs;
  g.num_outputs = p.num_outputs;
  for (int k = 0; k < p.num_outputs; ++k) g.nodes.push_back(new_node_gene(k, p, rng));
  const NeatConfig& c = p.neat;
  for (int i = 1; i <= p.num_inputs; ++i) {
    for (int o = 0; o < p.num_outputs; ++o) {
      const double w = init_clamped_gaussian(c.weight_init_mean, c.weight_init_stdev,
                                             c.weight_min_value, c.weight_max_value, rng);
      g.connections.push_back(ConnectionGene{-i, o, w, true});  // enabled_default = True
    }
  }
  return g;
}

namespace {

// §4.8: the hand-made genes of the pressure-driven oscillator (before the perturbation). Chamber
// q is served by hidden unit i = q mod H: its sensor drives the unit with gain -kSensorGain, the
// unit's context copies the unit (kContextCopy) and feeds it back with kHysteresis, and the unit
// opens the inlet (+kValveGain) and closes the outlet (-kValveGain). The unit switches when the
// summed sensors of its chambers cross +-kHysteresis c / kSensorGain = +-0.5 (1.025 and 1.075
// bar, §3.7), in the direction that ends the current stroke.
constexpr double kSensorGain = 4.0;
constexpr double kHysteresis = 2.0;
constexpr double kContextCopy = 3.0;
constexpr double kValveGain = 3.0;

void oscillator_genes(const ControllerShape& shape, int oscillator_inputs, int task_inputs,
                      ControllerVectors& v) {
  const int h = shape.hidden;
  const int chambers = shape.outputs / 2;
  for (int q = 0; q < chambers; ++q) {
    const int unit = q % h;
    // §4.1: after the oscillator inputs, at most 10 sensor values, the task's first; a chamber
    // past them (the 10th of a directed robot) has no sensor and follows its unit's others.
    const int sensor = task_inputs + q;
    if (sensor < kPressureSensorInputs) {
      const auto input = static_cast<std::size_t>(oscillator_inputs + sensor);
      v.weights_hidden[input * h + unit] = -kSensorGain;
    }
    v.weights_out[static_cast<std::size_t>(unit * shape.outputs + 2 * q)] = kValveGain;
    v.weights_out[static_cast<std::size_t>(unit * shape.outputs + 2 * q + 1)] = -kValveGain;
  }
  for (int i = 0; i < h; ++i) {
    v.weights_recurrent[static_cast<std::size_t>(i * h + i)] = kHysteresis;
    v.weights_context[i] = kContextCopy;
  }
}

}  // namespace

void oscillator_controller(const EvoParams& p, Rng& rng, Genome& genome) {
  const ControllerShape& shape = p.shape;
  const int oscillator_inputs = p.controller.oscillator_inputs ? kOscillatorInputs : 0;
  const int task_inputs = shape.inputs - oscillator_inputs - kPressureSensorInputs;
  if (task_inputs < 0)
    throw std::invalid_argument(
        "controller.init = \"oscillator\" needs the pressure sensors of a closed-loop controller");
  const auto lengths = shape.lengths();
  auto values = vectors_of(genome.controller);
  auto steps = vectors_of(genome.step_sizes);
  for (int v = 0; v < kControllerVectorCount; ++v) values[v]->assign(lengths[v], 0.0);
  oscillator_genes(shape, oscillator_inputs, task_inputs, genome.controller);
  // The perturbation in canonical order, one draw per gene as random_controller draws; small
  // step sizes, because the first mutation with weight_init_sd (3.0) would erase the design.
  const double sd = p.controller.init_perturbation_sd;
  const double limit = p.controller.gene_limit;
  for (int v = 0; v < kControllerVectorCount; ++v) {
    steps[v]->assign(lengths[v], sd);
    for (double& x : *values[v]) {
      if (v == kFreqVector) {
        x = rng.uniform(p.controller.freq_min, p.controller.freq_max);  // unused without sin/cos
      } else {
        x = std::clamp(x + sd * rng.normal(), -limit, limit);
      }
    }
  }
  genome.step_sizes.freq.assign(1, p.controller.freq_step_size_init);
}

void random_controller(const EvoParams& p, Rng& rng, Genome& genome) {
  if (p.controller.init == ControllerInit::oscillator) {
    oscillator_controller(p, rng, genome);
    return;
  }
  const auto lengths = p.shape.lengths();
  auto values = vectors_of(genome.controller);
  auto steps = vectors_of(genome.step_sizes);
  const double sd = p.controller.weight_init_sd;
  const double limit = p.controller.gene_limit;
  for (int v = 0; v < kControllerVectorCount; ++v) {
    values[v]->assign(lengths[v], 0.0);
    steps[v]->assign(lengths[v], sd);  // §8.2: every step size starts at weight_init_sd
    for (double& x : *values[v]) {
      if (v == kFreqVector) {
        x = rng.uniform(p.controller.freq_min, p.controller.freq_max);  // f ~ U(1, 5) [Hz]
      } else {
        x = std::clamp(sd * rng.normal(), -limit, limit);  // N(0, 3) clipped to +-5
      }
    }
  }
  genome.step_sizes.freq.assign(1, p.controller.freq_step_size_init);  // 0.2 [Hz]
}

Genome random_genome(const EvoParams& p, Rng& rng) {
  Genome g;
  g.cppn = random_cppn(p, rng);
  if (p.with_controller) random_controller(p, rng, g);
  return g;
}

// ---------------------------------------------------------------------------------------------
// Canonical encoding

namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw WireError("genome: " + message);
}

void require_finite(double v, const std::string& field) {
  require(std::isfinite(v), field + " is not finite");
}

}  // namespace

void check_controller_shape(const Genome& genome, const ControllerShape& shape) {
  const auto lengths = shape.lengths();
  const auto values = vectors_of(genome.controller);
  const auto steps = vectors_of(genome.step_sizes);
  for (int v = 0; v < kControllerVectorCount; ++v) {
    if (values[v]->size() != lengths[v] || steps[v]->size() != lengths[v])
      throw std::invalid_argument(
          std::string("controller vector ") + kControllerVectorNames[v] + " has " +
          std::to_string(values[v]->size()) + " values and " + std::to_string(steps[v]->size()) +
          " step sizes, expected " + std::to_string(lengths[v]) + " (n_in " +
          std::to_string(shape.inputs) + ", hidden " + std::to_string(shape.hidden) + ", outputs " +
          std::to_string(shape.outputs) + ")");
  }
}

void write_genome_payload(WireWriter& w, const Genome& genome) {
  const CppnGenome& c = genome.cppn;
  w.i32(c.num_inputs);
  w.i32(c.num_outputs);
  w.u64(c.nodes.size());
  for (const NodeGene& n : c.nodes) {
    w.i32(n.key);
    w.f64(n.bias);
    w.f64(n.response);
    w.u8(static_cast<std::uint8_t>(n.activation));
  }
  w.u64(c.connections.size());
  for (const ConnectionGene& e : c.connections) {
    w.i32(e.in);
    w.i32(e.out);
    w.f64(e.weight);
    w.boolean(e.enabled);
  }
  w.boolean(genome.has_controller());
  if (genome.has_controller()) {
    const auto values = vectors_of(genome.controller);
    const auto steps = vectors_of(genome.step_sizes);
    for (int v = 0; v < kControllerVectorCount; ++v) {
      w.f64_vector(*values[v]);
      w.f64_vector(*steps[v]);
    }
  }
}

Genome read_genome_payload(WireReader& r) {
  Genome g;
  CppnGenome& c = g.cppn;
  c.num_inputs = r.i32("num_inputs");
  c.num_outputs = r.i32("num_outputs");
  // Bounds guard against corrupt counts (a CPPN has a handful of inputs and outputs).
  require(c.num_inputs >= 1 && c.num_inputs <= 1024, "num_inputs out of range [1, 1024]");
  require(c.num_outputs >= 1 && c.num_outputs <= 1024, "num_outputs out of range [1, 1024]");
  const std::uint64_t node_count = r.u64("node count");
  // Every node takes 21 bytes: a count beyond the remaining bytes is corrupt (checked before
  // any allocation).
  require(node_count <= r.remaining() / 21, "node count exceeds the message length");
  c.nodes.reserve(node_count);
  for (std::uint64_t i = 0; i < node_count; ++i) {
    NodeGene n;
    n.key = r.i32("node key");
    n.bias = r.f64("node bias");
    n.response = r.f64("node response");
    const std::uint8_t act = r.u8("node activation");
    const std::string where = "node " + std::to_string(n.key);
    require(act <= static_cast<std::uint8_t>(Activation::tanh),
            where + ": unknown activation code " + std::to_string(act));
    n.activation = static_cast<Activation>(act);
    require(n.key >= 0, where + ": node keys must be >= 0");
    require(c.nodes.empty() || c.nodes.back().key < n.key,
            where + ": node keys must be strictly increasing");
    require_finite(n.bias, where + " bias");
    require_finite(n.response, where + " response");
    c.nodes.push_back(n);
  }
  for (int k = 0; k < c.num_outputs; ++k)
    require(c.find_node(k) != nullptr, "output node " + std::to_string(k) + " is missing");
  const std::uint64_t conn_count = r.u64("connection count");
  require(conn_count <= r.remaining() / 17, "connection count exceeds the message length");
  c.connections.reserve(conn_count);
  for (std::uint64_t i = 0; i < conn_count; ++i) {
    ConnectionGene e;
    e.in = r.i32("connection in");
    e.out = r.i32("connection out");
    e.weight = r.f64("connection weight");
    e.enabled = r.boolean("connection enabled");
    const std::string where =
        "connection (" + std::to_string(e.in) + ", " + std::to_string(e.out) + ")";
    require((e.in < 0 && e.in >= -c.num_inputs) || (e.in >= 0 && c.find_node(e.in)),
            where + ": unknown source node");
    require(e.out >= 0 && c.find_node(e.out), where + ": unknown or input target node");
    require_finite(e.weight, where + " weight");
    for (const ConnectionGene& o : c.connections)
      require(o.in != e.in || o.out != e.out, where + ": duplicate connection");
    c.connections.push_back(e);
  }
  if (r.boolean("has_controller")) {
    auto values = vectors_of(g.controller);
    auto steps = vectors_of(g.step_sizes);
    for (int v = 0; v < kControllerVectorCount; ++v) {
      *values[v] = r.f64_vector(kControllerVectorNames[v]);
      *steps[v] = r.f64_vector(kControllerVectorNames[v]);
      require(values[v]->size() == steps[v]->size(),
              std::string(kControllerVectorNames[v]) + ": values and step sizes differ in length");
      for (double x : *values[v]) require_finite(x, kControllerVectorNames[v]);
      for (double x : *steps[v]) require_finite(x, std::string(kControllerVectorNames[v]) + "_mut");
    }
    // Internal consistency: the lengths must be those of some shape (§4.4).
    ControllerShape shape;
    shape.hidden = static_cast<int>(g.controller.bias_hidden.size());
    shape.outputs = static_cast<int>(g.controller.bias_out.size());
    require(shape.hidden > 0, "controller bias_hidden is empty");
    require(g.controller.weights_hidden.size() % static_cast<std::size_t>(shape.hidden) == 0,
            "controller weights_hidden length is not a multiple of the hidden count");
    shape.inputs = static_cast<int>(g.controller.weights_hidden.size()) / shape.hidden;
    try {
      check_controller_shape(g, shape);
    } catch (const std::invalid_argument& e) {
      throw WireError(std::string("genome: ") + e.what());
    }
  }
  return g;
}

std::vector<std::uint8_t> encode_genome(const Genome& genome) {
  WireWriter w;
  write_genome_payload(w, genome);
  return frame_message(MessageKind::genome, w.data());
}

Genome decode_genome(std::span<const std::uint8_t> bytes) {
  WireReader r(unframe_message(bytes, MessageKind::genome), "genome");
  Genome g = read_genome_payload(r);
  r.finish();
  return g;
}

// ---------------------------------------------------------------------------------------------
// Robot file

ControllerSpec to_controller_spec(const Genome& genome, const Config& config, int task_inputs) {
  if (task_inputs < 0 || task_inputs > 1)
    throw std::invalid_argument("a robot file records 0 or 1 task inputs, the task has " +
                                std::to_string(task_inputs));
  const ControllerShape shape = controller_shape(config, task_inputs);
  check_controller_shape(genome, shape);
  ControllerSpec spec;
  spec.kind = "elman";
  spec.closed_loop = config.task.control == ControlLoop::closed;
  spec.directed = task_inputs == 1;
  spec.oscillator_inputs = config.controller.oscillator_inputs;
  spec.hidden = shape.hidden;
  spec.outputs = shape.outputs;
  spec.vectors = genome.controller;
  return spec;
}

RobotGenomeRecord to_genome_record(const Genome& genome, const Config& config) {
  RobotGenomeRecord rec;
  rec.nodes = cppn_node_records(genome.cppn);
  rec.connections = cppn_connection_records(genome.cppn);
  rec.controller_step_sizes = genome.step_sizes;
  rec.body_lattice.assign(config.body.lattice.begin(), config.body.lattice.end());
  rec.distance_input = config.body.distance_input;
  return rec;
}

Genome genome_from_robot(const RobotGenomeRecord& record, const ControllerSpec& controller) {
  Genome g;
  g.cppn = cppn_from_records(record.nodes, record.connections);
  g.controller = controller.vectors;
  g.step_sizes = record.controller_step_sizes;
  if (g.has_controller()) {
    ControllerShape shape;
    shape.inputs = controller.input_count();
    shape.hidden = controller.hidden;
    shape.outputs = controller.outputs;
    check_controller_shape(g, shape);
  }
  return g;
}

}  // namespace softevo::evo
