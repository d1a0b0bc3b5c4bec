// What a search strategy reports about a generation (docs/model.md §8.12), as plain data the
// archive stores (io/archive.hpp) and the progress line prints: evo/ fills it, io/ writes it.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace softevo {

// A table of named numeric columns, row-major.
struct StrategyTable {
  std::vector<std::string> columns;
  std::vector<double> values;  // [rows][columns.size()]
  std::size_t rows() const { return columns.empty() ? 0 : values.size() / columns.size(); }
  bool operator==(const StrategyTable&) const = default;
};

struct StrategyReport {
  // "map_elites" | "afpo"; "" for NEAT, whose species are the archive's own columns (nothing
  // more is reported, so a NEAT archive is the one earlier builds wrote).
  std::string strategy;
  StrategyTable rows;  // one row per individual of the generation, ascending id
  StrategyTable map;   // MAP-Elites: the elites after the generation, ascending cell
  std::vector<std::pair<std::string, double>> metrics;  // num_elites, coverage, ...
  bool empty() const { return strategy.empty(); }
  // The value of metric `name`; `otherwise` when it has none.
  double metric(const std::string& name, double otherwise = 0.0) const {
    for (const auto& [n, v] : metrics)
      if (n == name) return v;
    return otherwise;
  }
  bool operator==(const StrategyReport&) const = default;
};

}  // namespace softevo
