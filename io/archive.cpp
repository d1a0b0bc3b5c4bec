// The run archive (schema: docs/archive.md) over the RAII layer of io/h5.hpp: its records, their
// limits and the output check. The writer is archive_writer.cpp with its parts (listed in
// archive_writer_internal.hpp), the reader archive_reader.cpp, the digests archive_digest.cpp.
// Every failure, HDF5 or file system, becomes an ArchiveError naming the file and the object.
#include "io/archive.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/safe_write.hpp"
#include "io/archive_internal.hpp"

namespace softevo::io {
namespace {
namespace fs = std::filesystem;
}  // namespace

std::string generation_group_name(std::int64_t generation) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06lld", static_cast<long long>(generation));
  return buf;
}

const std::vector<std::string>& legacy_component_columns() {
  static const std::vector<std::string> columns = {
      "fitness", "distance", "path_length", "angle_error", "perpendicular_penalty", "status"};
  return columns;
}

namespace detail {

std::string join_columns(const std::vector<std::string>& columns) {
  std::string out;
  for (std::size_t i = 0; i < columns.size(); ++i) out += (i ? "," : "") + columns[i];
  return out;
}

std::vector<std::string> split_columns(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    out.push_back(text.substr(start, comma - start));
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

}  // namespace detail

void GenerationRecord::check() const {
  const std::size_t n = id.size();
  const std::string at = "generation " + std::to_string(generation) + ": ";
  const auto beyond = [&](const std::string& what, std::int64_t limit) {
    return ArchiveError(at + what + " beyond the limit of " + std::to_string(limit) +
                        " (docs/archive.md \"Limits\")");
  };
  if (generation < 0 || generation >= ArchiveLimits::generations)
    throw beyond("generation number", ArchiveLimits::generations - 1);
  if (n > static_cast<std::size_t>(ArchiveLimits::individuals))
    throw beyond(std::to_string(n) + " rows", ArchiveLimits::individuals);
  if (units > ArchiveLimits::units)
    throw beyond(std::to_string(units) + " work units", ArchiveLimits::units);
  if (component_columns.size() > static_cast<std::size_t>(ArchiveLimits::component_columns))
    throw beyond(std::to_string(component_columns.size()) + " component columns",
                 ArchiveLimits::component_columns);
  for (const std::vector<std::uint8_t>& g : genome)
    if (g.size() > static_cast<std::size_t>(ArchiveLimits::genome_bytes))
      throw beyond("a genome of " + std::to_string(g.size()) + " bytes",
                   ArchiveLimits::genome_bytes);
  const bool same =
      parent1.size() == n && parent2.size() == n && species.size() == n && status.size() == n &&
      fitness.size() == n && voxels.size() == n && chambers.size() == n &&
      wall_seconds.size() == n && worker_rank.size() == n && genome.size() == n && units >= 1 &&
      (reused_from.empty() || reused_from.size() == n) && !component_columns.empty() &&
      components.size() == n * static_cast<std::size_t>(units) * component_columns.size();
  const bool learning_same =
      fitness_before.empty()
          ? learn_evaluations.empty() && learned_genome.empty() && learning_curve.empty()
          : fitness_before.size() == n && learn_evaluations.size() == n &&
                learned_genome.size() == n && learning_points >= 1 &&
                learning_curve.size() == n * static_cast<std::size_t>(learning_points);
  const auto table_ok = [](const StrategyTable& t) {
    return t.columns.size() <= static_cast<std::size_t>(ArchiveLimits::strategy_columns) &&
           (t.columns.empty() ? t.values.empty() : t.values.size() % t.columns.size() == 0);
  };
  const bool strategy_same =
      strategy.empty() ||
      (table_ok(strategy.rows) && table_ok(strategy.map) && strategy.rows.rows() == n &&
       strategy.map.rows() <= static_cast<std::size_t>(ArchiveLimits::map_cells) &&
       strategy.metrics.size() <= static_cast<std::size_t>(ArchiveLimits::strategy_columns));
  if (!same || !learning_same || !strategy_same)
    throw ArchiveError("generation " + std::to_string(generation) +
                       ": record columns have different lengths");
  for (const std::string& c : component_columns)
    if (c.empty() || c.find(',') != std::string::npos)
      throw ArchiveError("generation " + std::to_string(generation) + ": component column '" + c +
                         "' is empty or contains a comma");
  for (std::size_t i = 1; i < n; ++i)
    if (id[i] <= id[i - 1])
      throw ArchiveError("generation " + std::to_string(generation) +
                         ": rows are not sorted by ascending unique id");
}

FitnessStats fitness_stats(const std::vector<double>& fitness) {
  FitnessStats s;
  if (fitness.empty()) return s;
  s.best = fitness[0];
  double sum = 0.0;
  for (double f : fitness) {
    s.best = std::max(s.best, f);
    sum += f;
  }
  s.mean = sum / static_cast<double>(fitness.size());
  double ss = 0.0;
  for (double f : fitness) ss += (f - s.mean) * (f - s.mean);
  s.sd = std::sqrt(ss / static_cast<double>(fitness.size()));
  return s;
}

void check_output_path(const std::string& path) {
  if (path.empty()) throw ArchiveError("output path is empty");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw ArchiveError(path + ": is a directory, not a file");
  const std::string dir = directory_of(path);
  if (!fs::is_directory(dir, ec))
    throw ArchiveError(path + ": output directory " + dir + " does not exist");
  try {
    // The archive is replaced like any output (common/safe_write.hpp): a symlink or special
    // file is refused now, before a run starts, rather than at its first write.
    const AtomicOutput probe(path, Overwrite::replace);
  } catch (const OutputFileError& e) {
    throw ArchiveError(e.what());
  }
}

}  // namespace softevo::io
