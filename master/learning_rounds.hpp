// One generation's controller learning, scheduled as work units (docs/model.md §8.11; MPI-free
// like the rest of master/). After the generation's ordinary evaluation (round 0: every member
// whose result is not reused), every newly evaluated body with a valid, actuatable body gets a
// ControllerLearner (evo/learning.hpp) that the master holds. The bodies learn in lock step:
// iteration i of every body is one round of work units in the one pool (bodies x lambda
// candidates x task units), handed out longest first like a generation's units, and the
// strategies advance only when the round is complete. Results are stored by candidate, never by
// arrival, so the learned controllers are the same for any rank count and timing.
//
// Between two rounds the whole state (every body's strategy, generator included, and the results
// so far) serializes into the run's checkpoint (io::Checkpoint::learning), so a run killed in a
// generation's learning continues after the last completed round (docs/model.md §8.11).
//
// A candidate's work unit carries the candidate's own genome (the body's CPPN with the
// candidate controller) under a round-local id (its index in the round), so workers evaluate
// it like any genome: nothing on the worker side knows about learning.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "evo/genome.hpp"
#include "evo/learning.hpp"
#include "master/scheduler.hpp"

namespace softevo::master {

// What learning made of one evaluated member.
struct LearnedResult {
  GenomeOutcome born;     // the evaluation of the genome as created
  GenomeOutcome learned;  // the evaluation of the learned genome (= born if nothing was taken)
  evo::Genome genome;     // the learned genome (the born one if nothing was taken)
  std::int64_t evaluations = 1;  // evaluations spent on this body, born one included
  std::vector<double> curve;     // best fitness so far after evaluation 0 and every iteration
  double wall_seconds = 0.0;     // [s] of every evaluation of the body (timing)
};

class GenerationLearning {
 public:
  // `ids`, `genomes`, `born` (the round-0 outcomes) and `costs` (predicted unit cost, empty =
  // none) in the same order: the members evaluated in this generation. A body learns unless its
  // born status is invalid_body (it was never simulated).
  GenerationLearning(const Config& config, const evo::EvoParams& params, std::int64_t generation,
                     std::vector<std::int64_t> ids, std::vector<evo::Genome> genomes,
                     std::vector<GenomeOutcome> born, std::vector<double> costs);

  bool finished() const { return iteration_ >= iterations_ || learners_.empty(); }
  std::int64_t iteration() const { return iteration_; }  // iterations completed
  std::int64_t iterations() const { return iterations_; }
  std::size_t bodies_learning() const { return learners_.size(); }

  // Proposes the next iteration of every learning body: the round's work-unit ids (0, 1, ...)
  // and predicted costs, for a GenerationScheduler. Requires !finished().
  void begin_iteration(std::vector<std::int64_t>& unit_ids, std::vector<double>& costs);
  // The request of a candidate's work unit (generation and config hash of the run).
  EvalRequest request(const WorkUnit& unit, std::uint64_t config_hash) const;
  // The round's outcomes in unit-id order: every body's strategy takes its candidates' scores.
  void end_iteration(const std::vector<GenomeOutcome>& outcomes);

  // The state between rounds (after round 0 or an iteration, before the next begin_iteration)
  // as a framed message (kind learning_state), for the run's checkpoint. Throws
  // std::logic_error while a round is in flight.
  std::vector<std::uint8_t> serialize() const;
  // The learning serialize() saved, to continue with the next round: `config` must give the
  // saved iterations and lambda, and `generation` be the saved one; the strategies propose
  // with `params` (the population's, as for the constructor). Throws WireError on malformed
  // bytes, std::invalid_argument for a state of another generation or config, or one with no
  // round left (never saved: the last round's results go straight into the archive).
  static GenerationLearning deserialize(std::span<const std::uint8_t> bytes, const Config& config,
                                        const evo::EvoParams& params, std::int64_t generation);
  // The ids of the members, constructor order (a restored state must be for the same members).
  std::vector<std::int64_t> ids() const;

  // Per member in constructor order; complete once finished().
  const std::vector<LearnedResult>& results() const { return results_; }
  // Mean and largest (learned - born) fitness over the learning bodies so far.
  double mean_improvement() const;
  double best_improvement() const;

 private:
  GenerationLearning(const evo::EvoParams& params, std::int64_t generation)
      : params_(params), generation_(generation) {}
  struct Body {
    std::size_t member = 0;  // index into results_
    evo::ControllerLearner learner;
    double cost = 0.0;
  };
  evo::EvoParams params_;  // a copy: the population's is replaced when it advances
  std::int64_t generation_;
  std::int64_t iterations_ = 0;
  std::int64_t iteration_ = 0;
  int lambda_ = 1;
  std::vector<LearnedResult> results_;
  std::vector<Body> learners_;
  // The round in flight: candidate genomes encoded, by unit id (body-major, candidate order).
  std::vector<std::vector<std::uint8_t>> round_genomes_;
};

}  // namespace softevo::master
