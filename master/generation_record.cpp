#include "master/generation_record.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <utility>

#include "evo/genome.hpp"

namespace softevo::master {

namespace {

// One row's learning columns (io::GenerationRecord), every row of a learning run.
void record_learning(io::GenerationRecord& rec, double fitness_before, std::int64_t evaluations,
                     std::vector<std::uint8_t> learned_genome, const std::vector<double>& curve) {
  rec.learning_points = static_cast<std::int64_t>(curve.size());
  rec.fitness_before.push_back(fitness_before);
  rec.learn_evaluations.push_back(evaluations);
  rec.learned_genome.push_back(std::move(learned_genome));
  rec.learning_curve.insert(rec.learning_curve.end(), curve.begin(), curve.end());
}

// A row whose result an earlier generation evaluated: its columns as archived then.
void add_earlier_result(io::GenerationRecord& rec, const ReusableResult& r, bool learning) {
  rec.status.push_back(r.status);
  rec.fitness.push_back(r.fitness);
  rec.voxels.push_back(r.voxels);
  rec.chambers.push_back(r.chambers);
  rec.wall_seconds.push_back(0.0);
  rec.worker_rank.push_back(-1);
  rec.components.insert(rec.components.end(), r.components.begin(), r.components.end());
  if (learning)
    record_learning(rec, r.fitness_before, r.learn_evaluations, r.learned_genome, r.learning_curve);
}

// A row evaluated in this generation: its own evaluation, or (`copy`) that of the member with
// the same genome, whose timing it does not repeat.
void add_outcome(io::GenerationRecord& rec, const GenomeOutcome& o, const LearnedResult* learned,
                 bool copy) {
  rec.status.push_back(static_cast<std::uint8_t>(o.status));
  rec.fitness.push_back(o.fitness);
  rec.voxels.push_back(o.voxels);
  rec.chambers.push_back(o.chambers);
  rec.wall_seconds.push_back(copy ? 0.0 : o.wall_seconds);
  rec.worker_rank.push_back(copy ? -1 : o.worker_rank);
  for (const UnitFitness& u : o.components) {
    const std::vector<double> row = tasks::component_row(u);
    rec.components.insert(rec.components.end(), row.begin(), row.end());
  }
  if (learned != nullptr) {
    const LearnedResult& l = *learned;
    record_learning(rec, l.born.fitness, l.evaluations, evo::encode_genome(l.genome), l.curve);
    if (!copy) rec.wall_seconds.back() = l.wall_seconds;
  }
}

}  // namespace

io::GenerationRecord generation_record(const GenerationInputs& in) {
  const std::vector<evo::Individual>& members = in.members;
  const ReusePlan& plan = in.plan;
  // Member index -> its outcome (and learning), for the members evaluated in this generation.
  std::vector<const GenomeOutcome*> outcome_of(members.size(), nullptr);
  std::vector<const LearnedResult*> learned_of(members.size(), nullptr);
  for (std::size_t k = 0; k < plan.evaluate.size(); ++k) {
    outcome_of[plan.evaluate[k]] = &in.evaluated[k];
    if (in.learned != nullptr) learned_of[plan.evaluate[k]] = &(*in.learned)[k];
  }

  // Archive rows in id order.
  std::vector<std::size_t> order(members.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return members[a].id < members[b].id; });
  io::GenerationRecord rec;
  rec.generation = in.generation;
  rec.units = in.task.units();
  rec.component_columns = tasks::component_columns(in.task);
  for (std::size_t i : order) {
    const evo::Individual& m = members[i];
    const ResultSource& source = plan.source[i];
    rec.id.push_back(m.id);
    rec.parent1.push_back(m.parent1);
    rec.parent2.push_back(m.parent2);
    rec.species.push_back(m.species);
    rec.genome.push_back(in.encoded[i]);
    rec.reused_from.push_back(source.origin_id);
    if (source.kind == ResultSource::Kind::earlier_generation) {
      add_earlier_result(rec, *source.earlier, in.learned != nullptr);
    } else {
      const bool copy = source.kind == ResultSource::Kind::same_generation;
      const std::size_t evaluated = copy ? source.member : i;
      add_outcome(rec, *outcome_of[evaluated], learned_of[evaluated], copy);
    }
  }
  const io::FitnessStats fs = io::fitness_stats(rec.fitness);
  rec.best = fs.best;
  rec.mean = fs.mean;
  rec.sd = fs.sd;
  rec.species_count = in.species_count;
  // Work units of the generation's results, reused ones too: the attribute is part of
  // content_digest, which reuse leaves as it was.
  rec.evaluations = static_cast<std::int64_t>(members.size()) * in.task.units();
  rec.eval_wall_seconds = in.eval_wall_seconds;
  return rec;
}

