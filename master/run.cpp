#include "master/run.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <exception>
#include <filesystem>
#include <numeric>

#include "common/config_identity.hpp"
#include "common/version.hpp"
#include "evo/genome.hpp"
#include "master/archive_check.hpp"
#include "master/run_state.hpp"
#include "master/signals.hpp"
#include "physics/revision.hpp"
#include "physics/work_limits.hpp"
#include "tasks/task.hpp"

namespace softevo::master {

// The run archive (io/archive.hpp) is what this loop writes.
using io::append_generation;
using io::Archive;
using io::ArchiveError;
using io::check_output_path;
using io::Checkpoint;
using io::create_archive;
using io::finish_archive;
using io::fitness_stats;
using io::FitnessStats;
using io::GenerationRecord;
using io::remove_archive_debris;
using io::RunInfo;
using io::StatsRow;
using io::update_run_info;

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

int task_inputs(const Config& config) {
  return tasks::make_task(config)->controller_inputs();
}

// What to do about an archive that fails its checks.
std::string repair_hint(const std::string& out, const ArchiveCheck& check) {
  const std::string kept =
      check.consistent_generations == 0
          ? "no generation passes them"
          : "generations 0-" + std::to_string(check.consistent_generations - 1) + " pass them";
  return "(" + kept + "; `softevo repair " + out +
         " -o FIXED.h5` copies those into a new file to resume from)";
}

// generations_done of the archive at `out`, -1 if it cannot be read.
std::int64_t generations_on_disk(const std::string& out) {
  try {
    return Archive(out).info().generations_done;
  } catch (const std::exception&) {
    return -1;
  }
}

// Archives generation `record.generation`; `info` counts it only once it is on disk. A failed
// write (full disk, I/O error) leaves the archive and `info` at the previous generation, so the
// error path's state change and a later --resume see a consistent archive: a failure loses at
// most the generation in flight.
void commit_generation(const std::string& out, RunInfo& info, const GenerationRecord& record,
                       const StatsRow& stats, const Checkpoint& checkpoint,
                       const io::WriteStepHook& fault) {
  RunInfo next = info;
  next.generations_done = record.generation + 1;
  try {
    append_generation(out, next, record, stats, checkpoint, fault);
  } catch (const ArchiveError& e) {
    // A failure after the rename (syncing the directory) has left the new archive in place:
    // what is on disk, not what was intended, is what the state change and --resume build on.
    if (generations_on_disk(out) == next.generations_done) info = next;
    const std::string kept = info.generations_done == 0
                                 ? "no generation yet"
                                 : "generations 0-" + std::to_string(info.generations_done - 1);
    throw RunError("generation " + std::to_string(record.generation) + " could not be archived (" +
                   out + " still holds " + kept +
                   " and can be continued with --resume): " + e.what());
  }
  info = next;
}

}  // namespace

