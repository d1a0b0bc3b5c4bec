// `softevo replay`: evaluate archived individuals again and, with --verify, check that the
// result is bit-identical to what the run archived.
//
// Record inputs, not outputs (ARCHITECTURE.md section 1): the archive keeps the resolved config
// text and every encoded genome, so an evaluation can be repeated exactly. Replay goes through
// the same code path as a run: worker::evaluate per work unit of the archived config's task and
// master::GenerationScheduler to combine the units as the task does. A difference in
// fitness bits, status or any archived fitness component is a mismatch (exit code 1).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "io/archive.hpp"
#include "master/scheduler.hpp"
#include "motion/robot_source.hpp"
#include "physics/revision.hpp"
#include "tasks/task.hpp"
#include "tools/commands.hpp"
#include "worker/evaluate.hpp"

namespace softevo::cli {

using motion::archived_generation;
using motion::archived_individual;
using motion::ArchivedIndividual;

namespace {

struct ReplayArgs {
  std::string archive;
  std::optional<std::int64_t> generation;
  std::optional<std::int64_t> id;
  bool best = false;
  bool verify = false;
  bool all = false;
};

struct Replayed {
  master::GenomeOutcome outcome;
  std::string mismatch;  // "" = identical (only filled when verifying)
};

Replayed replay_one(const ArchivedIndividual& ind, const tasks::Task& task, std::uint64_t hash,
                    bool verify) {
  master::GenerationScheduler scheduler(ind.generation, {ind.id}, task);
  while (auto unit = scheduler.next()) {
    EvalRequest request;
    request.config_hash = hash;
    request.generation = ind.generation;
    request.genome_id = ind.id;
    request.unit = unit->unit;
    request.genome = ind.genome;
    scheduler.complete(worker::evaluate(ind.config, task, hash, request));
  }
  Replayed r;
  r.outcome = scheduler.outcomes().at(0);
  if (!verify) return r;
  const auto status = static_cast<std::uint8_t>(r.outcome.status);
  if (status != ind.status) {
    r.mismatch = std::string("status ") + to_string(r.outcome.status) + " != archived " +
                 to_string(static_cast<EvalStatus>(ind.status));
  } else if (!same_bits(r.outcome.fitness, ind.fitness)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "fitness %.17g != archived %.17g (bits differ)",
                  r.outcome.fitness, ind.fitness);
    r.mismatch = buf;
  } else if (!ind.components.empty()) {
    // By name: every component the task has and the archive recorded (an archive of an older
    // build may lack some, e.g. direction_deg, and have others, e.g. the gait's path_length).
    const std::size_t rows = r.outcome.components.size();
    const std::size_t archived_width = ind.component_columns.size();
    if (rows * archived_width != ind.components.size()) {
      r.mismatch = "component rows " + std::to_string(rows) + " != archived " +
                   std::to_string(ind.components.size() / std::max<std::size_t>(1, archived_width));
    }
    const std::vector<std::string> columns = tasks::component_columns(task);
    for (std::size_t d = 0; d < rows && r.mismatch.empty(); ++d) {
      const std::vector<double> row = tasks::component_row(r.outcome.components[d]);
      for (std::size_t k = 0; k < columns.size() && r.mismatch.empty(); ++k) {
        const auto at =
            std::find(ind.component_columns.begin(), ind.component_columns.end(), columns[k]);
        if (at == ind.component_columns.end()) continue;
        const double archived =
            ind.components[d * archived_width +
                           static_cast<std::size_t>(at - ind.component_columns.begin())];
        if (!same_bits(row[k], archived) && !(std::isnan(row[k]) && std::isnan(archived))) {
          char buf[200];
          std::snprintf(buf, sizeof buf, "component %s of unit %zu: %.17g != archived %.17g",
                        columns[k].c_str(), d, row[k], archived);
          r.mismatch = buf;
        }
      }
    }
  }
  return r;
}

int run_replay(const ReplayArgs& args) {
  std::vector<ArchivedIndividual> selected;
  if (args.all) {
    if (args.id || args.best) throw std::invalid_argument("replay: --all excludes --id and --best");
    selected = archived_generation(args.archive, args.generation);
  } else {
    selected.push_back(archived_individual(args.archive, args.generation, args.id));
  }
  if (selected.empty()) throw std::runtime_error(args.archive + ": generation has no individual");
  const Config& config = selected.front().config;
  const std::uint64_t hash = config_hash(config);
  {
    // The archive's recorded hash must belong to its config text, or we would replay another
    // experiment than the one that ran.
    const io::Archive archive(args.archive);
    const io::RunInfo info = archive.info();
    const std::string& recorded = info.config_hash;
    if (recorded != hash_hex(hash)) {
      throw std::runtime_error(args.archive + ": config_hash attribute " + recorded +
                               " does not match the archived config text (hash " + hash_hex(hash) +
                               ")");
    }
    // Bits are only comparable within one physics revision (physics/revision.hpp).
    const int revision = info.physics_revision;
    if (revision != physics::kPhysicsRevision) {
      const std::string what = args.archive + ": simulated with physics revision " +
                               std::to_string(revision) + ", this build simulates revision " +
                               std::to_string(physics::kPhysicsRevision) +
                               " (physics/revision.hpp)";
      if (args.verify)
        throw std::runtime_error(what +
                                 ": fitness bits cannot match; --verify needs a build of the "
                                 "archive's revision");
      std::fprintf(stderr, "note: %s; fitness values will differ slightly\n", what.c_str());
    }
  }
  const std::unique_ptr<tasks::Task> task = tasks::make_task(config);
  int identical = 0, mismatched = 0, unverifiable = 0;
  for (const ArchivedIndividual& ind : selected) {
    // A timeout depends on the wall clock, not on the inputs: nothing to compare bit for bit.
    const bool can_verify = ind.status != static_cast<std::uint8_t>(EvalStatus::timeout);
    const Replayed r = replay_one(ind, *task, hash, args.verify && can_verify);
    std::printf("generation %lld id %lld: fitness %.17g status %s (archived %.17g %s)",
                static_cast<long long>(ind.generation), static_cast<long long>(ind.id),
                r.outcome.fitness, to_string(r.outcome.status), ind.fitness,
                to_string(static_cast<EvalStatus>(ind.status)));
    if (args.verify) {
      if (!can_verify) {
        ++unverifiable;
        std::printf("  SKIPPED (archived timeout is wall-clock dependent)\n");
      } else if (r.mismatch.empty()) {
        ++identical;
        std::printf("  IDENTICAL\n");
      } else {
        ++mismatched;
        std::printf("  MISMATCH: %s\n", r.mismatch.c_str());
      }
    } else {
      std::printf("\n");
    }
  }
  if (args.verify) {
    std::printf("verify %s generation %lld: %d identical, %d mismatched, %d skipped of %zu\n",
                args.archive.c_str(), static_cast<long long>(selected.front().generation),
                identical, mismatched, unverifiable, selected.size());
    return mismatched == 0 ? kExitOk : kExitMismatch;
  }
  return kExitOk;
}

}  // namespace

void register_replay(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "replay",
      "re-simulate archived individuals from their genome and the archived config; --verify "
      "checks bit-identity with the archived fitness (exit 1 on mismatch)");
  auto args = std::make_shared<ReplayArgs>();
  cmd->add_option("RUN", args->archive, "run archive (softevo.run/1 HDF5)")->required();
  cmd->add_option("--generation", args->generation, "generation (default: the last archived)");
  auto* id_opt = cmd->add_option("--id", args->id, "individual id");
  auto* best_opt =
      cmd->add_flag("--best", args->best, "the generation's best individual (the default)");
  id_opt->excludes(best_opt);
  cmd->add_flag("--verify", args->verify,
                "compare fitness, status and components bit for bit with the archive");
  cmd->add_flag("--all", args->all, "every individual of the generation (audit)")
      ->excludes(id_opt)
      ->excludes(best_opt);
  cmd->callback([&exit_code, args] { exit_code = run_replay(*args); });
}

}  // namespace softevo::cli
