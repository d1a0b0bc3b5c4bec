// Stagnation, adjusted fitness, spawn allocation, per-species elitism and tournament selection
// (docs/model.md §8.5: neat-python 0.92 DefaultStagnation + DefaultReproduction with the
// thesis' MIPReproduction tournament).
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "common/rng.hpp"
#include "evo/genome.hpp"
#include "evo/innovation.hpp"
#include "evo/speciation.hpp"

namespace softevo::evo {

// One member of the population: what the MPI master and the archive see.
struct Individual {
  std::int64_t id = 0;
  std::int64_t parent1 = -1;  // -1: none (random genome / immigrant)
  std::int64_t parent2 = -1;
  std::int64_t species = 0;  // species id after the last speciation
  Genome genome;
};

// An evaluated member (fitness known).
struct ScoredIndividual {
  Individual individual;
  double fitness = 0.0;
  bool killed = false;
};

// Python 3 round() on a double: nearest integer, ties to even (round(2.5) == 2).
std::int64_t round_half_even(double v);

// neat-python 0.92 DefaultReproduction.compute_spawn (§8.5 step 3), operation for operation:
//   s = max(min_size, af / sum_af * pop_size)   (min_size if sum_af <= 0)
//   d = (s - previous) * 0.5; c = round(d); spawn = previous + c if c != 0, else previous +-1
//   by the sign of d; then spawn_i = max(min_size, round(spawn_i * (pop_size / sum spawn))).
std::vector<std::int64_t> compute_spawn(const std::vector<double>& adjusted_fitness,
                                        const std::vector<std::int64_t>& previous_sizes,
                                        std::int64_t pop_size, std::int64_t min_species_size);

// DefaultStagnation.update (§8.5 step 1): updates each species' fitness (max member fitness),
// fitness history and last_improved; returns the species indices sorted by ascending fitness
// (stable) with their stagnant flag. `fitness` maps member id -> fitness.
struct StagnationEntry {
  std::size_t species_index;
  bool stagnant;
};
std::vector<StagnationEntry> update_stagnation(
    std::vector<Species>& species, const std::unordered_map<std::int64_t, double>& fitness,
    std::int64_t generation, const NeatConfig& c);

// Tournament selection inside a species (§8.5 step 5): draw a candidate uniformly (with
// replacement), then size-1 more; a later one replaces the current winner only if its fitness is
// strictly greater. Returns an index into `fitnesses`; size 1 = uniform random choice.
std::size_t tournament(const std::vector<double>& fitnesses, std::int64_t size, Rng& rng);

// One reproduction step (§8.5). `species` (with members lists naming ids in `members`) becomes
// the remaining species in ascending-fitness order with empty member lists; returns the new
// population: per species the elites (unchanged, same id), then the children (new ids from
// `innovation`, parents A and B from two tournaments, crossover then mutation, or a mutated copy
// of A with probability mutate_only_probability). Empty when every species stagnated away.
std::vector<Individual> reproduce(std::vector<Species>& species,
                                  const std::vector<ScoredIndividual>& members,
                                  std::int64_t generation, const EvoParams& p,
                                  InnovationTracker& innovation, Rng& rng);

}  // namespace softevo::evo
