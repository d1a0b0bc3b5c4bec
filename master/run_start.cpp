// Start-up of a run (master/run.hpp prepare_run): the output path, the run lock, --resume of
// an archive (its checks, its config, its checkpoint) or a new search strategy.
#include <unistd.h>

#include <ctime>
#include <exception>
#include <filesystem>

#include "common/config_identity.hpp"
#include "common/safe_write.hpp"
#include "common/version.hpp"
#include "master/archive_check.hpp"
#include "master/run.hpp"
#include "master/run_state.hpp"
#include "physics/revision.hpp"
#include "physics/work_limits.hpp"
#include "tasks/task.hpp"

namespace softevo::master {

using io::Archive;
using io::ArchiveError;
using io::check_output_path;
using io::Checkpoint;
using io::finish_archive;
using io::remove_archive_debris;
using io::RunInfo;
using io::RunState;

namespace {

namespace fs = std::filesystem;

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

// --resume with another search strategy than the archive's is refused naming both (the config
// check that follows would name the key only).
void check_same_strategy(const std::string& out, const std::string& archive_text,
                         const Config& config, const OptionNames& names) {
  const std::string archived = archived_strategy(archive_text);
  const std::string wanted = to_string(config.search.strategy);
  if (archived != wanted) refuse_other_strategy(out, archived, wanted, names);
}

}  // namespace

std::string archived_strategy(const std::string& config_text) {
  std::string archived = "neat";  // texts of NEAT runs have no search.strategy
  for (const auto& [key, value] : canonical_entries(config_text))
    if (key == "search.strategy") archived = value.substr(1, value.size() - 2);
  return archived;
}

void refuse_other_strategy(const std::string& out, const std::string& archived,
                           const std::string& wanted, const OptionNames& names) {
  throw StartupError(out + ": cannot resume: the archive was evolved by search strategy \"" +
                     archived + "\", this run asks for \"" + wanted +
                     "\" (search.strategy); a run keeps its strategy: leave out " + names.config +
                     " and " + names.overrides + ", or give the new strategy another " + names.out);
}

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

PreparedRun prepare_run(const Config& config, const RunOptions& options, int ranks) {
  if (options.resume && options.overwrite)
    throw StartupError(options.out_path + ": " + options.names.resume +
                       " (continue this archive) and " + options.names.overwrite +
                       " (replace it) contradict each other; give one of them");
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
  info.git_commit = git_commit();
  info.physics_revision = physics::kPhysicsRevision;
  info.seed = config.run.seed;
  info.ranks = ranks;
  info.program = options.program;
  info.host = options.host.empty() ? host_name() : options.host;
  info.start_time = iso8601_now();
  info.config_hash = hash;
  info.experiment_hash = hash_hex(experiment_hash(config));
  info.experiment = experiment_name(config);
  info.state = RunState::running;

  std::error_code ec;
  // Why the archive cannot be written, when a --resume finds it on storage it may not write
  // (read-only file system, no write permission): a complete, packed archive needs no write
  // and is reported complete (exit 0, docs/archive.md); anything else fails with this reason.
  std::optional<std::string> unwritable;
  try {
    check_output_path(out);
  } catch (const ArchiveError& e) {
    if (!(options.resume && fs::exists(out, ec) && ::access(directory_of(out).c_str(), W_OK) != 0))
      throw StartupError(e.what());
    unwritable = e.what();
  }
  try {
    // No lock without write access: no run can write the archive there either.
    if (!unwritable) run.lock.emplace(out, info.host);
  } catch (const io::RunLockError& e) {
    throw StartupError(e.what());
  }
  // A start that fails from here on leaves no lock file it created (issue 29: a failed --seeds
  // job left one per run it had prepared). Returns disarm it: only a throw abandons the lock.
  struct AbandonOnThrow {
    std::optional<io::RunLock>& lock;
    const int exceptions = std::uncaught_exceptions();
    ~AbandonOnThrow() {
      if (std::uncaught_exceptions() > exceptions && lock) lock->abandon();
    }
  } abandon_on_throw{run.lock};
  // Only now, under the lock, is "does the archive exist" an answer that stays true.
  const bool exists = fs::exists(out, ec);
  std::vector<std::uint8_t> learning_state;  // of a checkpoint within a learning generation
  if (exists && options.resume) {
    try {
      const Archive archive(out);
      const ArchiveCheck check = check_archive(archive);
      if (!check.ok())
        throw StartupError(out + ": cannot resume: the archive fails its integrity checks:\n" +
                           check.describe(out) + repair_hint(out, check));
      const RunInfo old = archive.info();
      // Everything but the run length must be the archive's (the experiment and the seed): the
      // generations evolve the same whatever the target, so only run.generations may grow.
      const std::string old_text = archive.config_text();
      check_same_strategy(out, old_text, config, options.names);
      std::string differing;
      int count = 0;
      for (const KeyDifference& d : config_differences(old_text, run.config_text)) {
        if (d.key == "run.generations") continue;
        differing += std::string(count++ == 0 ? "" : "; ") + d.key + ": archive " +
                     (d.first.empty() ? "(no such key)" : d.first) + ", this run " +
                     (d.second.empty() ? "(no such key)" : d.second);
      }
      if (count > 0)
        throw StartupError(
            out + ": cannot resume: this run's config differs from the archive's in " +
            std::to_string(count) + (count == 1 ? " key" : " keys") + " (" + differing +
            "); only run.generations (" + options.names.generations +
            ") may change on resume: leave out " + options.names.config + " and " +
            options.names.overrides +
            " to continue with the archive's config, or give the run another " + options.names.out);
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
        if (unwritable && (old.state != RunState::complete || !archive.self_contained()))
          throw StartupError(*unwritable +
                             " (the archive holds every generation, but recording "
                             "its end needs write access)");
        // Nothing to evaluate: the archive keeps the config it was written with.
        run.read_only = unwritable.has_value();
        run.already_complete = true;
        run.run_length_changed = false;
        run.info = old;
        return run;
      }
      if (unwritable) throw StartupError(*unwritable);
      const std::optional<Checkpoint> cp = archive.checkpoint();
      if (cp && !cp->learning.empty()) {
        if (cp->generation != old.generations_done)
          throw StartupError(out + ": cannot resume: the learning checkpoint is for generation " +
                             std::to_string(cp->generation) +
                             ", generations_done = " + std::to_string(old.generations_done));
        learning_state = cp->learning;
      }
      if (old.generations_done > 0) {
        if (!cp || cp->generation != old.generations_done)
          throw StartupError(out + ": cannot resume: no checkpoint for generation " +
                             std::to_string(old.generations_done));
        run.population = evo::restore_strategy(cp->population, config, task_inputs(config));
        if (run.population->generation() != cp->generation)
          throw StartupError(out + ": cannot resume: checkpoint population is at generation " +
                             std::to_string(run.population->generation()) + ", expected " +
                             std::to_string(cp->generation));
        // What the uninterrupted run would remember now: its last archived generation.
        run.memory.remember(archive.generation(old.generations_done - 1));
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
    throw StartupError(out + " exists: pass " + options.names.resume + " to continue it, " +
                       options.names.overwrite + " to replace it, or choose another " +
                       options.names.out);
  }
  if (!run.population)
    run.population = evo::make_strategy(config, task_inputs(config),
                                        static_cast<std::uint64_t>(config.run.seed));
  if (!learning_state.empty()) {
    try {
      run.learning.emplace(GenerationLearning::deserialize(
          learning_state, config, run.population->params(), run.population->generation()));
    } catch (const std::exception& e) {
      throw StartupError(out + ": cannot resume: bad learning checkpoint: " + e.what());
    }
  }
  return run;
}

// The end of a run whose every generation is archived, but whose end was not recorded (killed
// before it, or a full disk then): state complete, packed.
void finish_complete_run(PreparedRun& run) {
  if (run.read_only) return;  // complete and packed: nothing to record (prepare_run checked)
  const std::string& out = run.options.out_path;
  try {
    remove_archive_debris(out);
    if (run.info.state != RunState::complete || !Archive(out).self_contained()) {
      run.info.state = RunState::complete;
      if (run.info.end_time.empty()) run.info.end_time = iso8601_now();
      finish_archive(out, run.info, run.options.archive_fault);
    }
    remove_archive_debris(out);
  } catch (const std::exception& e) {
    throw RunError(std::string("the end of the complete run could not be recorded (the archive "
                               "holds every generation and is readable as it is): ") +
                   e.what());
  }
}

}  // namespace softevo::master
