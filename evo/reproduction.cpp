#include "evo/reproduction.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <stdexcept>
#include <string>

#include "evo/crossover.hpp"
#include "evo/mutation.hpp"

namespace softevo::evo {

std::int64_t round_half_even(double v) {
  const double f = std::floor(v);
  const double diff = v - f;  // exact for |v| < 2^52
  double r;
  if (diff < 0.5) {
    r = f;
  } else if (diff > 0.5) {
    r = f + 1.0;
  } else {
    r = std::fmod(f, 2.0) == 0.0 ? f : f + 1.0;  // tie: the even neighbour
  }
  return static_cast<std::int64_t>(r);
}

std::vector<std::int64_t> compute_spawn(const std::vector<double>& adjusted_fitness,
                                        const std::vector<std::int64_t>& previous_sizes,
                                        std::int64_t pop_size, std::int64_t min_species_size) {
  if (adjusted_fitness.size() != previous_sizes.size())
    throw std::invalid_argument("compute_spawn: adjusted fitness and sizes differ in length");
  double af_sum = 0.0;
  for (double af : adjusted_fitness) af_sum += af;  // Python sum(): left to right
  const double pop = static_cast<double>(pop_size);
  const double min_size = static_cast<double>(min_species_size);
  std::vector<std::int64_t> spawn_amounts;
  spawn_amounts.reserve(adjusted_fitness.size());
  for (std::size_t i = 0; i < adjusted_fitness.size(); ++i) {
    const double ps = static_cast<double>(previous_sizes[i]);
    const double s =
        af_sum > 0.0 ? std::max(min_size, adjusted_fitness[i] / af_sum * pop) : min_size;
    const double d = (s - ps) * 0.5;
    const std::int64_t c = round_half_even(d);
    std::int64_t spawn = previous_sizes[i];
    if (c != 0)
      spawn += c;
    else if (d > 0.0)
      spawn += 1;
    else if (d < 0.0)
      spawn -= 1;
    spawn_amounts.push_back(spawn);
  }
  std::int64_t total_spawn = 0;
  for (std::int64_t n : spawn_amounts) total_spawn += n;
  if (total_spawn == 0) throw std::runtime_error("compute_spawn: total spawn is zero");
  const double norm = pop / static_cast<double>(total_spawn);  // Python true division
  for (std::int64_t& n : spawn_amounts)
    n = std::max(min_species_size, round_half_even(static_cast<double>(n) * norm));
  return spawn_amounts;
}

std::vector<StagnationEntry> update_stagnation(
    std::vector<Species>& species, const std::unordered_map<std::int64_t, double>& fitness,
    std::int64_t generation, const NeatConfig& c) {
  for (Species& s : species) {
    double prev = -DBL_MAX;  // -sys.float_info.max for an empty history
    for (double h : s.fitness_history) prev = std::max(prev, h);
    if (s.members.empty()) throw std::logic_error("stagnation: species without members");
    double f = -DBL_MAX;  // species_fitness_func = max
    for (std::int64_t id : s.members) {
      auto it = fitness.find(id);
      if (it == fitness.end())
        throw std::logic_error("stagnation: no fitness for member " + std::to_string(id));
      f = std::max(f, it->second);
    }
    s.fitness = f;
    s.fitness_history.push_back(f);
    s.adjusted_fitness = std::nan("");
    if (f > prev) s.last_improved = generation;
  }
  std::vector<std::size_t> order(species.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return species[a].fitness < species[b].fitness;
  });
  std::vector<StagnationEntry> result;
  std::int64_t num_non_stagnant = static_cast<std::int64_t>(order.size());
  const std::int64_t n = static_cast<std::int64_t>(order.size());
  for (std::int64_t idx = 0; idx < n; ++idx) {
    const Species& s = species[order[idx]];
    const std::int64_t stagnant_time = generation - s.last_improved;
    bool stagnant = false;
    // Never mark more species stagnant than would leave fewer than species_elitism.
    if (num_non_stagnant > c.species_elitism) stagnant = stagnant_time >= c.max_stagnation;
    // The species_elitism best species (the end of the ascending order) are protected.
    if (n - idx <= c.species_elitism) stagnant = false;
    if (stagnant) --num_non_stagnant;
    result.push_back(StagnationEntry{order[idx], stagnant});
  }
  return result;
}

std::size_t tournament(const std::vector<double>& fitnesses, std::int64_t size, Rng& rng) {
  if (fitnesses.empty()) throw std::invalid_argument("tournament: no candidates");
  std::size_t winner = rng.uniform_int(fitnesses.size());
  for (std::int64_t k = 1; k < size; ++k) {
    const std::size_t other = rng.uniform_int(fitnesses.size());
    if (fitnesses[other] > fitnesses[winner]) winner = other;
  }
  return winner;
}

