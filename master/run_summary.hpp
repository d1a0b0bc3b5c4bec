// What `softevo info` says about a run archive (docs/archive.md): metadata, state, the
// per-generation stats, the resolved config, the two digests, the integrity checks --resume
// requires (master/archive_check.hpp), the robots of each status (all generations, and the last)
// and the champion (best of the last generation) with its status. A damaged archive is still
// summarised as far as it can be read; the checks say what is wrong. tools/cmd_info.cpp prints it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "io/archive.hpp"
#include "master/archive_check.hpp"

namespace softevo::master {

// Robots of one status (EvalStatus names; "unknown" for a code this build does not know).
struct StatusCount {
  std::string status;
  std::int64_t count = 0;
};

// The best robot of the last archived generation.
struct Champion {
  std::int64_t generation = 0;
  std::int64_t id = 0;
  double fitness = 0.0;
  std::string status;                      // a killed champion is flagged, not passed off
  std::optional<double> fitness_before{};  // a learning run's: the genome as born
  std::int64_t learn_evaluations = 0;
};

// Controller learning over the whole run (docs/model.md §8.11): bodies that learned (evaluated
// in their generation, not reused), the evaluations they cost, and their fitness gained.
struct LearningTotals {
  std::int64_t bodies = 0;
  std::int64_t evaluations = 0;
  double gain_sum = 0.0;
  double gain_best = 0.0;
  std::int64_t iterations = 0;  // strategy iterations per body (curve points - 1)
  void add(const io::GenerationRecord& r);
  double mean_gain() const;  // 0 when no body learned
};

// A search strategy's metrics of one generation (docs/model.md §8.12; none for NEAT).
struct StrategyMetrics {
  std::int64_t generation = 0;
  std::vector<std::pair<std::string, double>> metrics;  // num_elites, coverage, qd_score, ...
};

struct RunSummary {
  io::RunInfo info;
  std::string strategy = "neat";  // search.strategy of the archived config
  ArchiveCheck check;
  // "running" is what a live run and a dead one both leave; the run lock tells them apart:
  // its holder ("pid 4242 on node17"), nothing if the lock is free.
  std::optional<std::string> lock_holder;
  std::optional<std::string> state_note;    // master::previous_run_note
  std::string fitness_unit = "task units";  // the task's, if the archived config parses
  std::vector<io::StatsRow> stats;          // empty if unreadable
  std::string fitness_digest;               // hash_hex, "(unreadable)" if it cannot be read
  std::string content_digest;               // likewise
  std::optional<std::int64_t> checkpoint_generation;  // the archived checkpoint's, if readable
  std::string config_text;                            // "(unreadable)" if it cannot be read
  // Every status in EvalStatus order with its count (0 included: "no killed robot" is news too),
  // over every generation and in the last.
  std::vector<StatusCount> statuses;
  std::vector<StatusCount> last_generation_statuses;
  std::optional<Champion> champion;
  std::optional<LearningTotals> learning;  // a learning run's
  // Per generation, for a strategy other than NEAT. The champion of a MAP-Elites run is the
  // best elite of the last map (the last generation's rows are only its batch of offspring).
  std::vector<StrategyMetrics> strategy_metrics;
};

// Reads the archive at `path` (and its run lock). Throws io::ArchiveError only when the archive
// cannot be opened or its run info read; every later part it cannot read is left empty.
RunSummary summarize_run(const std::string& path);

}  // namespace softevo::master
