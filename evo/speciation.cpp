#include "evo/speciation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

namespace softevo::evo {

namespace {

double node_gene_distance(const NodeGene& a, const NodeGene& b, const NeatConfig& c) {
  double d = std::fabs(a.bias - b.bias) + std::fabs(a.response - b.response);
  if (a.activation != b.activation) d += 1.0;
  // Aggregation is always "sum": never differs.
  return d * c.compatibility_weight_coefficient;
}

double connection_gene_distance(const ConnectionGene& a, const ConnectionGene& b,
                                const NeatConfig& c) {
  double d = std::fabs(a.weight - b.weight);
  if (a.enabled != b.enabled) d += 1.0;
  return d * c.compatibility_weight_coefficient;
}

const ConnectionGene* find_connection(const CppnGenome& g, int in, int out) {
  for (const ConnectionGene& c : g.connections)
    if (c.in == in && c.out == out) return &c;
  return nullptr;
}

}  // namespace

namespace {

double paper_distance(const CppnGenome& a, const CppnGenome& b, const NeatConfig& c) {
  int disjoint = 0;
  int matching = 0;
  double weight_diff = 0.0;
  for (const ConnectionGene& c2 : b.connections)
    if (find_connection(a, c2.in, c2.out) == nullptr) ++disjoint;
  for (const ConnectionGene& c1 : a.connections) {
    const ConnectionGene* c2 = find_connection(b, c1.in, c1.out);
    if (c2 == nullptr) {
      ++disjoint;
    } else {
      ++matching;
      weight_diff += std::fabs(c1.weight - c2->weight);
    }
  }
  for (const NodeGene& n1 : a.nodes) {
    const NodeGene* n2 = b.find_node(n1.key);
    if (n2 != nullptr) {
      ++matching;
      weight_diff += std::fabs(n1.bias - n2->bias);
    }
  }
  const std::size_t genes = std::max(a.connections.size(), b.connections.size());
  const double n = genes < 20 ? 1.0 : static_cast<double>(genes);
  const double mean_w = matching > 0 ? weight_diff / matching : 0.0;
  return c.compatibility_disjoint_coefficient * disjoint / n +
         c.compatibility_weight_coefficient * mean_w;
}

}  // namespace

double genome_distance(const CppnGenome& a, const CppnGenome& b, const NeatConfig& c,
                       DistanceMode mode) {
  if (mode == DistanceMode::neat_paper) return paper_distance(a, b, c);
  double node_distance = 0.0;
  if (!a.nodes.empty() || !b.nodes.empty()) {
    int disjoint = 0;
    for (const NodeGene& n2 : b.nodes)
      if (a.find_node(n2.key) == nullptr) ++disjoint;
    for (const NodeGene& n1 : a.nodes) {
      const NodeGene* n2 = b.find_node(n1.key);
      if (n2 == nullptr)
        ++disjoint;
      else
        node_distance += node_gene_distance(n1, *n2, c);
    }
    const double max_nodes = static_cast<double>(std::max(a.nodes.size(), b.nodes.size()));
    node_distance = (node_distance + c.compatibility_disjoint_coefficient * disjoint) / max_nodes;
  }
  double connection_distance = 0.0;
  if (!a.connections.empty() || !b.connections.empty()) {
    int disjoint = 0;
    for (const ConnectionGene& c2 : b.connections)
      if (find_connection(a, c2.in, c2.out) == nullptr) ++disjoint;
    for (const ConnectionGene& c1 : a.connections) {
      const ConnectionGene* c2 = find_connection(b, c1.in, c1.out);
      if (c2 == nullptr)
        ++disjoint;
      else
        connection_distance += connection_gene_distance(c1, *c2, c);
    }
    const double max_conns =
        static_cast<double>(std::max(a.connections.size(), b.connections.size()));
    connection_distance =
        (connection_distance + c.compatibility_disjoint_coefficient * disjoint) / max_conns;
  }
  return node_distance + connection_distance;
}

std::vector<std::int64_t> speciate(std::vector<Species>& species,
                                   const std::vector<SpeciationInput>& population,
                                   std::int64_t generation, const NeatConfig& c,
                                   InnovationTracker& innovation, DistanceMode mode) {
  // Index of each genome id in `population`; the std::set iterates in ascending id order.
  std::map<std::int64_t, std::size_t> index;
  for (std::size_t i = 0; i < population.size(); ++i) index[population[i].id] = i;
  std::set<std::int64_t> unspeciated;
  for (const auto& [id, i] : index) unspeciated.insert(id);

  struct NewSpecies {
    std::size_t species_index;  // into `species` (existing or appended)
    std::size_t rep;            // population index of the new representative
    std::vector<std::int64_t> members;
  };
  std::vector<NewSpecies> assigned;
  std::vector<Species> kept;
  kept.reserve(species.size());
  // 1. New representatives of the existing species: closest genome to the old representative.
  for (Species& s : species) {
    if (unspeciated.empty()) continue;  // more species than genomes: the species dies
    double best = std::numeric_limits<double>::infinity();
    std::int64_t best_id = -1;
    for (std::int64_t id : unspeciated) {
      const double d = genome_distance(s.representative, *population[index[id]].cppn, c, mode);
      if (d < best || best_id < 0) {
        best = d;
        best_id = id;
      }
    }
    unspeciated.erase(best_id);
    kept.push_back(std::move(s));
    assigned.push_back(NewSpecies{kept.size() - 1, index[best_id], {best_id}});
  }
  species = std::move(kept);
  // 2. Every other genome joins the closest compatible species or founds a new one.
  for (std::int64_t id : unspeciated) {
    const CppnGenome& g = *population[index[id]].cppn;
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_species = assigned.size();
    for (std::size_t k = 0; k < assigned.size(); ++k) {
      const double d = genome_distance(*population[assigned[k].rep].cppn, g, c, mode);
      if (d < c.compatibility_threshold && d < best) {
        best = d;
        best_species = k;
      }
    }
    if (best_species < assigned.size()) {
      assigned[best_species].members.push_back(id);
    } else {
      Species s;
      s.id = innovation.new_species_id();
      s.created = generation;
      s.last_improved = generation;
      species.push_back(std::move(s));
      assigned.push_back(NewSpecies{species.size() - 1, index[id], {id}});
    }
  }
  // 3. Update representatives and member lists.
  std::vector<std::int64_t> result(population.size(), 0);
  for (NewSpecies& a : assigned) {
    Species& s = species[a.species_index];
    s.representative = *population[a.rep].cppn;
    s.members = std::move(a.members);
    for (std::int64_t id : s.members) result[index[id]] = s.id;
  }
  return result;
}

}  // namespace softevo::evo
