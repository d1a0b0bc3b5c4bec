#include "evo/crossover.hpp"

#include <stdexcept>
#include <utility>

namespace softevo::evo {

CppnGenome crossover_cppn(const CppnGenome& a, double fitness_a, const CppnGenome& b,
                          double fitness_b, Rng& rng) {
  // genome1 = a, genome2 = b: "if genome1.fitness > genome2.fitness: parent1 = genome1".
  const CppnGenome& p1 = fitness_a > fitness_b ? a : b;
  const CppnGenome& p2 = fitness_a > fitness_b ? b : a;
  CppnGenome child;
  child.num_inputs = p1.num_inputs;
  child.num_outputs = p1.num_outputs;
  child.connections.reserve(p1.connections.size());
  for (const ConnectionGene& c1 : p1.connections) {
    const ConnectionGene* c2 = nullptr;
    for (const ConnectionGene& c : p2.connections)
      if (c.in == c1.in && c.out == c1.out) {
        c2 = &c;
        break;
      }
    // Whole-gene inheritance (§8.6, the project's gene class): draw r > 0.5 keeps parent1's.
    if (c2 == nullptr || rng.uniform() > 0.5)
      child.connections.push_back(c1);
    else
      child.connections.push_back(*c2);
  }
  child.nodes.reserve(p1.nodes.size());
  for (const NodeGene& n1 : p1.nodes) {
    const NodeGene* n2 = p2.find_node(n1.key);
    if (n2 == nullptr || rng.uniform() > 0.5)
      child.nodes.push_back(n1);
    else
      child.nodes.push_back(*n2);
  }
  return child;
}

namespace {

void check_same_lengths(const Genome& a, const Genome& b) {
  const auto va = vectors_of(a.controller);
  const auto vb = vectors_of(b.controller);
  const auto sa = vectors_of(a.step_sizes);
  const auto sb = vectors_of(b.step_sizes);
  for (int v = 0; v < kControllerVectorCount; ++v)
    if (va[v]->size() != vb[v]->size() || sa[v]->size() != va[v]->size() ||
        sb[v]->size() != vb[v]->size())
      throw std::invalid_argument(std::string("controller crossover: vector ") +
                                  kControllerVectorNames[v] + " differs in length between parents");
}

}  // namespace

void crossover_controller(const Genome& a, const Genome& b, EvoParams::CrossoverMethod method,
                          Rng& rng, Genome& child) {
  child.controller = ControllerVectors{};
  child.step_sizes = ControllerVectors{};
  if (!a.has_controller()) return;
  check_same_lengths(a, b);
  const auto va = vectors_of(a.controller);
  const auto vb = vectors_of(b.controller);
  const auto sa = vectors_of(a.step_sizes);
  const auto sb = vectors_of(b.step_sizes);
  auto vc = vectors_of(child.controller);
  auto sc = vectors_of(child.step_sizes);
  using M = EvoParams::CrossoverMethod;
  switch (method) {
    case M::one_point_per_layer:
      for (int v = 0; v < kControllerVectorCount; ++v) {
        const bool swap = rng.uniform() < 0.5;
        const auto& first_v = swap ? *vb[v] : *va[v];
        const auto& second_v = swap ? *va[v] : *vb[v];
        const auto& first_s = swap ? *sb[v] : *sa[v];
        const auto& second_s = swap ? *sa[v] : *sb[v];
        const std::size_t len = first_v.size();
        const std::size_t cut = rng.uniform_int(len + 1);  // p in {0, ..., len}
        vc[v]->resize(len);
        sc[v]->resize(len);
        for (std::size_t i = 0; i < len; ++i) {
          (*vc[v])[i] = i < cut ? first_v[i] : second_v[i];
          (*sc[v])[i] = i < cut ? first_s[i] : second_s[i];
        }
      }
      break;
    case M::random:
      for (int v = 0; v < kControllerVectorCount; ++v) {
        const std::size_t len = va[v]->size();
        vc[v]->resize(len);
        sc[v]->resize(len);
        for (std::size_t i = 0; i < len; ++i) {
          const bool from_a = rng.uniform() < 0.5;  // gene carried with its step size
          (*vc[v])[i] = from_a ? (*va[v])[i] : (*vb[v])[i];
          (*sc[v])[i] = from_a ? (*sa[v])[i] : (*sb[v])[i];
        }
      }
      break;
    case M::one_point: {
      const bool swap = rng.uniform() < 0.5;
      std::size_t total = 0;
      for (int v = 0; v < kControllerVectorCount; ++v) total += va[v]->size();
      const std::size_t cut = rng.uniform_int(total + 1);  // p in {0, ..., total}
      std::size_t offset = 0;  // position of vector v in the concatenation
      for (int v = 0; v < kControllerVectorCount; ++v) {
        const auto& first_v = swap ? *vb[v] : *va[v];
        const auto& second_v = swap ? *va[v] : *vb[v];
        const auto& first_s = swap ? *sb[v] : *sa[v];
        const auto& second_s = swap ? *sa[v] : *sb[v];
        const std::size_t len = first_v.size();
        vc[v]->resize(len);
        sc[v]->resize(len);
        for (std::size_t i = 0; i < len; ++i) {
          const bool before = offset + i < cut;
          (*vc[v])[i] = before ? first_v[i] : second_v[i];
          (*sc[v])[i] = before ? first_s[i] : second_s[i];
        }
        offset += len;
      }
      break;
    }
  }
}

Genome crossover(const Genome& a, double fitness_a, const Genome& b, double fitness_b,
                 const EvoParams& p, Rng& rng) {
  Genome child;
  child.cppn = crossover_cppn(a.cppn, fitness_a, b.cppn, fitness_b, rng);
  crossover_controller(a, b, p.crossover_method, rng, child);
  return child;
}

}  // namespace softevo::evo
