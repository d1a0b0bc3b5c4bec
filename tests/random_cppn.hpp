// Random CPPNs for property tests of body development and of what is made of bodies
// (tests/evo/test_development.cpp, tests/fabricate/test_fabricate.cpp): 0-3 hidden nodes, random
// activations, weights, 10 % disabled connections.
#pragma once

#include "common/rng.hpp"
#include "evo/cppn.hpp"

namespace softevo::test {

inline evo::CppnGenome random_cppn(Rng& rng) {
  using namespace evo;
  CppnGenome g;
  const int hidden = static_cast<int>(rng.uniform_int(4));
  for (int k = 0; k < 4 + hidden; ++k)
    g.nodes.push_back(NodeGene{k < 4 ? k : 10 + k, rng.normal(0.0, 1.5), 1.0,
                               static_cast<Activation>(rng.uniform_int(7))});
  auto add = [&](int in, int out) {
    for (const auto& c : g.connections)
      if (c.in == in && c.out == out) return;
    g.connections.push_back({in, out, rng.normal(0.0, 2.0), rng.uniform() < 0.9});
  };
  for (int n = 0; n < 4 + hidden; ++n) {
    const int key = g.nodes[static_cast<std::size_t>(n)].key;
    const int inputs = 1 + static_cast<int>(rng.uniform_int(4));
    for (int i = 0; i < inputs; ++i) add(-1 - static_cast<int>(rng.uniform_int(4)), key);
    if (key < 4)
      for (int h = 4; h < 4 + hidden; ++h)
        if (rng.uniform() < 0.5) add(g.nodes[static_cast<std::size_t>(h)].key, key);
  }
  return g;
}

}  // namespace softevo::test
