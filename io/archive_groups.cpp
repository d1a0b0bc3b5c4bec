// The run archive's groups as the writer fills them (docs/archive.md "Root attributes",
// `/stats`, `/checkpoint`, `/generations/<G>`): the same for a small root, a segment and a pack.
#include <cstdint>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/archive_writer_internal.hpp"
#include "io/h5.hpp"

namespace softevo::io::detail {
namespace {

using h5::Charset;

const char* const kStatsColumnNames =
    "generation,best,mean,sd,species_count,evaluations_per_second";

// A strategy table as a 2-D dataset with its column names (nothing for a table without columns).
void write_strategy_table(const h5::Group& g, const std::string& name, const StrategyTable& t) {
  if (t.columns.empty()) return;
  g.write_dataset<double>(name, {static_cast<hsize_t>(t.rows()), t.columns.size()}, t.values)
      .write_string_attribute(kColumnsAttribute, join_columns(t.columns), h5::Charset::ascii);
}

// /generations/G/strategy (docs/archive.md): a strategy other than NEAT.
void write_strategy_group(const h5::Group& parent, const StrategyReport& s) {
  const h5::Group g = parent.create_group("strategy");
  g.write_string_attribute("name", s.strategy, Charset::utf8);
  g.write_attribute<std::int64_t>("schema_version", kStrategySchemaVersion);
  write_strategy_table(g, "rows", s.rows);
  write_strategy_table(g, "map", s.map);
  StrategyTable metrics;
  for (const auto& [key, value] : s.metrics) {
    metrics.columns.push_back(key);
    metrics.values.push_back(value);
  }
  write_strategy_table(g, "metrics", metrics);
}

}  // namespace

void write_run_info(const h5::File& file, const RunInfo& info) {
  file.write_string_attribute("format", info.format, Charset::utf8);
  file.write_string_attribute("version", info.version, Charset::utf8);
  file.write_string_attribute("git_commit", info.git_commit, Charset::utf8);
  file.write_attribute<std::int32_t>("physics_revision", info.physics_revision);
  file.write_attribute<std::int64_t>("seed", info.seed);
  file.write_attribute<std::int32_t>("ranks", info.ranks);
  if (!info.program.empty()) file.write_string_attribute("program", info.program, Charset::utf8);
  file.write_string_attribute("host", info.host, Charset::utf8);
  file.write_string_attribute("start_time", info.start_time, Charset::utf8);
  file.write_string_attribute("end_time", info.end_time, Charset::utf8);
  file.write_string_attribute("config_hash", info.config_hash, Charset::utf8);
  if (!info.experiment_hash.empty())
    file.write_string_attribute("experiment_hash", info.experiment_hash, Charset::utf8);
  file.write_string_attribute("experiment", info.experiment, Charset::utf8);
  file.write_string_attribute("state", to_string(info.state), Charset::utf8);
  file.write_attribute<std::int64_t>("generations_done", info.generations_done);
  if (!info.stop_reason.empty() || file.has_attribute("stop_reason"))  // "" clears it (--resume)
    file.write_string_attribute("stop_reason", info.stop_reason, Charset::utf8);
}

void write_stats(const h5::File& file, const std::vector<StatsRow>& rows) {
  // Chunked with unlimited rows, as it always was: an older build continuing this archive
  // extends it in place.
  h5::PropertyList creation = h5::PropertyList::dataset_creation();
  creation.chunk({64, kStatsColumns});
  const hsize_t n = rows.size();
  const h5::Dataset stats = file.create_dataset<double>(
      "stats", h5::Dataspace::simple({n, kStatsColumns}, {H5S_UNLIMITED, kStatsColumns}),
      &creation);
  stats.write_string_attribute("columns", kStatsColumnNames, Charset::utf8);
  if (n == 0) return;
  std::vector<double> values;
  values.reserve(rows.size() * kStatsColumns);
  for (const StatsRow& s : rows)
    values.insert(values.end(),
                  {s.generation, s.best, s.mean, s.sd, s.species_count, s.evaluations_per_second});
  stats.write_block<double>({0, 0}, {n, kStatsColumns}, values);
}

void write_checkpoint(const h5::File& file, const Checkpoint& checkpoint) {
  const h5::Group cg = file.create_group("checkpoint");
  cg.write_dataset<std::uint8_t>("population", {static_cast<hsize_t>(checkpoint.population.size())},
                                 checkpoint.population);
  cg.write_attribute<std::int64_t>("generation", checkpoint.generation);
  if (!checkpoint.learning.empty())
    cg.write_dataset<std::uint8_t>("learning", {static_cast<hsize_t>(checkpoint.learning.size())},
                                   checkpoint.learning);
}

void write_generation_group(const h5::Group& parent, const std::string& name,
                            const GenerationRecord& record) {
  const h5::Group g = parent.create_group(name);
  const hsize_t n = record.size();
  g.write_dataset<std::int64_t>("id", {n}, record.id);
  g.write_dataset<std::int64_t>("parent1", {n}, record.parent1);
  g.write_dataset<std::int64_t>("parent2", {n}, record.parent2);
  g.write_dataset<std::int64_t>("species", {n}, record.species);
  g.write_dataset<std::uint8_t>("status", {n}, record.status);
  g.write_dataset<double>("fitness", {n}, record.fitness);
  g.write_dataset<std::int32_t>("voxels", {n}, record.voxels);
  g.write_dataset<std::int32_t>("chambers", {n}, record.chambers);
  g.write_dataset<double>("wall_seconds", {n}, record.wall_seconds);
  g.write_dataset<std::int32_t>("worker_rank", {n}, record.worker_rank);
  g.write_dataset<std::int64_t>("reused_from", {n},
                                record.reused_from.empty()
                                    ? std::vector<std::int64_t>(record.size(), kNotReused)
                                    : record.reused_from);
  g.write_byte_rows("genome", record.genome);
  g.write_dataset<double>("components",
                          {n, static_cast<hsize_t>(record.units),
                           static_cast<hsize_t>(record.component_columns.size())},
                          record.components)
      .write_string_attribute(kColumnsAttribute, join_columns(record.component_columns),
                              h5::Charset::ascii);
  if (record.has_learning()) {
    g.write_dataset<double>("fitness_before", {n}, record.fitness_before);
    g.write_dataset<std::int64_t>("learn_evaluations", {n}, record.learn_evaluations);
    g.write_byte_rows("learned_genome", record.learned_genome);
    g.write_dataset<double>("learning_curve", {n, static_cast<hsize_t>(record.learning_points)},
                            record.learning_curve);
  }
  if (!record.strategy.empty()) write_strategy_group(g, record.strategy);
  g.write_attribute<double>("best", record.best);
  g.write_attribute<double>("mean", record.mean);
  g.write_attribute<double>("sd", record.sd);
  g.write_attribute<std::int64_t>("species_count", record.species_count);
  g.write_attribute<std::int64_t>("evaluations", record.evaluations);
  g.write_attribute<double>("eval_wall_seconds", record.eval_wall_seconds);
  g.write_string_attribute("digest", hash_hex(generation_digest(record)), Charset::utf8);
}

}  // namespace softevo::io::detail
