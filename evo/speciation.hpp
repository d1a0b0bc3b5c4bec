// Genome distance and speciation (docs/model.md §8.4: neat-python 0.92 DefaultSpeciesSet).
#pragma once

#include <cstdint>
#include <vector>

#include "common/config.hpp"
#include "evo/cppn.hpp"
#include "evo/innovation.hpp"

namespace softevo::evo {

// neat-python 0.92 DefaultGenome.distance (CPPN only; the controller is ignored):
//   nodes:       (sum_homologous d_n + c_disjoint #disjoint) / max(#nodes_a, #nodes_b),
//                d_n = c_weight (|dbias| + |dresponse| + [activation differs]);
//   connections: (sum_homologous d_c + c_disjoint #disjoint) / max(#conns_a, #conns_b),
//                d_c = c_weight (|dweight| + [enabled differs]);
// each part 0 when both genomes have none; genes match by node key / (in, out). Homologous terms
// are summed in `a`'s gene order.
//
// DistanceMode::neat_paper is Stanley & Miikkulainen (2002) eq. 1 instead, for the XOR benchmark:
//   delta = c_disjoint (#disjoint + #excess connection genes) / N + c_weight * mean |dw|,
// N = connection genes of the larger genome, 1 below 20 genes; mean |dw| over the matching
// connections and the matching node biases (the paper's bias is a weight from a bias input).
enum class DistanceMode : std::uint8_t { neat_python, neat_paper };
double genome_distance(const CppnGenome& a, const CppnGenome& b, const NeatConfig& c,
                       DistanceMode mode = DistanceMode::neat_python);

struct Species {
  std::int64_t id = 0;
  std::int64_t created = 0;        // generation of creation
  std::int64_t last_improved = 0;  // generation of the last rise of the species fitness (§8.5)
  std::vector<double> fitness_history;  // species fitness (max member fitness) per generation
  CppnGenome representative;            // genome the next speciation measures distances to
  std::vector<std::int64_t> members;    // genome ids, in membership order (rep first)
  // Reporting only (set by reproduction, not needed to continue): last species fitness and
  // adjusted fitness; NaN when not computed yet.
  double fitness = 0.0;
  double adjusted_fitness = 0.0;
};

// One population member as speciation sees it.
struct SpeciationInput {
  std::int64_t id;
  const CppnGenome* cppn;
};

// DefaultSpeciesSet.speciate (§8.4). `species` in species-dict order (ascending creation), its
// representatives from the previous speciation. For each existing species, the not yet assigned
// genome closest to the old representative (no threshold; first wins ties) becomes the new
// representative and first member. (neat-python would crash when genomes run out before
// species do; here such a species is dropped.) Then each remaining genome, in ascending id order
// (neat-python pops a Python set of int keys, which is close to ascending), joins the species
// whose new representative is closest if that distance < compatibility_threshold, else founds a
// new species (id from `innovation`, created = last_improved = generation). Species keep their
// history; the members lists are rebuilt. Returns, per input (same order), its species id.
std::vector<std::int64_t> speciate(std::vector<Species>& species,
                                   const std::vector<SpeciationInput>& population,
                                   std::int64_t generation, const NeatConfig& c,
                                   InnovationTracker& innovation,
                                   DistanceMode mode = DistanceMode::neat_python);

}  // namespace softevo::evo
