// Global counters of a NEAT run: node keys, genome ids and species ids.
//
// neat-python 0.92 hands out hidden-node keys from one global counter (DefaultGenomeConfig
// .get_new_node_key, started at max(output keys) + 1): every add-node mutation gets a fresh key,
// so two genomes that split the same connection independently get different node keys (there is
// no per-generation innovation matching as in the NEAT paper). Genome ids come from
// DefaultReproduction.genome_indexer and species ids from DefaultSpeciesSet.indexer; both start
// at 1. Unlike the thesis system (§8.10) nothing here ever restarts: the counters are part
// of the population state and are checkpointed with it.
#pragma once

#include <cstdint>

namespace softevo::evo {

class InnovationTracker {
 public:
  // `num_outputs` output nodes have keys 0..num_outputs-1; hidden keys start right after.
  explicit InnovationTracker(int num_outputs = 4) : next_node_key_(num_outputs) {}

  int new_node_key() { return next_node_key_++; }
  std::int64_t new_genome_id() { return next_genome_id_++; }
  std::int64_t new_species_id() { return next_species_id_++; }

  // Counter values (the next key/id to hand out), for checkpoints.
  int next_node_key() const { return next_node_key_; }
  std::int64_t next_genome_id() const { return next_genome_id_; }
  std::int64_t next_species_id() const { return next_species_id_; }
  // Restore from a checkpoint; throws std::invalid_argument on non-positive / negative values.
  void restore(int next_node_key, std::int64_t next_genome_id, std::int64_t next_species_id);

 private:
  int next_node_key_;
  std::int64_t next_genome_id_ = 1;
  std::int64_t next_species_id_ = 1;
};

}  // namespace softevo::evo
