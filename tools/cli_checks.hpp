// Range checks of integer command-line options shared by softevo and softevo-mpi. A -1 default
// often means "the config's" or "the last": a negative value typed on the command line must be
// refused, not silently become that default (`--generations -5` ran the config's 500).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace softevo::cli {

// An integer of at least `lo`; the message states the bound (CLI11's NonNegativeNumber prints
// the largest double in full).
inline CLI::Validator at_least(std::int64_t lo) {
  const std::string allowed = "an integer >= " + std::to_string(lo);
  return CLI::Validator(
      [lo, allowed](std::string& text) -> std::string {
        std::int64_t v = 0;
        if (!CLI::detail::lexical_cast(text, v) || v < lo) return text + " is not " + allowed;
        return "";
      },
      "INT >= " + std::to_string(lo));
}

}  // namespace softevo::cli
