#include "evo/afpo.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "evo/development.hpp"

namespace softevo::evo {

namespace {

constexpr std::uint32_t kAfpoStateVersion = 1;

bool dominates(double fa, std::int64_t aa, double fb, std::int64_t ab) {
  return fa >= fb && aa <= ab && (fa > fb || aa < ab);
}

}  // namespace

std::vector<std::int64_t> pareto_ranks(const std::vector<double>& fitness,
                                       const std::vector<std::int64_t>& age) {
  if (fitness.size() != age.size())
    throw std::invalid_argument("pareto_ranks: " + std::to_string(fitness.size()) +
                                " fitnesses for " + std::to_string(age.size()) + " ages");
  // Peel off non-dominated fronts; O(n^2) per front, n is twice the population at most.
  const std::size_t n = fitness.size();
  std::vector<std::int64_t> rank(n, -1);
  std::size_t assigned = 0;
  for (std::int64_t front = 0; assigned < n; ++front) {
    std::vector<std::size_t> members;
    for (std::size_t i = 0; i < n; ++i) {
      if (rank[i] >= 0) continue;
      bool dominated = false;
      for (std::size_t j = 0; j < n && !dominated; ++j)
        dominated = j != i && rank[j] < 0 && dominates(fitness[j], age[j], fitness[i], age[i]);
      if (!dominated) members.push_back(i);
    }
    for (std::size_t i : members) rank[i] = front;
    assigned += members.size();
  }
  return rank;
}

std::vector<std::size_t> afpo_survivors(const std::vector<double>& fitness,
                                        const std::vector<std::int64_t>& age,
                                        const std::vector<std::int64_t>& id, std::size_t count) {
  const std::vector<std::int64_t> rank = pareto_ranks(fitness, age);
  std::vector<std::size_t> order(fitness.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (rank[a] != rank[b]) return rank[a] < rank[b];
    if (fitness[a] != fitness[b]) return fitness[a] > fitness[b];
    if (age[a] != age[b]) return age[a] < age[b];
    return id[a] < id[b];
  });
  order.resize(std::min(count, order.size()));
  std::sort(order.begin(), order.end());
  return order;
}

std::int64_t offspring_age(AfpoAge rule, std::int64_t parent_age, bool body_changed) {
  return rule == AfpoAge::body && body_changed ? 0 : parent_age;
}

Afpo Afpo::create(const Config& config, int task_inputs, std::uint64_t seed) {
  Afpo a(config, task_inputs, seed);
  a.draw_first_generation();
  a.ages_.assign(a.members_.size(), 0);
  return a;
}

bool Afpo::body_changed(const Genome& parent, const Genome& child) const {
  const DevelopedBody p = develop_body(parent.cppn, config_.body);
  const DevelopedBody c = develop_body(child.cppn, config_.body);
  return p.plan.lattice != c.plan.lattice || p.plan.cells != c.plan.cells;
}

