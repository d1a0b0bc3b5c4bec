// Run archives from Python: the C++ reader (io::Archive), its tables as numpy columns.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "evo/genome.hpp"
#include "io/archive.hpp"
#include "master/archive_check.hpp"
#include "python/src/bindings.hpp"
#include "worker/evaluate.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace softevo::python {
namespace {

py::dict info_dict(const io::RunInfo& i) {
  py::dict d;
  d["format"] = i.format;
  d["version"] = i.version;
  d["git_commit"] = i.git_commit;
  d["physics_revision"] = i.physics_revision;
  d["seed"] = i.seed;
  d["ranks"] = i.ranks;
  d["program"] = i.program;
  d["host"] = i.host;
  d["start_time"] = i.start_time;
  d["end_time"] = i.end_time;
  d["config_hash"] = i.config_hash;
  d["experiment_hash"] = i.experiment_hash;
  d["experiment"] = i.experiment;
  d["state"] = to_string(i.state);
  d["generations_done"] = i.generations_done;
  d["stop_reason"] = i.stop_reason;
  return d;
}

// The integrity checks `softevo info` runs (master/archive_check.hpp), as a dict.
py::dict check_dict(const io::Archive& archive) {
  const master::ArchiveCheck check = master::check_archive(archive);
  py::list problems;
  for (const master::ArchiveProblem& p : check.problems) {
    py::dict d;
    d["generation"] = p.generation;
    d["check"] = p.check;
    d["message"] = p.message;
    problems.append(d);
  }
  py::dict d;
  d["ok"] = check.ok();
  d["generations_checked"] = check.generations_checked;
  d["generations_with_digest"] = check.generations_with_digest;
  d["consistent_generations"] = check.consistent_generations;
  d["problems"] = problems;
  d["description"] = check.describe(archive.path());
  return d;
}

// Column name of component `name` of unit u: the name itself for a one-unit task, name_u else.
std::string unit_column(const std::string& name, int unit, int units) {
  return units == 1 ? name : name + "_" + std::to_string(unit);
}

// Every individual of every generation as columns (dict name -> 1-D array), generations
// ascending, rows in id order; the component columns of every unit after the fixed ones.
py::dict individual_columns(const io::Archive& archive) {
  std::vector<std::int64_t> generation, id, parent1, parent2, species;
  std::vector<std::uint8_t> status;
  std::vector<double> fitness, wall_seconds;
  std::vector<std::int32_t> voxels, chambers, worker_rank;
  std::vector<std::string> component_names;
  std::vector<std::vector<double>> components;
  int units = 0;
  // Controller learning (docs/model.md §8.11): columns only when every generation has them.
  bool learning = true;
  std::vector<double> fitness_before;
  std::vector<std::int64_t> learn_evaluations, reused_from;
  std::vector<std::vector<double>> learning_curve;
  // A search strategy other than NEAT (docs/model.md §8.12): its per-row columns in place of
  // the species, when every generation has the same ones.
  std::string strategy;
  std::vector<std::string> strategy_names;
  std::vector<std::vector<double>> strategy_values;
  bool strategy_rows = true;
  for (const std::int64_t g : archive.generations()) {
    const io::GenerationRecord r = archive.generation(g);
    r.check();
    if (generation.empty()) {
      strategy = r.strategy.strategy;
      strategy_names = r.strategy.rows.columns;
      strategy_values.resize(strategy_names.size());
    }
    strategy_rows = strategy_rows && r.strategy.strategy == strategy &&
                    r.strategy.rows.columns == strategy_names;
    if (strategy_rows)
      for (std::size_t row = 0; row < r.size(); ++row)
        for (std::size_t c = 0; c < strategy_names.size(); ++c)
          strategy_values[c].push_back(r.strategy.rows.values[row * strategy_names.size() + c]);
    if (components.empty()) {
      units = r.units;
      for (int u = 0; u < units; ++u)
        for (const std::string& c : r.component_columns)
          component_names.push_back(unit_column(c, u, units));
      components.resize(component_names.size());
    } else if (r.units * r.component_columns.size() != components.size()) {
      throw io::ArchiveError(archive.path() + ": /generations/" + io::generation_group_name(g) +
                             "/components has a different shape from the earlier generations'");
    }
    generation.insert(generation.end(), r.size(), g);
    id.insert(id.end(), r.id.begin(), r.id.end());
    parent1.insert(parent1.end(), r.parent1.begin(), r.parent1.end());
    parent2.insert(parent2.end(), r.parent2.begin(), r.parent2.end());
    species.insert(species.end(), r.species.begin(), r.species.end());
    status.insert(status.end(), r.status.begin(), r.status.end());
    fitness.insert(fitness.end(), r.fitness.begin(), r.fitness.end());
    voxels.insert(voxels.end(), r.voxels.begin(), r.voxels.end());
    chambers.insert(chambers.end(), r.chambers.begin(), r.chambers.end());
    wall_seconds.insert(wall_seconds.end(), r.wall_seconds.begin(), r.wall_seconds.end());
    worker_rank.insert(worker_rank.end(), r.worker_rank.begin(), r.worker_rank.end());
    reused_from.insert(reused_from.end(), r.reused_from.begin(), r.reused_from.end());
    learning = learning && r.has_learning();
    if (learning) {
      fitness_before.insert(fitness_before.end(), r.fitness_before.begin(), r.fitness_before.end());
      learn_evaluations.insert(learn_evaluations.end(), r.learn_evaluations.begin(),
                               r.learn_evaluations.end());
      const auto points = static_cast<std::size_t>(r.learning_points);
      for (std::size_t row = 0; row < r.size(); ++row)
        learning_curve.emplace_back(
            r.learning_curve.begin() + static_cast<std::ptrdiff_t>(row * points),
            r.learning_curve.begin() + static_cast<std::ptrdiff_t>((row + 1) * points));
    }
    const std::size_t width = components.size();
    if (r.components.size() != r.size() * width)
      throw io::ArchiveError(archive.path() + ": /generations/" + io::generation_group_name(g) +
                             "/components has " + std::to_string(r.components.size()) +
                             " values, expected " + std::to_string(r.size() * width));
    for (std::size_t row = 0; row < r.size(); ++row)
      for (std::size_t c = 0; c < width; ++c)
        components[c].push_back(r.components[row * width + c]);
  }
  py::dict d;
  d["generation"] = array_of(generation);
  d["id"] = array_of(id);
  d["parent1"] = array_of(parent1);
  d["parent2"] = array_of(parent2);
  if (strategy.empty()) d["species"] = array_of(species);  // NEAT's own column
  py::dict strategy_columns;
  if (strategy_rows)
    for (std::size_t c = 0; c < strategy_names.size(); ++c)
      strategy_columns[py::str(strategy_names[c])] = array_of(strategy_values[c]);
  d["strategy_columns"] = strategy_columns;
  d["status_code"] = array_of(status);
  d["fitness"] = array_of(fitness);
  d["voxels"] = array_of(voxels);
  d["chambers"] = array_of(chambers);
  d["wall_seconds"] = array_of(wall_seconds);
  d["worker_rank"] = array_of(worker_rank);
  d["reused_from"] = array_of(reused_from);
  if (learning && !fitness_before.empty()) {
    d["fitness_before"] = array_of(fitness_before);
    d["learn_evaluations"] = array_of(learn_evaluations);
    py::list curves;
    for (const std::vector<double>& c : learning_curve) curves.append(array_of(c));
    d["learning_curve"] = curves;
  }
  py::dict comps;
  for (std::size_t c = 0; c < components.size(); ++c)
    comps[py::str(component_names[c])] = array_of(components[c]);
  d["components"] = comps;
  d["units"] = units;
  return d;
}

// A strategy table (common/strategy_report.hpp) as columns (dict name -> 1-D array).
py::dict table_columns(const StrategyTable& t) {
  py::dict d;
  const std::size_t k = t.columns.size();
  for (std::size_t c = 0; c < k; ++c) {
    std::vector<double> column;
    for (std::size_t r = 0; r < t.rows(); ++r) column.push_back(t.values[r * k + c]);
    d[py::str(t.columns[c])] = array_of(column);
  }
  return d;
}

// What the search strategy archived of generation `generation` (default: the last): its name
// ("" for NEAT), per-row columns (with the rows' ids), the MAP-Elites map and the metrics.
py::dict strategy_generation(const io::Archive& archive, std::optional<std::int64_t> generation) {
  const std::vector<std::int64_t> gens = archive.generations();
  if (gens.empty()) throw py::key_error(archive.path() + ": the archive has no generation yet");
  const std::int64_t g = generation.value_or(gens.back());
  if (std::find(gens.begin(), gens.end(), g) == gens.end())
    throw py::key_error(archive.path() + ": no generation " + std::to_string(g));
  const io::GenerationRecord r = archive.generation(g);
  py::dict d;
  d["generation"] = g;
  d["strategy"] = r.strategy.strategy;
  py::dict rows = table_columns(r.strategy.rows);
  if (!r.strategy.empty()) rows["id"] = array_of(r.id);
  d["rows"] = rows;
  d["map"] = table_columns(r.strategy.map);
  py::dict metrics;
  for (const auto& [name, value] : r.strategy.metrics) metrics[py::str(name)] = value;
  d["metrics"] = metrics;
  return d;
}

// Every generation's strategy metrics as columns (generation first); empty for NEAT.
py::dict strategy_metric_columns(const io::Archive& archive) {
  std::vector<std::string> names;
  std::vector<std::vector<double>> values;
  std::vector<std::int64_t> generation;
  for (const std::int64_t g : archive.generations()) {
    const io::GenerationRecord r = archive.generation(g);
    if (r.strategy.empty()) continue;
    if (names.empty())
      for (const auto& [name, value] : r.strategy.metrics) names.push_back(name);
    values.resize(names.size());
    generation.push_back(g);
    for (std::size_t k = 0; k < names.size(); ++k)
      values[k].push_back(r.strategy.metric(names[k], std::nan("")));
  }
  py::dict d;
  d["generation"] = array_of(generation);
  for (std::size_t k = 0; k < names.size(); ++k) d[py::str(names[k])] = array_of(values[k]);
  return d;
}

py::dict stats_columns(const io::Archive& archive) {
  std::vector<double> generation, best, mean, sd, species, rate;
  for (const io::StatsRow& s : archive.stats()) {
    generation.push_back(s.generation);
    best.push_back(s.best);
    mean.push_back(s.mean);
    sd.push_back(s.sd);
    species.push_back(s.species_count);
    rate.push_back(s.evaluations_per_second);
  }
  py::dict d;
  d["generation"] = array_of(generation);
  d["best"] = array_of(best);
  d["mean"] = array_of(mean);
  d["sd"] = array_of(sd);
  d["species_count"] = array_of(species);
  d["evaluations_per_second"] = array_of(rate);
  return d;
}

// Individual `id` of generation `generation` (default: the latest one that has it) as a robot,
// developed with the archived config as the run did.
RobotFile archived_robot(const io::Archive& archive, std::int64_t id,
                         std::optional<std::int64_t> generation) {
  std::vector<std::int64_t> gens = archive.generations();
  if (generation) {
    if (!std::binary_search(gens.begin(), gens.end(), *generation))
      throw py::key_error(archive.path() + ": no generation " + std::to_string(*generation));
    gens = {*generation};
  }
  const Config config = parse_config(archive.config_text(), archive.path() + ":/config");
  for (auto g = gens.rbegin(); g != gens.rend(); ++g) {
    const io::GenerationRecord r = archive.generation(*g);
    r.check();
    const auto at = std::lower_bound(r.id.begin(), r.id.end(), id);
    if (at == r.id.end() || *at != id) continue;
    const auto row = static_cast<std::size_t>(at - r.id.begin());
    if (row >= r.genome.size())
      throw io::ArchiveError(archive.path() + ": /generations/" + io::generation_group_name(*g) +
                             "/genome has no row " + std::to_string(row));
    // A learning run's fitness is the learned controller's: that robot is the individual.
    const evo::Genome genome =
        evo::decode_genome(r.has_learning() ? r.learned_genome[row] : r.genome[row]);
    return worker::robot_file_of(
        config, genome,
        archive.info().experiment + " gen " + std::to_string(*g) + " id " + std::to_string(id));
  }
  throw py::key_error(archive.path() + ": no individual with id " + std::to_string(id) +
                      (generation ? " in generation " + std::to_string(*generation) : ""));
}

}  // namespace

void bind_archive(py::module_& m) {
  py::class_<io::Archive>(m, "Archive", "A run archive (softevo.run/1) opened read-only.")
      .def(py::init<const std::string&>(), "path"_a)
      .def_property_readonly("path", &io::Archive::path)
      .def_property_readonly("info", [](const io::Archive& a) { return info_dict(a.info()); })
      .def_property_readonly("config_text", &io::Archive::config_text)
      .def_property_readonly("generations", &io::Archive::generations)
      .def("individual_columns", &individual_columns)
      .def("stats_columns", &stats_columns)
      .def("strategy_generation", &strategy_generation, "generation"_a = py::none())
      .def("strategy_metric_columns", &strategy_metric_columns)
      .def("robot", &archived_robot, "id"_a, "generation"_a = py::none())
      .def("fitness_digest", [](const io::Archive& a) { return hash_hex(io::fitness_digest(a)); })
      .def("check", &check_dict);
}

}  // namespace softevo::python