std::vector<GenomeOutcome> evaluated_outcomes(const GenerationScheduler& scheduler,
                                              const GenerationLearning* learning) {
  if (learning == nullptr) return scheduler.outcomes();
  std::vector<GenomeOutcome> evaluated;
  for (const LearnedResult& l : learning->results()) evaluated.push_back(l.learned);
  return evaluated;
}

std::vector<evo::Evaluation> evaluations(const io::GenerationRecord& rec) {
  std::vector<evo::Evaluation> out;
  out.reserve(rec.size());
  for (std::size_t r = 0; r < rec.size(); ++r)
    out.push_back(
        evo::Evaluation{.id = rec.id[r], .fitness = rec.fitness[r], .killed = rec.status[r] != 0});
  return out;
}

io::StatsRow stats_row(const io::GenerationRecord& rec, const GenerationWork& work) {
  const double seconds = rec.eval_wall_seconds;
  return io::StatsRow{
      .generation = static_cast<double>(rec.generation),
      .best = rec.best,
      .mean = rec.mean,
      .sd = rec.sd,
      .species_count = static_cast<double>(rec.species_count),
      .evaluations_per_second =
          seconds > 0 ? static_cast<double>(work.simulated_units) / seconds : 0.0,
  };
}

GenerationSummary generation_summary(const io::GenerationRecord& rec, const tasks::Task& task,
                                     const GenerationWork& work, double generation_seconds,
                                     const GenerationLearning* learning) {
  GenerationSummary summary{
      .generation = rec.generation,
      .best = rec.best,
      .mean = rec.mean,
      .species = rec.species_count,
      .search = strategy_text(rec.strategy),
      .evaluations = work.simulated_units,
      .eval_wall_seconds = rec.eval_wall_seconds,
      .generation_seconds = generation_seconds,
      .fitness_unit = task.fitness_unit(),
      .reused = work.reused_units,
  };
  if (learning != nullptr && learning->bodies_learning() > 0) {
    summary.learned_bodies = static_cast<std::int64_t>(learning->bodies_learning());
    summary.learning_iterations = learning->iterations();
    summary.learning_gain_mean = learning->mean_improvement();
    summary.learning_gain_best = learning->best_improvement();
  }
  for (std::size_t i = 0; i < rec.size(); ++i) {
    if (rec.status[i] < summary.status_counts.size()) ++summary.status_counts[rec.status[i]];
    if (rec.status[i] == static_cast<std::uint8_t>(EvalStatus::ok))
      summary.max_abs_ok_fitness = std::max(summary.max_abs_ok_fitness, std::fabs(rec.fitness[i]));
  }
  return summary;
}

std::string strategy_text(const StrategyReport& report) {
  char buf[128];
  if (report.strategy == "map_elites") {
    std::snprintf(buf, sizeof buf, "elites %lld (coverage %.1f%%) qd %.4g",
                  static_cast<long long>(report.metric("num_elites")),
                  100.0 * report.metric("coverage"), report.metric("qd_score"));
    return buf;
  }
  if (report.strategy == "afpo") {
    std::snprintf(buf, sizeof buf, "front %lld mean age %.1f",
                  static_cast<long long>(report.metric("pareto_front")), report.metric("mean_age"));
    return buf;
  }
  return report.strategy;
}

}  // namespace softevo::master
