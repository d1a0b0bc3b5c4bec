// The NEAT population of a run and its whole state (docs/model.md §8.1, docs/model.md §8.10).
//
// Generation loop as the thesis system ran it (§8.1), split at the evaluation:
//   create():  random genomes, speciate (generation 0), then step 2 (random immigrants replace
//              invalid or non-actuatable bodies, re-speciate)    -> members() to evaluate
//   advance(): step 4 singleton rescue, step 5 best tracking, step 6 reproduction (stagnation,
//              spawn, elitism, tournament, crossover, mutation), step 7 speciation, g += 1,
//              then step 2 for the new generation                -> members() to evaluate
// All randomness comes from the population's own Rng, whose state is part of serialize(), as are
// the species with their history, the node-key / genome-id / species-id counters and the
// generation: continuing from a deserialized copy gives exactly the same future.
//
// The robot run uses develop_body(...).valid && actuatable as viability predicate; other
// experiments (XOR) build the population from their own EvoParams and predicate.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "common/config.hpp"
#include "common/rng.hpp"
#include "evo/genome.hpp"
#include "evo/innovation.hpp"
#include "evo/reproduction.hpp"
#include "evo/speciation.hpp"

namespace softevo::evo {

// Result of evaluating one member.
struct Evaluation {
  std::int64_t id;
  double fitness;  // used for selection as is (a killed robot is expected to score 0)
  bool killed;
};
// `results` by genome id; std::invalid_argument for a non-finite fitness or an id given twice.
// Every strategy checks a generation's evaluations through it.
std::unordered_map<std::int64_t, const Evaluation*> evaluations_by_id(
    const std::vector<Evaluation>& results);

// Does a genome give a usable individual (§8.3)? Empty = every genome is viable.
using Viability = std::function<bool(const Genome&)>;
// develop_body(genome.cppn, body).valid && .actuatable (§8.1 step 2).
Viability robot_viability(const BodyConfig& body);

// Lamarckian inheritance for any strategy's members (docs/model.md §8.11): member `id` takes the
// controller values and step sizes of `learned`. Throws std::invalid_argument for an unknown
// id or a learned genome of another body or shape.
void adopt_learned_controller(std::vector<Individual>& members, std::int64_t id,
                              const Genome& learned, const ControllerShape& shape);

class Population {
 public:
  struct Best {
    std::int64_t id = 0;
    std::int64_t generation = 0;  // generation in which it was evaluated
    double fitness = 0.0;
    Genome genome;
  };

  // Robot run: EvoParams and viability from `config`, Rng seeded with `seed`.
  // `task_inputs`: the task's controller inputs (evo_params).
  static Population create(const Config& config, int task_inputs, std::uint64_t seed);
  // Any NEAT experiment.
  static Population create(const EvoParams& params, Viability viable, std::uint64_t seed);

  // The members to evaluate in generation().
  const std::vector<Individual>& members() const { return members_; }
  std::int64_t generation() const { return generation_; }
  // Results by id (any order). Throws std::invalid_argument on a missing, unknown or duplicate
  // id or a non-finite fitness and std::runtime_error if every species went extinct; the
  // population is unchanged when it throws.
  void advance(const std::vector<Evaluation>& results);
  // Lamarckian inheritance of controller learning (docs/model.md §8.11): member `id` takes the
  // controller values and step sizes of `learned` (same CPPN) before advance() reproduces.
  // Throws std::invalid_argument for an unknown id or a learned genome of another body or shape.
  void adopt_controller(std::int64_t id, const Genome& learned);

  // Whole state as a framed message (kind population); see population.cpp for the layout.
  std::vector<std::uint8_t> serialize() const;
  // Throws WireError on malformed bytes, std::invalid_argument when the state does not fit the
  // configuration (CPPN or controller dimensions).
  static Population deserialize(std::span<const std::uint8_t> bytes, const Config& config,
                                int task_inputs);
  static Population deserialize(std::span<const std::uint8_t> bytes, const EvoParams& params,
                                Viability viable);

  // Read access for reporters and the archive.
  const std::vector<Species>& species() const { return species_; }  // current speciation
  std::size_t species_count() const { return species_.size(); }
  const EvoParams& params() const { return params_; }
  const InnovationTracker& counters() const { return innovation_; }
  const Rng& rng() const { return rng_; }
  const std::optional<Best>& best_ever() const { return best_ever_; }
  // The previous generation as evaluated (singleton-rescue clones appended, with the fitness
  // copied from their original); empty before the first advance() and after deserialize().
  const std::vector<ScoredIndividual>& last_evaluated() const { return last_evaluated_; }
  // Random immigrants created for the current generation (viable or not); transient like
  // last_evaluated().
  std::int64_t immigrants_created() const { return immigrants_created_; }

 private:
  Population(const EvoParams& params, Viability viable, std::uint64_t seed);
  void apply_immigrants();  // §8.1 step 2 + re-speciation
  void speciate_members();  // species of members_ at generation_
  void advance_impl(const std::vector<Evaluation>& results);

  EvoParams params_;
  Viability viable_;
  Rng rng_;
  InnovationTracker innovation_;
  std::int64_t generation_ = 0;
  std::vector<Individual> members_;
  std::vector<Species> species_;
  std::optional<Best> best_ever_;
  std::vector<ScoredIndividual> last_evaluated_;
  std::int64_t immigrants_created_ = 0;
};

}  // namespace softevo::evo
