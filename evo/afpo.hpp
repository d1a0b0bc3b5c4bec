// Age-fitness Pareto optimisation (docs/model.md §8.12.3, thesis 5.3.5; Schmidt & Lipson's
// AFPO as evosoro runs it, and Cheney et al.'s morphological innovation protection): selection
// keeps the robots no other robot beats in both fitness (higher) and age (lower), so a young
// lineage is not lost to an old one that had longer to improve. The population is neat.pop_size
// survivors; each generation adds neat.pop_size - 1 mutated offspring of uniformly drawn
// survivors and one random newcomer (age 0), and selection brings it back to neat.pop_size.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "evo/search_strategy.hpp"

namespace softevo::evo {

// Pareto rank of each point (0 = no point dominates it, 1 = dominated only by rank-0 points,
// ...). Point i dominates j when fitness_i >= fitness_j and age_i <= age_j with one of them
// strict; equal points do not dominate each other.
std::vector<std::int64_t> pareto_ranks(const std::vector<double>& fitness,
                                       const std::vector<std::int64_t>& age);

// The `count` survivors (indices, ascending) among the points: by Pareto rank, within a rank by
// fitness (higher first), then age (younger first), then id (lower first).
std::vector<std::size_t> afpo_survivors(const std::vector<double>& fitness,
                                        const std::vector<std::int64_t>& age,
                                        const std::vector<std::int64_t>& id, std::size_t count);

// The age of a new offspring (§8.12.3): `parent_age` (the parent's age after its survival
// counted, i.e. already one generation older), or 0 under afpo.age = "body" when the mutation
// changed the developed body.
std::int64_t offspring_age(AfpoAge rule, std::int64_t parent_age, bool body_changed);

class Afpo final : public StrategyBase<Afpo> {
 public:
  static Afpo create(const Config& config, int task_inputs, std::uint64_t seed);
  static Afpo deserialize(std::span<const std::uint8_t> bytes, const Config& config,
                          int task_inputs);

  SearchKind kind() const override { return SearchKind::afpo; }
  std::vector<std::uint8_t> serialize() const override;

  // Age of each member, in members() order.
  const std::vector<std::int64_t>& ages() const { return ages_; }

 private:
  friend StrategyBase<Afpo>;
  Afpo(const Config& config, int task_inputs, std::uint64_t seed)
      : StrategyBase(config, task_inputs, seed) {}
  void tell_impl(const std::vector<Evaluation>& results);
  bool body_changed(const Genome& parent, const Genome& child) const;

  std::vector<std::int64_t> ages_;
};

}  // namespace softevo::evo
