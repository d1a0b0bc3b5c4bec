#include "master/result_reuse.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace softevo::master {
namespace {

std::string key_of(std::span<const std::uint8_t> genome) {
  return std::string(reinterpret_cast<const char*>(genome.data()), genome.size());
}

}  // namespace

bool reusable(EvalStatus status) {
  return status != EvalStatus::failed && status != EvalStatus::timeout;
}

void ResultMemory::remember(const io::GenerationRecord& record) {
  by_genome_.clear();
  const std::size_t per_row =
      static_cast<std::size_t>(record.units) * record.component_columns.size();
  for (std::size_t i = 0; i < record.size(); ++i) {
    if (!reusable(static_cast<EvalStatus>(record.status[i]))) continue;
    ReusableResult r;
    const bool reused = !record.reused_from.empty() && record.reused_from[i] != io::kNotReused;
    r.origin_id = reused ? record.reused_from[i] : record.id[i];
    r.status = record.status[i];
    r.fitness = record.fitness[i];
    r.voxels = record.voxels[i];
    r.chambers = record.chambers[i];
    const auto first = record.components.begin() + static_cast<std::ptrdiff_t>(i * per_row);
    r.components.assign(first, first + static_cast<std::ptrdiff_t>(per_row));
    if (record.has_learning()) {
      r.fitness_before = record.fitness_before[i];
      r.learn_evaluations = record.learn_evaluations[i];
      r.learned_genome = record.learned_genome[i];
      const auto points = static_cast<std::size_t>(record.learning_points);
      const auto curve = record.learning_curve.begin() + static_cast<std::ptrdiff_t>(i * points);
      r.learning_curve.assign(curve, curve + static_cast<std::ptrdiff_t>(points));
      if (record.learned_genome[i] != record.genome[i])
        by_genome_.emplace(key_of(record.learned_genome[i]), r);
    }
    // Equal bytes have equal results: the first row of them is as good as any.
    by_genome_.emplace(key_of(record.genome[i]), std::move(r));
  }
}

const ReusableResult* ResultMemory::find(std::span<const std::uint8_t> genome) const {
  const auto it = by_genome_.find(key_of(genome));
  return it == by_genome_.end() ? nullptr : &it->second;
}

ReuseScope reuse_scope(const TerrainConfig& terrain) {
  return {.earlier_generations = !terrain.ground_varies_with_generation(),
          .same_generation = !terrain.ground_varies_with_evaluation()};
}

ReusePlan plan_reuse(const std::vector<std::int64_t>& ids,
                     const std::vector<std::vector<std::uint8_t>>& genomes,
                     const ResultMemory* memory, ReuseScope scope) {
  if (ids.size() != genomes.size())
    throw std::invalid_argument("plan_reuse: " + std::to_string(ids.size()) + " ids for " +
                                std::to_string(genomes.size()) + " genomes");
  ReusePlan plan;
  plan.source.resize(ids.size());
  if (memory == nullptr) {
    plan.evaluate.resize(ids.size());
    std::iota(plan.evaluate.begin(), plan.evaluate.end(), std::size_t{0});
    return plan;
  }
  // Lowest id first, so which duplicate is evaluated does not depend on the member order.
  std::vector<std::size_t> by_id(ids.size());
  std::iota(by_id.begin(), by_id.end(), std::size_t{0});
  std::sort(by_id.begin(), by_id.end(),
            [&](std::size_t a, std::size_t b) { return ids[a] < ids[b]; });
  std::unordered_map<std::string, std::size_t> first_of;  // genome bytes -> evaluated member
  for (std::size_t m : by_id) {
    ResultSource& s = plan.source[m];
    const ReusableResult* earlier = scope.earlier_generations ? memory->find(genomes[m]) : nullptr;
    if (earlier != nullptr) {
      s.kind = ResultSource::Kind::earlier_generation;
      s.earlier = earlier;
      s.origin_id = earlier->origin_id;
      continue;
    }
    if (!scope.same_generation) continue;
    const auto [it, fresh] = first_of.emplace(key_of(genomes[m]), m);
    if (!fresh) {
      s.kind = ResultSource::Kind::same_generation;
      s.member = it->second;
      s.origin_id = ids[it->second];
    }
  }
  for (std::size_t m = 0; m < ids.size(); ++m)
    if (plan.source[m].kind == ResultSource::Kind::evaluated) plan.evaluate.push_back(m);
  return plan;
}

}  // namespace softevo::master
