// Integrity checks of a run archive (docs/archive.md "Integrity checks"): what --resume
// requires before it continues a run and what `softevo info` reports. An archive that fails
// one is never continued: a flipped byte would otherwise be carried into a "complete" run.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/archive.hpp"

namespace softevo::master {

struct ArchiveProblem {
  std::int64_t generation = -1;  // -1: the archive as a whole (config, counts, checkpoint)
  std::string check;             // "config", "generations_done", "readable", "ids", "digest",
                                 // "statistics", "status", "stats", "checkpoint"
  std::string message;           // names the object and what is wrong
};

struct ArchiveCheck {
  std::vector<ArchiveProblem> problems;  // empty = consistent
  // Generations 0..consistent_generations-1 pass every per-generation check.
  std::int64_t consistent_generations = 0;
  std::int64_t generations_with_digest = 0;  // the rest predate the digest attribute
  std::int64_t generations_checked = 0;
  bool ok() const { return problems.empty(); }
  // "generation 3: digest: ..." lines, one per problem.
  std::string describe(const std::string& path) const;
};

// Runs every check on `archive`; never throws for a damaged archive (damage is a problem).
ArchiveCheck check_archive(const io::Archive& archive);

}  // namespace softevo::master
