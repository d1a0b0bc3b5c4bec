// A finished generation as the archive stores it (io::GenerationRecord) and as the progress line
// and the reproduction see it. RunLoop::end_generation (master/run.cpp) calls these in order:
// rows, then the evaluations that reproduce, then the stats row and the summary.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "evo/population.hpp"
#include "evo/reproduction.hpp"
#include "io/archive.hpp"
#include "master/learning_rounds.hpp"
#include "master/progress.hpp"
#include "master/result_reuse.hpp"
#include "master/scheduler.hpp"
#include "tasks/task.hpp"

namespace softevo::master {

// Everything a generation's rows are made of: views of the run loop's state, named at the call
// (designated initializers; a missing reference does not compile).
struct GenerationInputs {
  std::int64_t generation = 0;
  const tasks::Task& task;
  const std::vector<evo::Individual>& members;            // population order
  const std::vector<std::vector<std::uint8_t>>& encoded;  // members' genomes, same order
  const ReusePlan& plan;
  // The outcomes of the members evaluated in this generation, in plan.evaluate order (with
  // learning: those of the learned genomes).
  const std::vector<GenomeOutcome>& evaluated;
  // With controller learning: what learning made of each evaluated member, plan.evaluate order;
  // nullptr without learning.
  const std::vector<LearnedResult>* learned = nullptr;
  std::int64_t species_count = 0;  // species after the last speciation
  double eval_wall_seconds = 0.0;  // [s] the evaluation phase (timing)
};

// The generation's archive rows in id order, each from where its result comes
// (ResultSource::Kind): the member's own evaluation, a result of an earlier generation, or the
// evaluation of a member of this generation with the same genome. A reused row has wall_seconds
// 0 and worker_rank -1. Also fills the group attributes (fitness stats, species, work units).
io::GenerationRecord generation_record(const GenerationInputs& in);

// The outcomes the rows are made of, plan.evaluate order: the scheduler's, or with learning
// (`learning` not null) the learned genomes'.
std::vector<GenomeOutcome> evaluated_outcomes(const GenerationScheduler& scheduler,
                                              const GenerationLearning* learning);

// What reproduction selects on, one per row in row (id) order.
std::vector<evo::Evaluation> evaluations(const io::GenerationRecord& rec);

// The work of a generation beside its rows, for the stats row and the progress line.
struct GenerationWork {
  std::int64_t simulated_units = 0;  // work units simulated, learning rounds included
  std::int64_t reused_units = 0;     // work units whose result was reused
};

// The archive's stats row (its evaluations per second: simulated units over the rows'
// eval_wall_seconds, 0 when that is 0).
io::StatsRow stats_row(const io::GenerationRecord& rec, const GenerationWork& work);

// The progress line's view of the generation (master/progress.hpp): `generation_seconds` [s]
// the whole generation, reproduction and archive included; `learning` the generation's
// learning, nullptr without.
GenerationSummary generation_summary(const io::GenerationRecord& rec, const tasks::Task& task,
                                     const GenerationWork& work, double generation_seconds,
                                     const GenerationLearning* learning);

// The progress line's figures of a strategy other than NEAT: "elites 34 (coverage 3.4%) qd
// 118.2" for MAP-Elites, "front 5 mean age 2.3" for AFPO; "" for NEAT (an empty report).
std::string strategy_text(const StrategyReport& report);

}  // namespace softevo::master
