// MAP-Elites (docs/model.md §8.12.2, thesis 5.3.4): the best robot of every kind instead of one
// population. A grid over 1-3 descriptors (common/map_grid.hpp); generation 0 is a batch of
// neat.pop_size random viable genomes, every later generation a batch of neat.pop_size
// offspring of uniformly drawn elites (NEAT's mutation, crossover with
// map_elites.crossover_probability). An evaluated robot whose status is ok enters its cell when
// the cell is empty or its fitness is strictly greater than the elite's; ties keep the
// incumbent, and the batch is inserted in ascending id order, so the map is a function of the
// results alone.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/map_grid.hpp"
#include "evo/development.hpp"
#include "evo/search_strategy.hpp"

namespace softevo::evo {

struct Elite {
  std::int64_t cell = 0;
  Individual individual;
  double fitness = 0.0;
  std::vector<double> descriptors;  // one per axis of the grid, in its unit (§8.12.2)
  std::int64_t generation = 0;      // generation in which it was evaluated
};

// Inserts `candidate` into `map` (ascending cell, one elite per cell) when its cell is empty or
// its fitness is strictly greater than the elite's (a tie keeps the incumbent). Returns whether
// it was inserted.
bool insert_elite(std::vector<Elite>& map, Elite candidate);

// The body descriptors of §8.12.2 of a developed body: every descriptor but mean_speed, in the
// order of map_descriptor_names() (mean_speed is NaN here). `lattice_cells`: cells of the query
// lattice (body.lattice); `voxel_size` [m].
std::vector<double> body_descriptor_values(const DevelopedBody& body, std::int64_t lattice_cells,
                                           double voxel_size);

class MapElites final : public StrategyBase<MapElites> {
 public:
  static MapElites create(const Config& config, int task_inputs, std::uint64_t seed);
  static MapElites deserialize(std::span<const std::uint8_t> bytes, const Config& config,
                               int task_inputs);

  SearchKind kind() const override { return SearchKind::map_elites; }
  std::vector<std::uint8_t> serialize() const override;

  const MapGrid& grid() const { return grid_; }
  const std::vector<Elite>& elites() const { return elites_; }  // ascending cell
  // The grid's descriptors of `genome` evaluated as `evaluation`.
  std::vector<double> descriptors(const Genome& genome, const Evaluation& evaluation) const;

 private:
  friend StrategyBase<MapElites>;
  MapElites(const Config& config, int task_inputs, std::uint64_t seed)
      : StrategyBase(config, task_inputs, seed), grid_(map_grid(config)) {}
  void tell_impl(const std::vector<Evaluation>& results);
  void next_batch();

  MapGrid grid_;
  std::vector<Elite> elites_;
};

}  // namespace softevo::evo
