// Self-scheduling of one generation's work units (MPI-free; the MPI master and the single-rank
// executor both drive it). A work unit is a (genome, unit) pair; the task says how many units a
// genome has (one for gait, one per direction for directed, §7.4) and how they combine. Units
// are handed out to whoever asks next, the ones predicted to take longest first (so the slowest
// robots do not start last and leave the other workers idle at the generation's end); results
// are stored by (genome id, unit), never by arrival or hand-out order, so the combined outcome
// is the same for any order, any number of workers and any timing (docs/architecture.md §4).
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/eval_types.hpp"
#include "tasks/task.hpp"

namespace softevo::master {

struct WorkUnit {
  std::size_t member = 0;  // index into the generation's member list
  std::int64_t genome_id = 0;
  std::int32_t unit = 0;  // 0 .. Task::units()-1
};

// The combined result of one genome (all its units, tasks::combine_units).
struct GenomeOutcome {
  std::int64_t genome_id = 0;
  EvalStatus status = EvalStatus::ok;   // first non-ok status in unit order, else ok
  double fitness = 0.0;                 // Task::combine; 0 when any unit is not ok
  std::vector<UnitFitness> components;  // one per unit
  std::int32_t voxels = 0;
  std::int32_t chambers = 0;
  double wall_seconds = 0.0;     // [s] summed over units (timing)
  std::int32_t worker_rank = 0;  // rank of the first unit (timing/diagnostics)
  std::string message;           // first failure message
};

class SchedulerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class GenerationScheduler {
 public:
  // `genome_ids` in member order (need not be sorted, must be unique); `task` gives the units
  // per genome and combines them (it must outlive the scheduler). `predicted_cost`: one value
  // per genome (any unit, e.g. master/unit_cost.hpp), handed out highest first, ties in member
  // order; empty = member order (genome-major, units in task order).
  GenerationScheduler(std::int64_t generation, std::vector<std::int64_t> genome_ids,
                      const tasks::Task& task, const std::vector<double>& predicted_cost = {});

  std::int64_t generation() const { return generation_; }
  std::size_t units_total() const { return units_.size(); }
  std::size_t units_done() const { return done_count_; }
  std::size_t units_handed_out() const { return next_; }
  bool has_next() const { return next_ < units_.size(); }
  bool done() const { return done_count_ == units_.size(); }

  // Next unit to hand out (highest predicted cost first, units of a genome in task order), or
  // nullopt.
  std::optional<WorkUnit> next();
  // Stores a result; throws SchedulerError for an unknown (id, unit), a unit that was not
  // handed out or a duplicate result.
  void complete(const EvalResult& result);

  // Combined outcome of every genome in member order; requires done(). Any non-ok unit makes
  // the genome score 0 (Task::combine; failures per run.on_failure = "killed").
  std::vector<GenomeOutcome> outcomes() const;
  // Results of non-ok status `failed` or `timeout` (for run.on_failure = "abort").
  std::vector<const EvalResult*> failures() const;

 private:
  std::size_t slot(std::int64_t genome_id, std::int32_t unit) const;

  std::int64_t generation_;
  std::vector<std::int64_t> ids_;
  const tasks::Task& task_;
  int units_per_genome_;
  std::vector<WorkUnit> units_;        // by unit slot: genome-major, units in task order
  std::vector<std::size_t> hand_out_;  // unit slots in hand-out order
  std::vector<std::optional<EvalResult>> results_;  // by unit slot
  std::vector<bool> handed_out_;
  std::size_t next_ = 0;
  std::size_t done_count_ = 0;
};

}  // namespace softevo::master