std::vector<Individual> reproduce(std::vector<Species>& species,
                                  const std::vector<ScoredIndividual>& members,
                                  std::int64_t generation, const EvoParams& p,
                                  InnovationTracker& innovation, Rng& rng) {
  const NeatConfig& c = p.neat;
  std::unordered_map<std::int64_t, const ScoredIndividual*> by_id;
  std::unordered_map<std::int64_t, double> fitness;
  for (const ScoredIndividual& m : members) {
    by_id[m.individual.id] = &m;
    fitness[m.individual.id] = m.fitness;
  }
  // 1. Stagnation; the remaining species keep the ascending-fitness order from here on.
  std::vector<Species> remaining;
  std::vector<double> all_fitnesses;
  for (const StagnationEntry& e : update_stagnation(species, fitness, generation, c)) {
    if (e.stagnant) continue;
    for (std::int64_t id : species[e.species_index].members) all_fitnesses.push_back(fitness[id]);
    remaining.push_back(std::move(species[e.species_index]));
  }
  species = std::move(remaining);
  if (species.empty()) return {};
  // 2. Adjusted fitness = (mean member fitness - min) / max(1, max - min).
  const double min_fitness = *std::min_element(all_fitnesses.begin(), all_fitnesses.end());
  const double max_fitness = *std::max_element(all_fitnesses.begin(), all_fitnesses.end());
  const double fitness_range = std::max(1.0, max_fitness - min_fitness);
  std::vector<double> adjusted;
  std::vector<std::int64_t> previous_sizes;
  for (Species& s : species) {
    double sum = 0.0;
    for (std::int64_t id : s.members) sum += fitness[id];
    const double msf = sum / static_cast<double>(s.members.size());
    s.adjusted_fitness = (msf - min_fitness) / fitness_range;
    adjusted.push_back(s.adjusted_fitness);
    previous_sizes.push_back(static_cast<std::int64_t>(s.members.size()));
  }
  // 3. Spawn amounts; neat 0.92 raises min_species_size to at least elitism.
  const std::int64_t min_species_size = std::max(c.min_species_size, c.elitism);
  const std::vector<std::int64_t> spawn_amounts =
      compute_spawn(adjusted, previous_sizes, c.pop_size, min_species_size);
  // 4.-5. Elites and children per species.
  std::vector<Individual> next;
  for (std::size_t k = 0; k < species.size(); ++k) {
    Species& s = species[k];
    std::int64_t spawn = std::max(spawn_amounts[k], c.elitism);
    std::vector<const ScoredIndividual*> old_members;
    for (std::int64_t id : s.members) old_members.push_back(by_id.at(id));
    s.members.clear();
    // Descending fitness; Python's sort(reverse=True) is stable, ties keep membership order.
    std::stable_sort(old_members.begin(), old_members.end(),
                     [](const ScoredIndividual* a, const ScoredIndividual* b) {
                       return a->fitness > b->fitness;
                     });
    const std::size_t elites = std::min(
        old_members.size(), static_cast<std::size_t>(std::max<std::int64_t>(c.elitism, 0)));
    for (std::size_t i = 0; i < elites; ++i) {
      next.push_back(old_members[i]->individual);  // same id, re-evaluated next generation
      --spawn;
    }
    if (spawn <= 0) continue;
    std::size_t cutoff = static_cast<std::size_t>(
        std::ceil(c.survival_threshold * static_cast<double>(old_members.size())));
    cutoff = std::min(std::max<std::size_t>(cutoff, 2), old_members.size());
    old_members.resize(cutoff);
    std::vector<double> parent_fitness;
    for (const ScoredIndividual* m : old_members) parent_fitness.push_back(m->fitness);
    while (spawn > 0) {
      --spawn;
      const ScoredIndividual& a = *old_members[tournament(parent_fitness, c.tournament_size, rng)];
      const ScoredIndividual& b = *old_members[tournament(parent_fitness, c.tournament_size, rng)];
      Individual child;
      child.id = innovation.new_genome_id();
      child.parent1 = a.individual.id;
      if (rng.uniform() < p.mutate_only_probability) {
        child.genome = a.individual.genome;  // mutation only
      } else {
        child.parent2 = b.individual.id;
        child.genome =
            crossover(a.individual.genome, a.fitness, b.individual.genome, b.fitness, p, rng);
      }
      mutate(child.genome, p, innovation, rng);
      next.push_back(std::move(child));
    }
  }
  return next;
}

}  // namespace softevo::evo
