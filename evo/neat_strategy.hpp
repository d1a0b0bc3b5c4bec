// NEAT speciation (docs/model.md §8.1-§8.10) behind the search-strategy seam: the thesis
// system's population, unchanged (the same bits and the same checkpoint bytes as before the
// seam existed).
#pragma once

#include "evo/population.hpp"
#include "evo/search_strategy.hpp"

namespace softevo::evo {

class NeatStrategy final : public SearchStrategy {
 public:
  explicit NeatStrategy(Population population) : population_(std::move(population)) {}
  std::unique_ptr<SearchStrategy> clone() const override {
    return std::make_unique<NeatStrategy>(*this);
  }
  SearchKind kind() const override { return SearchKind::neat; }
  std::int64_t generation() const override { return population_.generation(); }
  const EvoParams& params() const override { return population_.params(); }
  const std::vector<Individual>& ask() const override { return population_.members(); }
  void adopt_controller(std::int64_t id, const Genome& learned) override {
    population_.adopt_controller(id, learned);
  }
  void tell(const std::vector<Evaluation>& results) override { population_.advance(results); }
  std::vector<std::uint8_t> serialize() const override { return population_.serialize(); }
  std::int64_t species_count() const override {
    return static_cast<std::int64_t>(population_.species_count());
  }
  const StrategyReport& report() const override { return report_; }
  const Population& population() const { return population_; }

 private:
  Population population_;
  StrategyReport report_;  // always empty: species are the archive's own columns
};

}  // namespace softevo::evo
