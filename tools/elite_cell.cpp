#include "tools/elite_cell.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "common/config.hpp"
#include "common/map_grid.hpp"
#include "tools/cli_checks.hpp"

namespace softevo::cli {

EliteRow elite_of_cell(const io::Archive& archive, const std::string& cell_text,
                       std::optional<std::int64_t> generation) {
  const Config config = parse_config(archive.config_text(), archive.path() + ":/config");
  if (config.search.strategy != SearchKind::map_elites)
    throw std::invalid_argument(
        std::string("--cell ") + cell_text + ": the run's search strategy is \"" +
        to_string(config.search.strategy) + "\"; only a \"map_elites\" run has cells (use --id)");
  const MapGrid grid = map_grid(config, archive.path() + ":/config");
  std::vector<std::int64_t> bins;
  std::string axes;
  for (const MapAxis& a : grid.axes)
    axes += (axes.empty() ? "" : ", ") + a.name + " 0.." + std::to_string(a.bins - 1);
  const std::string usage = "--cell " + cell_text + ": give one bin per descriptor (" + axes + ")";
  std::size_t start = 0;
  while (start <= cell_text.size()) {
    const std::size_t comma = cell_text.find(',', start);
    const std::string part =
        cell_text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    std::size_t used = 0;
    long long v = -1;
    try {
      v = std::stoll(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (part.empty() || used != part.size()) throw std::invalid_argument(usage);
    bins.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::int64_t cell = 0;
  try {
    cell = grid.cell_of_bins(bins);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(usage);
  }
  const std::vector<std::int64_t> gens = archive.generations();
  if (gens.empty()) throw io::ArchiveError(archive.path() + ": no evaluated generation");
  const std::int64_t g = generation.value_or(gens.back());
  const StrategyTable& map = archive.generation(g).strategy.map;
  const std::size_t k = map.columns.size();
  for (std::size_t r = 0; r < map.rows(); ++r)
    if (static_cast<std::int64_t>(map.values[r * k]) == cell)
      return EliteRow{.generation = static_cast<std::int64_t>(map.values[r * k + 3]),
                      .id = static_cast<std::int64_t>(map.values[r * k + 1]),
                      .cell = cell};
  // The cells that hold an elite, as bins, so that the next try can be one of them.
  std::string held;
  const std::size_t shown = std::min<std::size_t>(map.rows(), 12);
  for (std::size_t r = 0; r < shown; ++r) {
    std::string bins_text;
    for (const std::int64_t b : grid.coordinates(static_cast<std::int64_t>(map.values[r * k])))
      bins_text += (bins_text.empty() ? "" : ",") + std::to_string(b);
    held += (held.empty() ? "" : " ") + bins_text;
  }
  if (map.rows() > shown) held += " ... (" + std::to_string(map.rows()) + " in all)";
  throw std::invalid_argument(
      "--cell " + cell_text + ": the cell is empty in the map after generation " +
      std::to_string(g) +
      (held.empty() ? std::string("; the map has no elite") : "; cells with an elite: " + held));
}

std::pair<CLI::Option*, CLI::Option*> add_individual_options(
    CLI::App& cmd, std::optional<std::int64_t>& generation, std::optional<std::int64_t>& id,
    bool& best, std::string* cell, const std::string& scope) {
  cmd.add_option("--generation,-g", generation, scope + "generation (default: the last)")
      ->check(at_least(0));
  CLI::Option* id_option =
      cmd.add_option("--id", id,
                     scope +
                         "the individual with this genome id (from the last generation "
                         "that holds it, unless --generation)")
          ->check(at_least(0));
  CLI::Option* best_option =
      cmd.add_flag("--best", best, scope + "the generation's best individual (the default)")
          ->excludes(id_option);
  if (cell != nullptr)
    cmd.add_option("--cell", *cell,
                   scope +
                       "a MAP-Elites run: the elite of this cell of the generation's map "
                       "(one 0-based bin per descriptor, e.g. 2,3)")
        ->excludes(id_option)
        ->excludes(best_option);
  return {id_option, best_option};
}

void select_cell(const std::string& path, const std::string& cell,
                 std::optional<std::int64_t>& generation, std::optional<std::int64_t>& id) {
  if (cell.empty()) return;
  if (!io::is_run_archive(path))
    throw std::invalid_argument("--cell " + cell + ": selects from a run archive; " + path +
                                " is not one");
  const EliteRow elite = elite_of_cell(io::Archive(path), cell, generation);
  generation = elite.generation;
  id = elite.id;
}

}  // namespace softevo::cli
