#include "master/scheduler.hpp"

#include <algorithm>
#include <unordered_set>
#include <utility>

namespace softevo::master {

GenerationScheduler::GenerationScheduler(std::int64_t generation,
                                         std::vector<std::int64_t> genome_ids, int n_directions)
    : generation_(generation), ids_(std::move(genome_ids)), n_directions_(n_directions) {
  if (n_directions < 0) throw SchedulerError("negative direction count");
  std::unordered_set<std::int64_t> seen;
  for (std::int64_t id : ids_)
    if (!seen.insert(id).second)
      throw SchedulerError("generation " + std::to_string(generation) + ": duplicate genome id " +
                           std::to_string(id));
  const int per_genome = n_directions_ == 0 ? 1 : n_directions_;
  units_.reserve(ids_.size() * static_cast<std::size_t>(per_genome));
  for (std::size_t m = 0; m < ids_.size(); ++m)
    for (int d = 0; d < per_genome; ++d)
      units_.push_back(WorkUnit{m, ids_[m], n_directions_ == 0 ? -1 : d});
  results_.resize(units_.size());
  handed_out_.assign(units_.size(), false);
}

std::optional<WorkUnit> GenerationScheduler::next() {
  if (next_ >= units_.size()) return std::nullopt;
  handed_out_[next_] = true;
  return units_[next_++];
}

std::size_t GenerationScheduler::slot(std::int64_t genome_id, std::int32_t direction_index) const {
  // Units are genome-major in member order; find the member by id (linear: n <= a few hundred).
  const auto it = std::find(ids_.begin(), ids_.end(), genome_id);
  const int per_genome = n_directions_ == 0 ? 1 : n_directions_;
  const bool dir_ok = n_directions_ == 0 ? direction_index == -1
                                         : direction_index >= 0 && direction_index < n_directions_;
  if (it == ids_.end() || !dir_ok)
    throw SchedulerError("generation " + std::to_string(generation_) +
                         ": result for unknown work unit (genome " + std::to_string(genome_id) +
                         ", direction " + std::to_string(direction_index) + ")");
  const auto m = static_cast<std::size_t>(it - ids_.begin());
  return m * static_cast<std::size_t>(per_genome) +
         static_cast<std::size_t>(n_directions_ == 0 ? 0 : direction_index);
}

void GenerationScheduler::complete(const EvalResult& result) {
  const std::size_t s = slot(result.genome_id, result.direction_index);
  const std::string unit = "(genome " + std::to_string(result.genome_id) + ", direction " +
                           std::to_string(result.direction_index) + ")";
  if (!handed_out_[s]) throw SchedulerError("result for a unit never handed out " + unit);
  if (results_[s].has_value()) throw SchedulerError("duplicate result for unit " + unit);
  results_[s] = result;
  ++done_count_;
}

std::vector<GenomeOutcome> GenerationScheduler::outcomes() const {
  if (!done()) throw SchedulerError("outcomes() before every unit has a result");
  const int per_genome = n_directions_ == 0 ? 1 : n_directions_;
  std::vector<GenomeOutcome> out(ids_.size());
  for (std::size_t m = 0; m < ids_.size(); ++m) {
    GenomeOutcome& o = out[m];
    o.genome_id = ids_[m];
    double sum = 0.0;  // §7.4: F = sum over directions, in the fixed direction order
    for (int d = 0; d < per_genome; ++d) {
      const EvalResult& r =
          *results_[m * static_cast<std::size_t>(per_genome) + static_cast<std::size_t>(d)];
      if (d == 0) {
        o.worker_rank = r.worker_rank;
        o.voxels = r.voxels;
        o.chambers = r.chambers;
      }
      o.wall_seconds += r.wall_seconds;
      if (r.status != EvalStatus::ok && o.status == EvalStatus::ok) {
        o.status = r.status;
        o.message = r.message;
      }
      sum += r.fitness;
      DirectionComponents c;
      if (!r.components.empty()) c = r.components.front();
      c.fitness = r.fitness;
      c.status = r.status;
      o.components.push_back(c);
    }
    // Any killed/failed direction scores the genome like a killed robot (§7.1, §7.4).
    o.fitness = o.status == EvalStatus::ok ? sum : 0.0;
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