void Afpo::tell_impl(const std::vector<Evaluation>& results) {
  const std::vector<Evaluation> matched = match_results(members_, results, generation_);
  const std::size_t n = members_.size();
  std::vector<double> fitness(n);
  std::vector<std::int64_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) {
    fitness[i] = matched[i].fitness;
    ids[i] = members_[i].id;
  }
  const std::vector<std::int64_t> rank = pareto_ranks(fitness, ages_);
  const auto pop_size = static_cast<std::size_t>(config_.neat.pop_size);
  const std::vector<std::size_t> kept = afpo_survivors(fitness, ages_, ids, pop_size);

  // Report: per row (ascending id) age, Pareto rank, survived.
  std::vector<std::size_t> by_id(n);
  std::iota(by_id.begin(), by_id.end(), std::size_t{0});
  std::sort(by_id.begin(), by_id.end(),
            [&](std::size_t a, std::size_t b) { return ids[a] < ids[b]; });
  std::vector<bool> survives(n, false);
  for (std::size_t i : kept) survives[i] = true;
  StrategyReport report;
  report.strategy = "afpo";
  report.rows.columns = {"age", "pareto_rank", "survived"};
  for (std::size_t i : by_id)
    report.rows.values.insert(
        report.rows.values.end(),
        {static_cast<double>(ages_[i]), static_cast<double>(rank[i]), survives[i] ? 1.0 : 0.0});
  double max_fitness = -std::numeric_limits<double>::infinity();
  double sum = 0.0;
  double age_sum = 0.0;
  std::int64_t front = 0;
  for (std::size_t i = 0; i < n; ++i) {
    max_fitness = std::max(max_fitness, fitness[i]);
    sum += fitness[i];
    if (rank[i] == 0) ++front;
  }
  for (std::size_t i : kept) age_sum += static_cast<double>(ages_[i]);
  report.metrics = {{"max_fitness", max_fitness},
                    {"mean_fitness", sum / static_cast<double>(n)},
                    {"pareto_front", static_cast<double>(front)},
                    {"mean_age", age_sum / static_cast<double>(kept.size())}};

  // The survivors, one generation older, in ascending id order; then the offspring and the
  // newcomer.
  std::vector<Individual> survivors;
  std::vector<std::int64_t> survivor_ages;
  std::vector<double> survivor_fitness;
  for (std::size_t i : by_id)
    if (survives[i]) {
      survivors.push_back(members_[i]);
      survivor_ages.push_back(ages_[i] + 1);
      survivor_fitness.push_back(fitness[i]);
    }
  std::vector<Individual> next = survivors;
  std::vector<std::int64_t> next_ages = survivor_ages;
  for (std::size_t k = 0; k + 1 < pop_size; ++k) {
    const std::size_t p = rng_.uniform_int(survivors.size());
    Individual child = mutated_offspring(survivors[p], survivor_fitness[p], nullptr, 0.0, params_,
                                         viable_, innovation_, rng_);
    const bool changed =
        config_.afpo.age == AfpoAge::body && body_changed(survivors[p].genome, child.genome);
    next_ages.push_back(offspring_age(config_.afpo.age, survivor_ages[p], changed));
    next.push_back(std::move(child));
  }
  for (Individual& newcomer : random_individuals(1, params_, viable_, innovation_, rng_)) {
    next.push_back(std::move(newcomer));
    next_ages.push_back(0);
  }
  members_ = std::move(next);
  ages_ = std::move(next_ages);
  report_ = std::move(report);
  ++generation_;
}

// ---------------------------------------------------------------------------------------------
// State layout (payload of a MessageKind::strategy_state frame), little-endian, in this order:
//   the head of write_state_head ("afpo", layout version 1, generation, Rng, counters),
//   u64 member count, per member: i64 age, i64 id, i64 parent1, i64 parent2, genome payload
std::vector<std::uint8_t> Afpo::serialize() const {
  WireWriter w;
  write_state_head(w, SearchKind::afpo, kAfpoStateVersion, generation_, rng_, innovation_);
  w.u64(members_.size());
  for (std::size_t i = 0; i < members_.size(); ++i) {
    w.i64(ages_[i]);
    write_individual(w, members_[i]);
  }
  return frame_message(MessageKind::strategy_state, w.data());
}

Afpo Afpo::deserialize(std::span<const std::uint8_t> bytes, const Config& config, int task_inputs) {
  WireReader r(unframe_message(bytes, MessageKind::strategy_state), "afpo state");
  Afpo a(config, task_inputs, 0);
  a.generation_ = read_state_head(r, SearchKind::afpo, kAfpoStateVersion, a.rng_, a.innovation_);
  const std::uint64_t members = r.u64("member count");
  if (members > r.remaining() / 32)
    throw WireError("afpo state: member count exceeds the message length");
  for (std::uint64_t i = 0; i < members; ++i) {
    const std::int64_t age = r.i64("member age");
    if (age < 0) throw WireError("afpo state: member " + std::to_string(i) + ": negative age");
    a.members_.push_back(read_individual(r, a.params_, a.innovation_, "member"));
    a.ages_.push_back(age);
  }
  r.finish();
  return a;
}

}  // namespace softevo::evo
