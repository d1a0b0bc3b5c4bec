#include "master/scheduler.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <span>
#include <unordered_set>
#include <utility>

namespace softevo::master {

GenerationScheduler::GenerationScheduler(std::int64_t generation,
                                         std::vector<std::int64_t> genome_ids,
                                         const tasks::Task& task,
                                         const std::vector<double>& predicted_cost)
    : generation_(generation),
      ids_(std::move(genome_ids)),
      task_(task),
      units_per_genome_(task.units()) {
  if (units_per_genome_ < 1)
    throw SchedulerError(std::string("task ") + to_string(task.kind()) + " has no work unit");
  std::unordered_set<std::int64_t> seen;
  for (std::int64_t id : ids_)
    if (!seen.insert(id).second)
      throw SchedulerError("generation " + std::to_string(generation) + ": duplicate genome id " +
                           std::to_string(id));
  units_.reserve(ids_.size() * static_cast<std::size_t>(units_per_genome_));
  for (std::size_t m = 0; m < ids_.size(); ++m)
    for (int u = 0; u < units_per_genome_; ++u) units_.push_back(WorkUnit{m, ids_[m], u});
  results_.resize(units_.size());
  handed_out_.assign(units_.size(), false);
  hand_out_.resize(units_.size());
  std::iota(hand_out_.begin(), hand_out_.end(), std::size_t{0});
  if (predicted_cost.empty()) return;
  if (predicted_cost.size() != ids_.size())
    throw SchedulerError("generation " + std::to_string(generation) + ": " +
                         std::to_string(predicted_cost.size()) + " predicted costs for " +
                         std::to_string(ids_.size()) + " genomes");
  for (double c : predicted_cost)
    if (!std::isfinite(c))
      throw SchedulerError("generation " + std::to_string(generation) +
                           ": a predicted cost is not finite");
  // Stable: equal costs keep member order, so the order is a function of the inputs alone.
  std::stable_sort(hand_out_.begin(), hand_out_.end(), [&](std::size_t a, std::size_t b) {
    return predicted_cost[units_[a].member] > predicted_cost[units_[b].member];
  });
}

std::optional<WorkUnit> GenerationScheduler::next() {
  if (next_ >= units_.size()) return std::nullopt;
  const std::size_t s = hand_out_[next_++];
  handed_out_[s] = true;
  return units_[s];
}

std::size_t GenerationScheduler::slot(std::int64_t genome_id, std::int32_t unit) const {
  // Units are genome-major in member order; find the member by id (linear: n <= a few hundred).
  const auto it = std::find(ids_.begin(), ids_.end(), genome_id);
  if (it == ids_.end() || unit < 0 || unit >= units_per_genome_)
    throw SchedulerError("generation " + std::to_string(generation_) +
                         ": result for unknown work unit (genome " + std::to_string(genome_id) +
                         ", unit " + std::to_string(unit) + ")");
  const auto m = static_cast<std::size_t>(it - ids_.begin());
  return m * static_cast<std::size_t>(units_per_genome_) + static_cast<std::size_t>(unit);
}

void GenerationScheduler::complete(const EvalResult& result) {
  const std::size_t s = slot(result.genome_id, result.unit);
  const std::string unit =
      "(genome " + std::to_string(result.genome_id) + ", unit " + std::to_string(result.unit) + ")";
  if (!handed_out_[s]) throw SchedulerError("result for a unit never handed out " + unit);
  if (results_[s].has_value()) throw SchedulerError("duplicate result for unit " + unit);
  results_[s] = result;
  ++done_count_;
}

std::vector<GenomeOutcome> GenerationScheduler::outcomes() const {
  if (!done()) throw SchedulerError("outcomes() before every unit has a result");
  const auto per_genome = static_cast<std::size_t>(units_per_genome_);
  std::vector<GenomeOutcome> out(ids_.size());
  std::vector<EvalResult> units(per_genome);
  for (std::size_t m = 0; m < ids_.size(); ++m) {
    for (std::size_t u = 0; u < per_genome; ++u) units[u] = *results_[m * per_genome + u];
    EvalResult combined = tasks::combine_units(task_, units);
    GenomeOutcome& o = out[m];
    o.genome_id = ids_[m];
    o.status = combined.status;
    o.fitness = combined.fitness;
    o.components = std::move(combined.components);
    o.voxels = combined.voxels;
    o.chambers = combined.chambers;
    o.wall_seconds = combined.wall_seconds;
    o.worker_rank = combined.worker_rank;
    o.message = std::move(combined.message);
  }
  return out;
}

std::vector<const EvalResult*> GenerationScheduler::failures() const {
  std::vector<const EvalResult*> out;
  for (const auto& r : results_)
    if (r && (r->status == EvalStatus::failed || r->status == EvalStatus::timeout))
      out.push_back(&*r);
  return out;
}

}  // namespace softevo::master
