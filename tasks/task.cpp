// Shared parts of the Task seam. See task.hpp.
#include "tasks/task.hpp"

#include <stdexcept>

namespace softevo::tasks {

void UnitScore::controller_inputs(const physics::Model&, const physics::State&, std::span<float>) {}

void UnitScore::observe(int, const physics::Model&, const physics::State&) {}

void UnitScore::steer(double) {
  throw std::logic_error("this task has no target direction to steer");
}

CombinedFitness Task::combine(std::span<const EvalResult> units) const {
  CombinedFitness c;
  double sum = 0.0;  // in the fixed unit order: the same bits for any number of workers
  for (const EvalResult& r : units) {
    if (r.status != EvalStatus::ok && c.status == EvalStatus::ok) {
      c.status = r.status;
      c.message = r.message;
    }
    sum += r.fitness;
  }
  c.fitness = c.status == EvalStatus::ok ? sum : 0.0;
  return c;
}

EvalResult combine_units(const Task& task, std::span<const EvalResult> units) {
  EvalResult total;
  if (units.empty()) return total;
  const EvalResult& first = units.front();
  total.genome_id = first.genome_id;
  total.voxels = first.voxels;
  total.chambers = first.chambers;
  total.worker_rank = first.worker_rank;
  const std::size_t values = task.component_names().size();
  for (const EvalResult& r : units) {
    UnitFitness row;
    if (!r.components.empty()) row = r.components.front();
    row.fitness = r.fitness;
    row.status = r.status;
    row.values.resize(values, 0.0);
    total.components.push_back(std::move(row));
    total.steps += r.steps;
    total.sim_seconds += r.sim_seconds;
    total.wall_seconds += r.wall_seconds;
  }
  const CombinedFitness c = task.combine(units);
  total.status = c.status;
  total.fitness = c.fitness;
  total.message = c.message;
  return total;
}

std::vector<double> component_row(const UnitFitness& unit) {
  std::vector<double> row;
  row.reserve(unit.values.size() + 2);
  row.push_back(unit.fitness);
  row.insert(row.end(), unit.values.begin(), unit.values.end());
  row.push_back(static_cast<double>(static_cast<int>(unit.status)));
  return row;
}

std::vector<std::string> component_columns(const Task& task) {
  std::vector<std::string> columns = {"fitness"};
  for (const ComponentName& c : task.component_names()) columns.push_back(c.name);
  columns.emplace_back("status");
  return columns;
}

}  // namespace softevo::tasks
