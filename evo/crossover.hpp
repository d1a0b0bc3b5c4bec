// Crossover operators (docs/model.md §8.6).
#pragma once

#include "common/rng.hpp"
#include "evo/genome.hpp"

namespace softevo::evo {

// CPPN, neat-python 0.92 configure_crossover with the project's whole-gene inheritance: the
// fitter genome is parent1 (a tie makes the SECOND argument parent1); for every connection gene
// of parent1 (its order), then every node gene (key order): a gene parent2 also has is taken
// whole from parent1 if U[0,1) > 0.5, else from parent2; genes only parent1 has are copied;
// genes only parent2 has are dropped.
CppnGenome crossover_cppn(const CppnGenome& a, double fitness_a, const CppnGenome& b,
                          double fitness_b, Rng& rng);

// Controller vectors, parent order = call order (A, B), not fitness order.
// 1pointpl: per vector (canonical order) independently: U < 0.5 swaps the roles of A and B;
//   cut p uniform in {0..len}; child = first[:p] + second[p:], the same cut for step sizes.
// random: per gene (canonical order) U < 0.5 takes A's value and step size, else B's.
// 1point: one role swap (U < 0.5), one cut p in {0..total} across the 9 vectors concatenated.
// Writes child.controller and child.step_sizes. No-op (child left without controller) when A
// has none. Throws std::invalid_argument when the parents' vector lengths differ.
void crossover_controller(const Genome& a, const Genome& b, EvoParams::CrossoverMethod method,
                          Rng& rng, Genome& child);

// Whole child: CPPN crossover (fitness decides parent1), then controller crossover (A, B).
Genome crossover(const Genome& a, double fitness_a, const Genome& b, double fitness_b,
                 const EvoParams& p, Rng& rng);

}  // namespace softevo::evo
