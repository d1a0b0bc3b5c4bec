#include "master/run_summary.hpp"

#include <algorithm>
#include <map>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "io/run_lock.hpp"
#include "master/run_state.hpp"
#include "tasks/task.hpp"

namespace softevo::master {

namespace {

using StatusMap = std::map<std::string, std::int64_t>;

// Every status in EvalStatus order, then a code this build does not know.
std::vector<StatusCount> status_rows(const StatusMap& counts) {
  std::vector<StatusCount> rows;
  for (int code = 0; code <= static_cast<int>(EvalStatus::invalid_body); ++code) {
    const std::string name = to_string(static_cast<EvalStatus>(code));
    const auto it = counts.find(name);
    rows.push_back(StatusCount{.status = name, .count = it == counts.end() ? 0 : it->second});
  }
  for (const auto& [name, n] : counts)
    if (name == "unknown") rows.push_back(StatusCount{.status = name, .count = n});
  return rows;
}

// The best row of `r` (generation left to the caller, who knows it).
Champion champion_of(const io::GenerationRecord& r) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < r.size(); ++i)
    if (r.fitness[i] > r.fitness[best]) best = i;
  Champion c{.id = r.id[best],
             .fitness = r.fitness[best],
             .status = to_string(static_cast<EvalStatus>(r.status[best]))};
  if (r.has_learning()) {
    c.fitness_before = r.fitness_before[best];
    c.learn_evaluations = r.learn_evaluations[best];
  }
  return c;
}

// The best elite of a MAP-Elites map (columns cell, id, fitness, generation, ...; the first
// in cell order on ties); nothing for another table. Elites are robots of status ok.
std::optional<Champion> best_elite(const StrategyTable& map) {
  if (map.rows() == 0 || map.columns.size() < 4 || map.columns[1] != "id" ||
      map.columns[2] != "fitness" || map.columns[3] != "generation")
    return std::nullopt;
  const std::size_t k = map.columns.size();
  std::size_t best = 0;
  for (std::size_t i = 1; i < map.rows(); ++i)
    if (map.values[i * k + 2] > map.values[best * k + 2]) best = i;
  return Champion{.generation = static_cast<std::int64_t>(map.values[best * k + 3]),
                  .id = static_cast<std::int64_t>(map.values[best * k + 1]),
                  .fitness = map.values[best * k + 2],
                  .status = "ok"};
}

// The parts read generation by generation: statuses, champion, learning.
void add_generations(const io::Archive& archive, RunSummary& s) {
  StatusMap all_statuses, last_statuses;
  try {
    const std::vector<std::int64_t> gens = archive.generations();
    for (const std::int64_t g : gens) {
      const io::GenerationRecord r = archive.generation(g);
      if (r.has_learning()) {
        if (!s.learning) s.learning.emplace();
        s.learning->add(r);
      }
      for (const std::uint8_t code : r.status) {
        const std::string name = to_string(static_cast<EvalStatus>(code));
        ++all_statuses[name];
        if (g == gens.back()) ++last_statuses[name];
      }
      if (g == gens.back() && r.size() > 0) {
        s.champion = champion_of(r);
        s.champion->generation = g;
        if (const auto elite = best_elite(r.strategy.map)) s.champion = elite;
      }
      if (!r.strategy.empty()) s.strategy_metrics.push_back({g, r.strategy.metrics});
    }
  } catch (const io::ArchiveError&) {
  }
  s.statuses = status_rows(all_statuses);
  s.last_generation_statuses = status_rows(last_statuses);
}

}  // namespace

void LearningTotals::add(const io::GenerationRecord& r) {
  iterations = r.learning_points - 1;
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (r.reused_from[i] != io::kNotReused) continue;
    ++bodies;
    evaluations += r.learn_evaluations[i];
    const double gain = r.fitness[i] - r.fitness_before[i];
    gain_sum += gain;
    gain_best = std::max(gain_best, gain);
  }
}

double LearningTotals::mean_gain() const {
  return bodies > 0 ? gain_sum / static_cast<double>(bodies) : 0.0;
}

RunSummary summarize_run(const std::string& path) {
  const io::Archive archive(path);
  RunSummary s;
  s.info = archive.info();
  s.check = check_archive(archive);
  s.lock_holder = io::lock_holder(path);
  std::optional<std::int64_t> generations;  // the run's target, if its config parses
  try {
    const Config config = parse_config(archive.config_text(), path + ":/config");
    generations = config.run.generations;
    s.fitness_unit = tasks::make_task(config)->fitness_unit();
    s.strategy = to_string(config.search.strategy);
  } catch (const std::exception&) {
  }
  s.state_note = previous_run_note(s.info, s.lock_holder, generations);
  const auto or_unreadable = [](auto&& read) -> std::string {
    try {
      return read();
    } catch (const io::ArchiveError&) {
      return "(unreadable)";
    }
  };
  try {
    s.stats = archive.stats();
  } catch (const io::ArchiveError&) {
  }
  s.fitness_digest = or_unreadable([&] { return hash_hex(io::fitness_digest(archive)); });
  s.content_digest = or_unreadable([&] { return hash_hex(io::content_digest(archive)); });
  try {
    if (const std::optional<io::Checkpoint> c = archive.checkpoint())
      s.checkpoint_generation = c->generation;
  } catch (const io::ArchiveError&) {
  }
  s.config_text = or_unreadable([&] { return archive.config_text(); });
  add_generations(archive, s);
  return s;
}

}  // namespace softevo::master
