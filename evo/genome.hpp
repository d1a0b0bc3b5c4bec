// The robot genome: a CPPN (body, docs/model.md §6) plus the Elman controller sub-genome
// (§4.4: 9 named real vectors, each with a parallel vector of per-gene mutation step sizes).
//
// The same type carries plain NEAT genomes (XOR benchmark): their controller vectors are all
// empty (`has_controller() == false`) and every controller operator is then a no-op.
//
// EvoParams collects everything the operators read (neat-python 0.92 names, §8.8), resolved once
// from a Config (or built by hand for a non-robot experiment).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/rng.hpp"
#include "common/robot.hpp"
#include "evo/cppn.hpp"

namespace softevo {
class WireWriter;
class WireReader;
}  // namespace softevo

namespace softevo::evo {

inline constexpr int kControllerVectorCount = 9;

// Dimensions of the controller sub-genome (§4.1): vector lengths follow from these (§4.4).
struct ControllerShape {
  int inputs = 2;    // n_in
  int hidden = 4;    // H (= context units)
  int outputs = 20;  // n_out = 2 x max chambers
  // Expected lengths of the 9 vectors in canonical order (§4.4).
  std::array<std::size_t, kControllerVectorCount> lengths() const;
  std::size_t gene_count() const;  // 4 n_in + 133 for H = 4, n_out = 20
};

struct Genome {
  CppnGenome cppn;
  ControllerVectors controller;  // gene values; freq[0] in [Hz]
  ControllerVectors step_sizes;  // per-gene self-adaptive step sizes (same layout)
  bool has_controller() const { return !controller.freq.empty(); }
};

// The 9 vectors in canonical order (§4.4: weights_hidden, bias_hidden, weights_out, bias_out,
// weights_recurrent, weights_recurrent_self, weights_context, bias_context, freq).
std::array<std::vector<double>*, kControllerVectorCount> vectors_of(ControllerVectors& v);
std::array<const std::vector<double>*, kControllerVectorCount> vectors_of(
    const ControllerVectors& v);
extern const std::array<const char*, kControllerVectorCount> kControllerVectorNames;
// Canonical index of the frequency vector.
inline constexpr int kFreqVector = 8;

// Everything the NEAT operators, speciation and reproduction read.
struct EvoParams {
  NeatConfig neat;  // rates, powers, limits, thresholds (§8.8)
  int num_inputs = 4;
  int num_outputs = 4;
  bool feed_forward = true;                             // add-connection refuses cycles (§8.7)
  std::vector<Activation> activation_options;           // resolved neat.activation_options
  bool activation_random = true;                        // activation_default = "random"
  Activation activation_default = Activation::sigmoid;  // when not random
  // Controller sub-genome; with_controller = false for plain NEAT experiments.
  bool with_controller = true;
  ControllerShape shape;
  ControllerConfig controller;
  // 1pointpl / random / 1point (§8.6), the config's choice.
  using CrossoverMethod = softevo::CrossoverMethod;
  CrossoverMethod crossover_method = CrossoverMethod::one_point_per_layer;
  // MIPReproduction.mutateonlyprobability (0.0 in the thesis, §8.5 step 5): probability that a
  // child is a mutated copy of parent A instead of crossover(A, B) + mutation.
  double mutate_only_probability = 0.0;
  // Genome distance of speciation: neat-python 0.92 (thesis) or the NEAT paper's (XOR).
  bool paper_distance = false;
  // Attempts of one add-connection mutation to find a new, legal connection: 1 in neat-python
  // (a failed draw is simply no mutation); NEAT 1.2.1 (the paper's code) tries 20 times.
  int add_connection_attempts = 1;
};

// Controller dimensions of a run (§4.1): n_in = controller_input_count(task_inputs, closed
// loop), H = controller.hidden, n_out = 2 x body.max_chambers (inlet + outlet valve per
// chamber). `task_inputs`: the task's controller inputs (tasks::Task::controller_inputs(); evo
// knows no task).
ControllerShape controller_shape(const Config& config, int task_inputs);
// Resolves a Config into operator parameters; throws std::invalid_argument naming the key for
// an unknown activation option.
EvoParams evo_params(const Config& config, int task_inputs);

// --- Initialisation (§8.2) -----------------------------------------------------------------
// A neat-python 0.92 gene value draw: clamp(N(mean, stdev), min, max) (gaussian init_type).
double init_clamped_gaussian(double mean, double stdev, double lo, double hi, Rng& rng);
// A new node gene with `key`: bias and response drawn, activation default or uniform choice.
NodeGene new_node_gene(int key, const EvoParams& p, Rng& rng);
// CPPN with the output nodes 0..n-1 (in key order) and full input->output connectivity
// (initial_connection = full, no hidden nodes): connection order input -1, -2, ... outer,
// outputs inner, as neat-python's compute_full_connections.
CppnGenome random_cppn(const EvoParams& p, Rng& rng);
// Controller genes (§8.2): f ~ U(freq_min, freq_max), all others N(0, weight_init_sd) clipped to
// +-gene_limit, drawn in canonical vector order; step sizes weight_init_sd, frequency step size
// freq_step_size_init (not random).
// With controller.init = "oscillator" this is oscillator_controller() instead.
void random_controller(const EvoParams& p, Rng& rng, Genome& genome);
// §4.8: the hand-made pressure-driven oscillator of every chamber slot (p.shape.outputs / 2),
// chamber q on hidden unit q mod H, each gene then perturbed by init_perturbation_sd N(0, 1)
// (clipped to +-gene_limit) in canonical order, frequency U(freq_min, freq_max); step sizes
// init_perturbation_sd, the frequency's freq_step_size_init. Needs pressure sensors (closed
// loop); throws std::invalid_argument otherwise.
void oscillator_controller(const EvoParams& p, Rng& rng, Genome& genome);
// Both parts (CPPN first, then the controller when p.with_controller).
Genome random_genome(const EvoParams& p, Rng& rng);

// --- Canonical binary encoding (wire and archive) -----------------------------------------
// A framed message (common/wire.hpp, kind genome). Payload, little-endian, one field at a time:
//   i32 num_inputs, i32 num_outputs,
//   u64 node count, per node: i32 key, f64 bias, f64 response, u8 activation,
//   u64 connection count, per connection: i32 in, i32 out, f64 weight, u8 enabled,
//   u8 has_controller, then (if 1) per vector in canonical order: f64_vector values,
//   f64_vector step sizes.
// Equal genomes give equal bytes, so the bytes are the genome's identity.
std::vector<std::uint8_t> encode_genome(const Genome& genome);
// Throws WireError naming the field on truncated, oversized or inconsistent input (unsorted or
// duplicate node keys, missing outputs, unknown connection endpoints, duplicate connections,
// unknown activation, non-finite numbers, controller vectors of inconsistent lengths).
Genome decode_genome(std::span<const std::uint8_t> bytes);
// Payload-level helpers (no frame), used when a genome is embedded in a larger message.
void write_genome_payload(WireWriter& w, const Genome& genome);
Genome read_genome_payload(WireReader& r);
// Throws std::invalid_argument when the controller vectors do not match `shape`.
void check_controller_shape(const Genome& genome, const ControllerShape& shape);

// --- Robot file -------------------------------------------------------------------------------
// Controller part of the robot file (kind elman, loop flag and sizes from the config, `directed`
// for one task input).
ControllerSpec to_controller_spec(const Genome& genome, const Config& config, int task_inputs);
// "genome" section: CPPN records, step sizes, the lattice and distance input of the config.
RobotGenomeRecord to_genome_record(const Genome& genome, const Config& config);
// Inverse: a Genome from a robot file's records (throws std::invalid_argument on bad records).
Genome genome_from_robot(const RobotGenomeRecord& record, const ControllerSpec& controller);

}  // namespace softevo::evo
