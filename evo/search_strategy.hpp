// The search-strategy seam (docs/model.md §8.12): a strategy owns selection and reproduction of
// a run, one module per strategy (evo/neat_strategy, evo/map_elites, evo/afpo) as tasks are one
// module each. Evaluation, scheduling, result reuse, learning, checkpoints and the archive stay
// with the master, which sees only this interface:
//   ask()    the members of generation() to evaluate (ids unique; a member of an earlier
//            generation may appear again with its id: its result is reused by genome bytes)
//   tell()   every member's evaluation: selection, reproduction, generation() += 1
//   serialize() / restore_strategy(): the whole state, so that a resumed run continues
//            exactly as the uninterrupted one.
// All randomness comes from the strategy's own generator (part of its state).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/config.hpp"
#include "common/rng.hpp"
#include "common/strategy_report.hpp"
#include "common/wire.hpp"
#include "evo/genome.hpp"
#include "evo/innovation.hpp"
#include "evo/population.hpp"
#include "evo/reproduction.hpp"

namespace softevo::evo {

class SearchStrategy {
 public:
  virtual ~SearchStrategy() = default;
  virtual std::unique_ptr<SearchStrategy> clone() const = 0;
  virtual SearchKind kind() const = 0;
  const char* name() const { return to_string(kind()); }

  virtual std::int64_t generation() const = 0;
  virtual const EvoParams& params() const = 0;
  // The members to evaluate in generation().
  virtual const std::vector<Individual>& ask() const = 0;
  const std::vector<Individual>& members() const { return ask(); }
  // Lamarckian inheritance of controller learning (§8.11): member `id` takes the controller of
  // `learned` (same CPPN) before tell(). Throws std::invalid_argument as Population does.
  virtual void adopt_controller(std::int64_t id, const Genome& learned) = 0;
  // Results by id (any order), one per member. Throws std::invalid_argument on a missing,
  // unknown or duplicate id or a non-finite fitness, std::runtime_error when the generation
  // leaves nothing to reproduce from; the strategy is unchanged when it throws.
  virtual void tell(const std::vector<Evaluation>& results) = 0;
  // The whole state as a framed message.
  virtual std::vector<std::uint8_t> serialize() const = 0;

  // Species of the current speciation (NEAT); 0 for the other strategies.
  virtual std::int64_t species_count() const { return 0; }
  // What the last tell() made of the generation it was told (empty before the first, and for
  // NEAT); transient, not part of serialize().
  virtual const StrategyReport& report() const = 0;
};

// A new run's strategy for `config` (search.strategy), generation 0 created.
std::unique_ptr<SearchStrategy> make_strategy(const Config& config, int task_inputs,
                                              std::uint64_t seed);
// The strategy serialized by SearchStrategy::serialize(). Throws WireError on malformed bytes,
// std::invalid_argument for a state of another strategy than config.search.strategy (naming
// both) or that does not fit the configuration.
std::unique_ptr<SearchStrategy> restore_strategy(std::span<const std::uint8_t> bytes,
                                                 const Config& config, int task_inputs);
// Which strategy serialized `bytes` (the frame's kind and, for the non-NEAT ones, its name);
// throws WireError when it cannot tell.
SearchKind serialized_strategy(std::span<const std::uint8_t> bytes);

// ---- shared by the strategies other than NEAT ---------------------------------------------

// Checks `results` against `members` (every member once, finite fitness) and returns the
// evaluation of each member, in member order.
std::vector<Evaluation> match_results(const std::vector<Individual>& members,
                                      const std::vector<Evaluation>& results,
                                      std::int64_t generation);
// `count` random viable genomes (§8.2, §8.3) with fresh ids; throws std::runtime_error after
// 1000 x count unviable draws.
std::vector<Individual> random_individuals(std::size_t count, const EvoParams& params,
                                           const Viability& viable, InnovationTracker& innovation,
                                           Rng& rng);
// One viable offspring of `a` (mutated copy), or of crossover(a, b) then mutation when `b` is
// given (§8.6-§8.7), with a fresh id; an unviable child is drawn again from the same parents,
// up to 1000 times (then std::runtime_error).
Individual mutated_offspring(const Individual& a, double fitness_a, const Individual* b,
                             double fitness_b, const EvoParams& params, const Viability& viable,
                             InnovationTracker& innovation, Rng& rng);

// The common head of a non-NEAT state (payload of a MessageKind::strategy_state frame):
//   string strategy name, u32 layout version, i64 generation, 4 x u64 Rng state,
//   i32 next node key, i64 next genome id, i64 next species id
// then the strategy's own fields. The reader checks name and version (WireError naming the
// strategy) and restores the generator and the counters; returns the generation.
void write_state_head(WireWriter& w, SearchKind kind, std::uint32_t version,
                      std::int64_t generation, const Rng& rng, const InnovationTracker& counters);
std::int64_t read_state_head(WireReader& r, SearchKind kind, std::uint32_t version, Rng& rng,
                             InnovationTracker& counters);
// A member in a state: i64 id, i64 parent1, i64 parent2, genome payload. The reader checks the
// id against the counters and the genome against `params` (WireError / std::invalid_argument
// naming `what`).
void write_individual(WireWriter& w, const Individual& m);
Individual read_individual(WireReader& r, const EvoParams& params,
                           const InnovationTracker& counters, const std::string& what);

// ---- the base of the strategies other than NEAT ----------------------------------------------

// What the strategies other than NEAT share (evo/map_elites, evo/afpo): the run's config and
// the parameters derived from it, the generator, the innovation counters, the generation, its
// members and the last report; tell() with the strong guarantee (a copy of the strategy is told
// and then replaces it, so a throw leaves it as it was). `Derived` holds its own fields besides
// and provides tell_impl(results) (it may be private, with StrategyBase<Derived> a friend).
template <class Derived>
class StrategyBase : public SearchStrategy {
 public:
  std::unique_ptr<SearchStrategy> clone() const override {
    return std::make_unique<Derived>(derived());
  }
  std::int64_t generation() const override { return generation_; }
  const EvoParams& params() const override { return params_; }
  const std::vector<Individual>& ask() const override { return members_; }
  void adopt_controller(std::int64_t id, const Genome& learned) override {
    adopt_learned_controller(members_, id, learned, params_.shape);
  }
  void tell(const std::vector<Evaluation>& results) override {
    Derived next = derived();
    next.tell_impl(results);
    static_cast<Derived&>(*this) = std::move(next);
  }
  const StrategyReport& report() const override { return report_; }

 protected:
  StrategyBase(const Config& config, int task_inputs, std::uint64_t seed)
      : config_(config),
        params_(evo_params(config, task_inputs)),
        viable_(robot_viability(config.body)),
        rng_(seed),
        innovation_(params_.num_outputs) {}

  // Generation 0: neat.pop_size random viable genomes (std::invalid_argument for a size < 1).
  void draw_first_generation() {
    if (config_.neat.pop_size < 1) throw std::invalid_argument("neat.pop_size must be >= 1");
    members_ = random_individuals(static_cast<std::size_t>(config_.neat.pop_size), params_, viable_,
                                  innovation_, rng_);
  }

  Config config_;
  EvoParams params_;
  Viability viable_;
  Rng rng_;
  InnovationTracker innovation_;
  std::int64_t generation_ = 0;
  std::vector<Individual> members_;
  StrategyReport report_;

 private:
  const Derived& derived() const { return static_cast<const Derived&>(*this); }
};

}  // namespace softevo::evo
