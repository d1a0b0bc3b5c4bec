// See replay.hpp.
#include "validation/replay.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "common/round_trip.hpp"
#include "io/archive.hpp"
#include "physics/revision.hpp"
#include "worker/evaluate.hpp"

namespace softevo::validation {
namespace {

// Bit-identical doubles: NaN equals a NaN of the same bits, +0 differs from -0.
bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// "" when every component the task has and the archive recorded has the same bits.
std::string compare_components(const master::GenomeOutcome& outcome,
                               const motion::ArchivedIndividual& archived,
                               const tasks::Task& task) {
  const std::size_t rows = outcome.components.size();
  const std::size_t archived_width = archived.component_columns.size();
  if (rows * archived_width != archived.components.size())
    return "component rows " + std::to_string(rows) + " != archived " +
           std::to_string(archived.components.size() / std::max<std::size_t>(1, archived_width));
  const std::vector<std::string> columns = tasks::component_columns(task);
  for (std::size_t d = 0; d < rows; ++d) {
    const std::vector<double> row = tasks::component_row(outcome.components[d]);
    for (std::size_t k = 0; k < columns.size(); ++k) {
      const auto at = std::find(archived.component_columns.begin(),
                                archived.component_columns.end(), columns[k]);
      if (at == archived.component_columns.end()) continue;
      const double stored =
          archived.components[d * archived_width +
                              static_cast<std::size_t>(at - archived.component_columns.begin())];
      if (!same_bits(row[k], stored) && !(std::isnan(row[k]) && std::isnan(stored))) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "component %s of unit %zu: %s != archived %s",
                      columns[k].c_str(), d, round_trip(row[k]).c_str(),
                      round_trip(stored).c_str());
        return buf;
      }
    }
  }
  return "";
}

}  // namespace

ReplaySelection select_for_replay(const std::string& archive_path,
                                  std::optional<std::int64_t> generation,
                                  std::optional<std::int64_t> id, bool all, bool verify) {
  ReplaySelection selection;
  selection.archive_path = archive_path;
  if (all) {
    if (id) throw std::invalid_argument("replay: --all excludes --id and --best");
    selection.individuals = motion::archived_generation(archive_path, generation);
  } else {
    selection.individuals.push_back(motion::archived_individual(archive_path, generation, id));
  }
  if (selection.individuals.empty())
    throw std::runtime_error(archive_path + ": generation has no individual");
  const Config& config = selection.individuals.front().config;
  selection.config_hash = config_hash(config);

  // The recorded hash must belong to the config text, or we would replay another experiment
  // than the one that ran.
  const io::RunInfo info = io::Archive(archive_path).info();
  if (info.config_hash != hash_hex(selection.config_hash))
    throw std::runtime_error(archive_path + ": config_hash attribute " + info.config_hash +
                             " does not match the archived config text (hash " +
                             hash_hex(selection.config_hash) + ")");
  // Bits are only comparable within one physics revision (physics/revision.hpp).
  if (info.physics_revision != physics::kPhysicsRevision) {
    const std::string what = archive_path + ": simulated with physics revision " +
                             std::to_string(info.physics_revision) +
                             ", this build simulates revision " +
                             std::to_string(physics::kPhysicsRevision) + " (physics/revision.hpp)";
    if (verify)
      throw std::runtime_error(what +
                               ": fitness bits cannot match; --verify needs a build of the "
                               "archive's revision");
    selection.revision_note = what + "; fitness values will differ slightly";
  }
  return selection;
}

ReplayResult replay(const motion::ArchivedIndividual& individual, const tasks::Task& task,
                    std::uint64_t config_hash, bool verify) {
  master::GenerationScheduler scheduler(individual.generation, {individual.id}, task);
  while (auto unit = scheduler.next()) {
    EvalRequest request;
    request.config_hash = config_hash;
    request.generation = individual.generation;
    request.genome_id = individual.id;
    request.unit = unit->unit;
    request.genome = individual.genome;
    scheduler.complete(worker::evaluate(individual.config, task, config_hash, request));
  }
  ReplayResult result;
  result.outcome = scheduler.outcomes().at(0);
  result.verifiable = individual.status != static_cast<std::uint8_t>(EvalStatus::timeout);
  if (!verify || !result.verifiable) return result;

  if (static_cast<std::uint8_t>(result.outcome.status) != individual.status) {
    result.mismatch = std::string("status ") + to_string(result.outcome.status) + " != archived " +
                      to_string(static_cast<EvalStatus>(individual.status));
  } else if (!same_bits(result.outcome.fitness, individual.fitness)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "fitness %s != archived %s (bits differ)",
                  round_trip(result.outcome.fitness).c_str(),
                  round_trip(individual.fitness).c_str());
    result.mismatch = buf;
  } else if (!individual.components.empty()) {
    result.mismatch = compare_components(result.outcome, individual, task);
  }
  return result;
}

}  // namespace softevo::validation