std::string iso8601_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string host_name() {
  char buf[256] = {0};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

bool LocalExecutor::evaluate(GenerationScheduler& scheduler,
                             const std::function<EvalRequest(const WorkUnit&)>& make_request,
                             ProgressReporter& progress) {
  while (auto unit = scheduler.next()) {
    if (stop_requested() == StopRequest::now) return false;
    EvalResult result = evaluate_(make_request(*unit));
    // A stop-now during the evaluation may have abandoned it: never archive that result.
    if (stop_requested() == StopRequest::now) return false;
    result.worker_rank = 0;
    scheduler.complete(result);
    progress.unit_done(scheduler.units_done(), scheduler.units_total());
  }
  return true;
}

PreparedRun prepare_run(const Config& config, const RunOptions& options, int ranks) {
  if (options.resume && options.overwrite)
    throw StartupError(options.out_path +
                       ": --resume (continue this archive) and --overwrite (replace it) "
                       "contradict each other; give one of them");
  // Every evaluation of the run stays within the work limits: refused here, not as a run of
  // failed evaluations (or, before the limits, of days per evaluation).
  try {
    physics::check_run_work(config);
  } catch (const physics::WorkLimitError& e) {
    throw ConfigError(e.what());
  }
  PreparedRun run;
  run.config = config;
  run.config_text = canonical_text(config);
  run.config_hash = config_hash(config);
  run.options = options;
  const std::string& out = options.out_path;
  const std::string hash = hash_hex(run.config_hash);

  RunInfo& info = run.info;
  info.version = kVersion;
  info.git_commit = kGitCommit;
  info.physics_revision = physics::kPhysicsRevision;
  info.seed = config.run.seed;
  info.ranks = ranks;
  info.host = options.host.empty() ? host_name() : options.host;
  info.start_time = iso8601_now();
  info.config_hash = hash;
  info.experiment_hash = hash_hex(experiment_hash(config));
  info.experiment = experiment_name(config);
  info.state = "running";

  std::error_code ec;
  try {
    check_output_path(out);
  } catch (const ArchiveError& e) {
    throw StartupError(e.what());
  }
  try {
    run.lock.emplace(out, info.host);
  } catch (const io::RunLockError& e) {
    throw StartupError(e.what());
  }
  // Only now, under the lock, is "does the archive exist" an answer that stays true.
  const bool exists = fs::exists(out, ec);
  if (exists && options.resume) {
    try {
      const Archive archive(out);
      const ArchiveCheck check = check_archive(archive);
      if (!check.ok())
        throw StartupError(out + ": cannot resume: the archive fails its integrity checks:\n" +
                           check.describe(out) + repair_hint(out, check));
      const RunInfo old = archive.info();
      // The experiment (everything but run length and seed) must be the archive's; the run
      // length may grow: the generations evolve the same whatever the target.
      const std::string old_text = archive.config_text();
      if (experiment_text(old_text) != experiment_text(run.config_text))
        throw StartupError(out + ": cannot resume: the archive was written with experiment hash " +
                           hash_hex(experiment_hash_of_text(old_text)) + ", this run has " +
                           info.experiment_hash +
                           " (use the same config file and --set overrides; only --generations "
                           "may differ)");
      if (old.seed != config.run.seed)
        throw StartupError(out + ": cannot resume: the archive was written with --seed " +
                           std::to_string(old.seed) + ", this run has --seed " +
                           std::to_string(config.run.seed) +
                           " (another seed is another run: give it its own --out)");
      run.run_length_changed = old_text != run.config_text;
      if (old.physics_revision != physics::kPhysicsRevision)
        throw StartupError(
            out + ": cannot resume: the archive was simulated with physics revision " +
            std::to_string(old.physics_revision) + ", this build simulates revision " +
            std::to_string(physics::kPhysicsRevision) +
            " (physics/revision.hpp); finish it with a build of its revision or "
            "start a new run");
      info.start_time = old.start_time;
      info.generations_done = old.generations_done;
      // The lock is ours now: a "running" archive was left by a run that died.
      run.previous_run = previous_run_note(old, std::nullopt, config.run.generations);
      if (old.generations_done >= config.run.generations) {
        // Nothing to evaluate: the archive keeps the config it was written with.
        run.already_complete = true;
        run.run_length_changed = false;
        run.info = old;
        return run;
      }
      const std::optional<Checkpoint> cp = archive.checkpoint();
      if (old.generations_done > 0) {
        if (!cp || cp->generation != old.generations_done)
          throw StartupError(out + ": cannot resume: no checkpoint for generation " +
                             std::to_string(old.generations_done));
        run.population.emplace(
            evo::Population::deserialize(cp->population, config, task_inputs(config)));
        if (run.population->generation() != cp->generation)
          throw StartupError(out + ": cannot resume: checkpoint population is at generation " +
                             std::to_string(run.population->generation()) + ", expected " +
                             std::to_string(cp->generation));
      }
      run.resumed = true;
    } catch (const ArchiveError& e) {
      throw StartupError(std::string("cannot resume: ") + e.what());
    } catch (const StartupError&) {
      throw;
    } catch (const std::exception& e) {
      throw StartupError(out + ": cannot resume: bad checkpoint: " + e.what());
    }
  } else if (exists && !options.overwrite) {
    throw StartupError(out +
                       " exists: pass --resume to continue it, --overwrite to replace it, or "
                       "choose another --out");
  }
  if (!run.population)
    run.population.emplace(evo::Population::create(config, task_inputs(config),
                                                   static_cast<std::uint64_t>(config.run.seed)));
  return run;
}

RunOutcome execute_run(PreparedRun& run, UnitExecutor& executor, ProgressReporter& progress) {
  if (run.already_complete) {
    // Every generation is archived, but a run killed before its end (or a full disk then) left
    // the state unset or the archive unpacked: the end of the run is done now.
    const std::string& out = run.options.out_path;
    try {
      remove_archive_debris(out);
      if (run.info.state != "complete" || !Archive(out).self_contained()) {
        run.info.state = "complete";
        if (run.info.end_time.empty()) run.info.end_time = iso8601_now();
        finish_archive(out, run.info, run.options.archive_fault);
      }
      remove_archive_debris(out);
    } catch (const std::exception& e) {
      throw RunError(std::string("the end of the complete run could not be recorded (the archive "
                                 "holds every generation and is readable as it is): ") +
                     e.what());
    }
    return RunOutcome::already_complete;
  }
  const Config& config = run.config;
  const std::string& out = run.options.out_path;
  RunInfo& info = run.info;
  info.ranks = executor.ranks();
  bool archive_written = false;
  bool state_recorded = false;
  try {
    // Debris of a run killed while writing (SIGKILL, crash): its temporaries and the segment it
    // wrote before the root that would have named it. We hold the run lock: no one else writes.
    remove_archive_debris(out);
    if (run.resumed) {
      info.state = "running";
      info.end_time.clear();
      if (run.run_length_changed)
        io::update_run_config(out, info, run.config_text, run.options.archive_fault);
      else
        update_run_info(out, info, run.options.archive_fault);
    } else {
      create_archive(out, info, run.config_text, run.options.archive_fault);
    }
    archive_written = true;
    remove_archive_debris(out);  // the segments of the archive an --overwrite replaced

    evo::Population& population = *run.population;
    const std::unique_ptr<tasks::Task> task = tasks::make_task(config);
    RunOutcome outcome = RunOutcome::complete;
    while (population.generation() < config.run.generations) {
      if (stop_requested() != StopRequest::none) {
        outcome = RunOutcome::interrupted;
        break;
      }
      const auto t_generation = Clock::now();
      const std::int64_t g = population.generation();
      const std::vector<evo::Individual>& members = population.members();
      std::vector<std::vector<std::uint8_t>> encoded(members.size());
      std::vector<std::int64_t> ids(members.size());
      for (std::size_t i = 0; i < members.size(); ++i) {
        encoded[i] = evo::encode_genome(members[i].genome);
        ids[i] = members[i].id;
      }
      GenerationScheduler scheduler(g, ids, *task);
      const auto make_request = [&](const WorkUnit& unit) {
        EvalRequest r;
        r.config_hash = run.config_hash;
        r.generation = g;
        r.genome_id = unit.genome_id;
        r.unit = unit.unit;
        r.genome = encoded[unit.member];
        return r;
      };
      progress.generation_started(g, scheduler.units_total());
      const auto t_eval = Clock::now();
      if (!executor.evaluate(scheduler, make_request, progress)) {
        outcome = RunOutcome::interrupted;
        break;
      }
      const double eval_seconds = seconds_since(t_eval);
      if (config.run.on_failure == "abort") {
        const auto failures = scheduler.failures();
        if (!failures.empty()) {
          const EvalResult& f = *failures.front();
          throw RunError("genome " + std::to_string(f.genome_id) + " (generation " +
                         std::to_string(g) + ", unit " + std::to_string(f.unit) +
                         ") failed on rank " + std::to_string(f.worker_rank) + ": " + f.message +
                         " (run.on_failure = abort)");
        }
      }
      const std::vector<GenomeOutcome> outcomes = scheduler.outcomes();

      // Archive rows in id order.
      std::vector<std::size_t> order(members.size());
      std::iota(order.begin(), order.end(), std::size_t{0});
      std::sort(order.begin(), order.end(),
                [&](std::size_t a, std::size_t b) { return members[a].id < members[b].id; });
      GenerationRecord rec;
      rec.generation = g;
      rec.units = task->units();
      rec.component_columns = tasks::component_columns(*task);
      std::vector<evo::Evaluation> evaluations;
      evaluations.reserve(members.size());
      for (std::size_t i : order) {
        const evo::Individual& m = members[i];
        const GenomeOutcome& o = outcomes[i];
        rec.id.push_back(m.id);
        rec.parent1.push_back(m.parent1);
        rec.parent2.push_back(m.parent2);
        rec.species.push_back(m.species);
        rec.status.push_back(static_cast<std::uint8_t>(o.status));
        rec.fitness.push_back(o.fitness);
        rec.voxels.push_back(o.voxels);
        rec.chambers.push_back(o.chambers);
        rec.wall_seconds.push_back(o.wall_seconds);
        rec.worker_rank.push_back(o.worker_rank);
        rec.genome.push_back(encoded[i]);
        for (const UnitFitness& u : o.components) {
          const std::vector<double> row = tasks::component_row(u);
          rec.components.insert(rec.components.end(), row.begin(), row.end());
        }
        evaluations.push_back(evo::Evaluation{m.id, o.fitness, o.status != EvalStatus::ok});
      }
      const FitnessStats fs = fitness_stats(rec.fitness);
      rec.best = fs.best;
      rec.mean = fs.mean;
      rec.sd = fs.sd;
      rec.species_count = static_cast<std::int64_t>(population.species_count());
      rec.evaluations = static_cast<std::int64_t>(scheduler.units_total());
      rec.eval_wall_seconds = eval_seconds;

      try {
        population.advance(evaluations);
      } catch (const std::exception& e) {
        throw RunError("generation " + std::to_string(g) + ": reproduction failed: " + e.what());
      }
      StatsRow stats{static_cast<double>(g),
                     rec.best,
                     rec.mean,
                     rec.sd,
                     static_cast<double>(rec.species_count),
                     eval_seconds > 0 ? static_cast<double>(rec.evaluations) / eval_seconds : 0.0};
      commit_generation(out, info, rec, stats,
                        Checkpoint{population.generation(), population.serialize()},
                        run.options.archive_fault);
      GenerationSummary summary{g,
                                rec.best,
                                rec.mean,
                                rec.species_count,
                                rec.evaluations,
                                eval_seconds,
                                seconds_since(t_generation),
                                {},
                                0.0,
                                task->fitness_unit()};
      for (std::size_t i = 0; i < rec.size(); ++i) {
        if (rec.status[i] < summary.status_counts.size()) ++summary.status_counts[rec.status[i]];
        if (rec.status[i] == static_cast<std::uint8_t>(EvalStatus::ok))
          summary.max_abs_ok_fitness =
              std::max(summary.max_abs_ok_fitness, std::fabs(rec.fitness[i]));
      }
      progress.generation_finished(summary);
      if (stop_requested() != StopRequest::none &&
          population.generation() < config.run.generations) {
        outcome = RunOutcome::interrupted;
        break;
      }
    }
    info.state = outcome == RunOutcome::complete ? "complete" : "interrupted";
    info.end_time = iso8601_now();
    try {
      finish_archive(out, info, run.options.archive_fault);
    } catch (const std::exception& e) {
      // Every generation is on disk; only packing them into one file failed (a full disk: the
      // pack needs room for a second copy). The state is still worth recording.
      update_run_info(out, info, run.options.archive_fault);
      state_recorded = true;
      throw RunError(out + ": the run's results are archived (state " + info.state +
                     "), but packing them into one file failed; the archive is readable as it "
                     "is, and --resume packs it: " +
                     e.what());
    }
    return outcome;
  } catch (const std::exception& e) {
    // Leave the archive marked as not running, in one file if possible (best effort: it already
    // holds the last consistent checkpoint whatever happens here).
    if (archive_written && !state_recorded) {
      info.state = "interrupted";
      info.end_time = iso8601_now();
      try {
        finish_archive(out, info, run.options.archive_fault);
      } catch (...) {
        try {
          update_run_info(out, info, run.options.archive_fault);
        } catch (...) {
        }
      }
    }
    if (dynamic_cast<const RunError*>(&e) != nullptr) throw;
    throw RunError(e.what());
  }
}

}  // namespace softevo::master
