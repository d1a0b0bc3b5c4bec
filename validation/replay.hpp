// Replaying archived individuals: evaluate an archived genome again, exactly as the run did, and
// compare the result bit for bit with what the run stored (`softevo replay --verify`, and the
// tests and scripts that audit archives).
//
// Record inputs, not outputs: the archive keeps the resolved config text and every encoded
// genome, so an evaluation can be repeated exactly. A replay goes through the path of a run:
// worker::evaluate per work unit of the archived config's task, and master::GenerationScheduler
// to combine the units as the task does.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "master/scheduler.hpp"
#include "motion/robot_source.hpp"
#include "tasks/task.hpp"

namespace softevo::validation {

// The individuals to replay and what they need: the archived config, its hash (checked against
// the archive's config_hash attribute) and, when the archive was simulated with another physics
// revision, a note saying so.
struct ReplaySelection {
  std::string archive_path;
  std::vector<motion::ArchivedIndividual> individuals;  // in id order
  std::uint64_t config_hash = 0;
  std::optional<std::string> revision_note;  // set when the revisions differ
};

// One individual (`id`, or the best of the generation) or, with `all`, every individual of the
// generation (default: the last). Throws std::runtime_error naming the file when the recorded
// config hash does not belong to the archived config text, when the generation is empty, or
// when `verify` is asked of an archive of another physics revision (its bits cannot match).
ReplaySelection select_for_replay(const std::string& archive_path,
                                  std::optional<std::int64_t> generation,
                                  std::optional<std::int64_t> id, bool all, bool verify);

struct ReplayResult {
  master::GenomeOutcome outcome;
  // False for an archived timeout: it depended on the wall clock, not on the inputs, so there
  // is nothing to compare bit for bit.
  bool verifiable = true;
  std::string mismatch;  // "" = identical (filled only when verifying)
};

// Evaluates `individual` again with `task` (made from the archived config) and, when `verify`,
// compares status, fitness bits and every archived component the task has, by name (an archive
// of an older build may lack some components and hold others).
ReplayResult replay(const motion::ArchivedIndividual& individual, const tasks::Task& task,
                    std::uint64_t config_hash, bool verify);

}  // namespace softevo::validation
