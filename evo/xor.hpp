// XOR with the NEAT machinery (issue 5): proves speciation, reproduction and the CPPN operators
// on the classic benchmark of Stanley & Miikkulainen (2002), independently of robots.
//
// Networks: 2 inputs (keys -1, -2), 1 output (key 0), sigmoid nodes only (neat-python's
// 1/(1+exp(-5z)), close to the paper's steepened sigmoid 4.9), the bias is the node bias (no
// bias input). Evaluated with FeedForwardNetwork (neat-python 0.92 semantics).
#pragma once

#include <cstdint>
#include <vector>

#include "evo/genome.hpp"

namespace softevo::evo {

// Parameters of the XOR experiment (values and reasons in xor.cpp).
EvoParams xor_params();

struct XorScore {
  double fitness = 0.0;  // 4 - sum of squared errors over the 4 cases (neat-python's xor example)
  bool solved = false;   // every output on the correct side of 0.5 (>= 0.5 for 1, < 0.5 for 0)
};
XorScore evaluate_xor(const CppnGenome& genome);

struct XorRun {
  bool solved = false;
  std::int64_t generations = 0;  // generations evaluated (the solving one included)
  std::int64_t evaluations = 0;  // members evaluated up to and including the solving generation
  int hidden_nodes = 0;          // of the first solution (first in member order)
  int enabled_connections = 0;
};
// One seeded run: evaluate every generation until some member solves XOR or `max_generations`
// generations have been evaluated.
XorRun run_xor(std::uint64_t seed, std::int64_t max_generations = 500);
XorRun run_xor(std::uint64_t seed, std::int64_t max_generations, const EvoParams& params);

struct XorSummary {
  int runs = 0;
  int solved = 0;
  double mean_evaluations = 0.0;  // over solved runs
  double sd_evaluations = 0.0;    // sample standard deviation (n - 1) over solved runs
  double mean_generations = 0.0;
  double mean_hidden_nodes = 0.0;
  double mean_enabled_connections = 0.0;
  std::int64_t worst_evaluations = 0;
};
// Runs seeds first_seed .. first_seed + runs - 1.
XorSummary run_xor_benchmark(int runs, std::uint64_t first_seed = 1,
                             std::int64_t max_generations = 500);
XorSummary run_xor_benchmark(int runs, std::uint64_t first_seed, std::int64_t max_generations,
                             const EvoParams& params);

}  // namespace softevo::evo
