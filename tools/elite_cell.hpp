// `--cell i,j[,k]` of `softevo export`, `view`, `render` and `fabricate`: the elite of one cell of
// a MAP-Elites map (docs/model.md §8.12.2), as the generation and id of its archived row.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

#include "io/archive.hpp"

namespace softevo::cli {

struct EliteRow {
  std::int64_t generation = 0;  // the generation in which the elite was evaluated
  std::int64_t id = 0;
  std::int64_t cell = 0;
};

// The elite of cell `cell_text` ("2,3": one bin index per descriptor, 0-based) in the map after
// generation `generation` (default: the last). Throws std::invalid_argument naming --cell for a
// run of another strategy, malformed text, a bin out of range or an empty cell.
EliteRow elite_of_cell(const io::Archive& archive, const std::string& cell_text,
                       std::optional<std::int64_t> generation);

// Which archived individual a command takes: --generation (-g), --id, --best and, with `cell`,
// --cell, with one spelling and one help text each in export, replay, render, view and
// fabricate. `scope` starts each help ("archive: ") where the command also reads other inputs.
// Returns the --id and --best options (for more exclusions, as replay's --all).
std::pair<CLI::Option*, CLI::Option*> add_individual_options(
    CLI::App& cmd, std::optional<std::int64_t>& generation, std::optional<std::int64_t>& id,
    bool& best, std::string* cell, const std::string& scope);

// With `cell` given (not ""): `generation` and `id` become those of the elite of that cell of
// the map after `generation` (default: the last) of the archive at `path`.
void select_cell(const std::string& path, const std::string& cell,
                 std::optional<std::int64_t>& generation, std::optional<std::int64_t>& id);

}  // namespace softevo::cli
