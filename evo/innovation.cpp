#include "evo/innovation.hpp"

#include <stdexcept>

namespace softevo::evo {

void InnovationTracker::restore(int next_node_key, std::int64_t next_genome_id,
                                std::int64_t next_species_id) {
  if (next_node_key < 0 || next_genome_id < 1 || next_species_id < 1)
    throw std::invalid_argument(
        "innovation counters: next node key must be >= 0, next genome and species ids >= 1");
  next_node_key_ = next_node_key;
  next_genome_id_ = next_genome_id;
  next_species_id_ = next_species_id;
}

}  // namespace softevo::evo
