#include "master/run.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <exception>
#include <filesystem>

#include "common/config_identity.hpp"
#include "common/safe_write.hpp"
#include "common/version.hpp"
#include "evo/genome.hpp"
#include "master/archive_check.hpp"
#include "master/generation_record.hpp"
#include "master/run_state.hpp"
#include "master/signals.hpp"
#include "master/unit_cost.hpp"
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

std::optional<std::size_t> LocalExecutor::evaluate_any(
    const std::vector<ActiveGeneration>& generations) {
  // One unit at a time: the oldest generation is finished before any other is started.
  const ActiveGeneration& a = generations.front();
  GenerationScheduler& scheduler = *a.scheduler;
  while (auto unit = scheduler.next()) {
    if (stop_requested() == StopRequest::now) return std::nullopt;
    EvalResult result = evaluate_(a.request(*unit));
    // A stop-now during the evaluation may have abandoned it: never archive that result.
    if (stop_requested() == StopRequest::now) return std::nullopt;
    result.worker_rank = 0;
    scheduler.complete(result);
    a.progress->unit_done(scheduler.units_done(), scheduler.units_total());
  }
  return a.run;
}

namespace {

// The descriptors this process has open now (its own, MPI's, libraries'); 0 if unknown.
std::size_t open_descriptors() {
  std::error_code ec;
  std::size_t n = 0;
  for (auto it = std::filesystem::directory_iterator("/proc/self/fd", ec);
       !ec && it != std::filesystem::directory_iterator(); it.increment(ec))
    ++n;
  return ec ? 0 : n;
}

}  // namespace

std::uint64_t estimate_run_memory(const Config& config) {
  const auto pop = static_cast<std::uint64_t>(std::max<std::int64_t>(config.neat.pop_size, 0));
  // Every species keeps at least max(min_species_size, elitism) members (docs/model.md §8.5). The
  // per-member figure was measured at the default 2, so only a larger minimum adds members: up
  // to (minimum - 2) more for each of at most pop/2 species of 2 (issue 39: min_species_size
  // grew a population of 4 by 300 MB/s and was not counted here).
  const auto minimum = static_cast<std::uint64_t>(
      std::max<std::int64_t>({config.neat.min_species_size, config.neat.elitism, 2}));
  const std::uint64_t members = pop + pop / 2 * (minimum - 2);
  std::uint64_t per_member = kBytesPerMember;
  if (config.learning.method != LearningMethod::none)
    per_member += kBytesPerLearningCandidate *
                  static_cast<std::uint64_t>(std::max<std::int64_t>(config.learning.population, 0));
  return kRunBaseBytes + members * per_member;
}

std::string check_run_memory(const std::vector<const Config*>& configs,
                             const std::optional<AvailableMemory>& available) {
  if (!available || configs.empty()) return "";
  std::uint64_t total = 0;
  for (const Config* c : configs) total += estimate_run_memory(*c);
  const Config& first = *configs.front();
  std::string what = configs.size() == 1
                         ? "the run (neat.pop_size = " + std::to_string(first.neat.pop_size)
                         : std::to_string(configs.size()) + " runs of this job (neat.pop_size = " +
                               std::to_string(first.neat.pop_size) + " in the first";
  if (first.learning.method != LearningMethod::none)
    what += ", learning.population = " + std::to_string(first.learning.population);
  what += ")";
  const std::string keys =
      "lower neat.pop_size (--population)" +
      std::string(first.learning.method != LearningMethod::none ? " or learning.population" : "") +
      (configs.size() > 1 ? ", or run fewer seeds per job" : "");
  if (total > available->bytes)
    throw StartupError(what + " needs about " + mebibytes(total) + " of memory on rank 0, but " +
                       mebibytes(available->bytes) + " are available (" + available->where +
                       "): " + keys + "; nothing was written");
  if (total > available->bytes / 4 * 3)
    return what + " needs about " + mebibytes(total) + " of memory on rank 0, close to the " +
           mebibytes(available->bytes) + " available (" + available->where + "); if it runs out, " +
           keys;
  return "";
}

std::size_t descriptors_for_runs(std::size_t runs) {
  return open_descriptors() + runs + kDescriptorsBesideRunLocks;
}

void reserve_descriptors(std::size_t runs) {
  const std::size_t needed = descriptors_for_runs(runs);
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return;  // unknown: the opens will say
  const auto fits = [needed](rlim_t l) { return l == RLIM_INFINITY || l >= needed; };
  if (fits(limit.rlim_cur)) return;
  if (fits(limit.rlim_max)) {
    // The soft limit is this process's to raise up to the hard one: no need to ask the user.
    limit.rlim_cur = static_cast<rlim_t>(needed);
    if (::setrlimit(RLIMIT_NOFILE, &limit) == 0) return;
  }
  throw StartupError(
      std::to_string(runs) + " runs in one job need about " + std::to_string(needed) +
      " open file descriptors (one run lock each for the whole job, plus " +
      std::to_string(needed - runs) +
      " for this process, the archives being written and MPI), "
      "but the limit is " +
      std::to_string(limit.rlim_cur) + " (hard limit " +
      (limit.rlim_max == RLIM_INFINITY ? std::string("unlimited")
                                       : std::to_string(limit.rlim_max)) +
      "): raise it (ulimit -n " + std::to_string(needed) +
      " in the job script) or split the seeds over several jobs; nothing was written");
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
  info.git_commit = kGitCommit;
  info.physics_revision = physics::kPhysicsRevision;
  info.seed = config.run.seed;
  info.ranks = ranks;
  info.program = options.program;
  info.host = options.host.empty() ? host_name() : options.host;
  info.start_time = iso8601_now();
  info.config_hash = hash;
  info.experiment_hash = hash_hex(experiment_hash(config));
  info.experiment = experiment_name(config);
  info.state = "running";

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
        if (unwritable && (old.state != "complete" || !archive.self_contained()))
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
        run.population.emplace(
            evo::Population::deserialize(cp->population, config, task_inputs(config)));
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
    run.population.emplace(evo::Population::create(config, task_inputs(config),
                                                   static_cast<std::uint64_t>(config.run.seed)));
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

namespace {

// The end of a run whose every generation is archived, but whose end was not recorded (killed
// before it, or a full disk then): state complete, packed.
void finish_complete_run(PreparedRun& run) {
  if (run.read_only) return;  // complete and packed: nothing to record (prepare_run checked)
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
}

}  // namespace

RunLoop::RunLoop(PreparedRun& run, int ranks, ProgressReporter& progress)
    : run_(run), progress_(progress), task_(tasks::make_task(run.config)) {
  run_.info.ranks = ranks;
}

RunLoop::~RunLoop() = default;

void RunLoop::open() {
  const std::string& out = run_.options.out_path;
  RunInfo& info = run_.info;
  guarded([&] {
    // Debris of a run killed while writing (SIGKILL, crash): its temporaries and the segment it
    // wrote before the root that would have named it. We hold the run lock: no one else writes.
    remove_archive_debris(out);
    if (run_.resumed) {
      info.state = "running";
      info.end_time.clear();
      info.stop_reason.clear();
      if (run_.run_length_changed)
        io::update_run_config(out, info, run_.config_text, run_.options.archive_fault);
      else
        update_run_info(out, info, run_.options.archive_fault);
    } else {
      create_archive(out, info, run_.config_text, run_.options.archive_fault);
    }
    archive_written_ = true;
    remove_archive_debris(out);  // the segments of the archive an --overwrite replaced
  });
}

bool RunLoop::finished() const {
  return run_.population->generation() >= run_.config.run.generations;
}

GenerationScheduler& RunLoop::begin_generation() {
  guarded([&] {
    const Config& config = run_.config;
    t_generation_ = Clock::now();
    const std::vector<evo::Individual>& members = run_.population->members();
    encoded_.assign(members.size(), {});
    std::vector<std::int64_t> ids(members.size());
    for (std::size_t i = 0; i < members.size(); ++i) {
      encoded_[i] = evo::encode_genome(members[i].genome);
      ids[i] = members[i].id;
    }
    // Results are reused only as far as the ground allows (reuse_scope). A learned result is not
    // a function of the genome alone when it is learned again (a Lamarckian elite would learn on
    // from its learned controller): with learning, results are always reused, whatever the
    // ground (docs/model.md §8.11).
    const bool learns = config.learning.method != LearningMethod::none;
    const bool reuse = run_.options.reuse_results || learns;
    plan_ = plan_reuse(ids, encoded_, reuse ? &run_.memory : nullptr,
                       learns ? ReuseScope{} : reuse_scope(config.terrain));
    std::vector<std::int64_t> evaluated_ids;
    costs_.clear();
    for (std::size_t m : plan_.evaluate) {
      evaluated_ids.push_back(ids[m]);
      if (run_.options.longest_first)
        costs_.push_back(predicted_unit_cost(members[m].genome, config.body));
    }
    learning_.reset();
    units_before_ = 0;
    t_eval_ = Clock::now();
    if (run_.learning) {
      // --resume within this generation's learning: round 0 and the iterations before the
      // checkpoint are not evaluated again (§8.11, "Checkpoints").
      learning_.emplace(std::move(*run_.learning));
      run_.learning.reset();
      if (learning_->ids() != evaluated_ids)
        throw RunError("the learning checkpoint of generation " +
                       std::to_string(run_.population->generation()) +
                       " is for other members than the generation evaluates");
      progress_.generation_started(run_.population->generation(), 0);
      const std::int64_t done = learning_->iteration();
      const std::string iterations_done = done == 0   ? ""
                                          : done == 1 ? " and iteration 1"
                                                      : " and iterations 1-" + std::to_string(done);
      progress_.message(("generation " + std::to_string(run_.population->generation()) +
                         ": controller learning continues from the checkpoint at iteration " +
                         std::to_string(done + 1) + "/" + std::to_string(learning_->iterations()) +
                         " (" + std::to_string(learning_->bodies_learning()) +
                         " bodies; their born evaluations" + iterations_done + " restored)")
                            .c_str());
      start_learning_round();
      return;
    }
    scheduler_.emplace(run_.population->generation(), evaluated_ids, *task_, costs_);
    progress_.generation_started(scheduler_->generation(), scheduler_->units_total());
  });
  return *scheduler_;
}

EvalRequest RunLoop::request(const WorkUnit& unit) const {
  if (learning_) return learning_->request(unit, run_.config_hash);
  EvalRequest r;
  r.config_hash = run_.config_hash;
  r.generation = scheduler_->generation();
  r.genome_id = unit.genome_id;
  r.unit = unit.unit;
  r.genome = encoded_[plan_.evaluate[unit.member]];
  return r;
}

GenerationScheduler* RunLoop::continue_generation() {
  GenerationScheduler* next = nullptr;
  if (run_.config.learning.method == LearningMethod::none) return next;
  guarded([&] {
    GenerationScheduler& scheduler = *scheduler_;
    const std::int64_t g = scheduler.generation();
    check_failures(scheduler);
    if (!learning_) {
      // Round 0 (the members as born) is done: every evaluated body starts learning.
      const std::vector<evo::Individual>& members = run_.population->members();
      std::vector<std::int64_t> ids;
      std::vector<evo::Genome> genomes;
      for (std::size_t m : plan_.evaluate) {
        ids.push_back(members[m].id);
        genomes.push_back(members[m].genome);
      }
      learning_.emplace(run_.config, run_.population->params(), g, std::move(ids),
                        std::move(genomes), scheduler.outcomes(), costs_);
    } else {
      learning_->end_iteration(scheduler.outcomes());
    }
    // The last round's results go straight into the generation's archive record.
    if (learning_->finished()) return;
    units_before_ += scheduler.units_total();
    checkpoint_learning();
    start_learning_round();
    next = &*scheduler_;
  });
  return next;
}

void RunLoop::checkpoint_learning() {
  const evo::Population& population = *run_.population;
  io::update_checkpoint(
      run_.options.out_path, run_.info,
      Checkpoint{population.generation(), population.serialize(), learning_->serialize()},
      run_.options.archive_fault);
}

void RunLoop::start_learning_round() {
  std::vector<std::int64_t> unit_ids;
  std::vector<double> costs;
  learning_->begin_iteration(unit_ids, costs);
  if (!run_.options.longest_first) costs.clear();
  scheduler_.emplace(run_.population->generation(), std::move(unit_ids), *task_, costs);
  progress_.learning_started(LearningProgress{
      learning_->iteration() + 1, learning_->iterations(), learning_->bodies_learning(),
      learning_->mean_improvement(), learning_->best_improvement()});
  progress_.unit_done(0, scheduler_->units_total());
}

void RunLoop::check_failures(const GenerationScheduler& scheduler) const {
  if (run_.config.run.on_failure != FailurePolicy::abort) return;
  const auto failures = scheduler.failures();
  if (failures.empty()) return;
  const EvalResult& f = *failures.front();
  throw RunError((learning_ ? "learning candidate " : "genome ") + std::to_string(f.genome_id) +
                 " (generation " + std::to_string(scheduler.generation()) + ", unit " +
                 std::to_string(f.unit) + ") failed on rank " + std::to_string(f.worker_rank) +
                 ": " + f.message + " (run.on_failure = abort)");
}

void RunLoop::end_generation() {
  guarded([&] {
    GenerationScheduler& scheduler = *scheduler_;
    evo::Population& population = *run_.population;
    const double eval_seconds = seconds_since(t_eval_);
    check_failures(scheduler);
    const GenerationLearning* learning = learning_ ? &*learning_ : nullptr;
    const std::vector<GenomeOutcome> evaluated = evaluated_outcomes(scheduler, learning);
    const GenerationRecord rec = generation_record(GenerationInputs{
        .generation = scheduler.generation(),
        .task = *task_,
        .members = population.members(),
        .encoded = encoded_,
        .plan = plan_,
        .evaluated = evaluated,
        .learned = learning ? &learning->results() : nullptr,
        .species_count = static_cast<std::int64_t>(population.species_count()),
        .eval_wall_seconds = eval_seconds,
    });
    const GenerationWork work{
        .simulated_units = static_cast<std::int64_t>(units_before_ + scheduler.units_total()),
        .reused_units = static_cast<std::int64_t>(plan_.reused()) * task_->units(),
    };
    reproduce(rec);
    commit_generation(
        run_.options.out_path, run_.info, rec, stats_row(rec, work),
        Checkpoint{.generation = population.generation(), .population = population.serialize()},
        run_.options.archive_fault);
    run_.memory.remember(rec);
    progress_.generation_finished(
        generation_summary(rec, *task_, work, seconds_since(t_generation_), learning));
    scheduler_.reset();
    check_failed_generations(rec, evaluated);
  });
}

void RunLoop::reproduce(const GenerationRecord& rec) {
  evo::Population& population = *run_.population;
  try {
    // Lamarckian inheritance: the learned controllers are what reproduces (§8.11).
    if (learning_ && run_.config.learning.inheritance == Inheritance::lamarckian)
      for (std::size_t r = 0; r < rec.size(); ++r)
        if (rec.learned_genome[r] != rec.genome[r])
          population.adopt_controller(rec.id[r], evo::decode_genome(rec.learned_genome[r]));
    population.advance(evaluations(rec));
  } catch (const std::exception& e) {
    throw RunError("generation " + std::to_string(rec.generation) +
                   ": reproduction failed: " + e.what());
  }
}

void RunLoop::check_failed_generations(const GenerationRecord& rec,
                                       const std::vector<GenomeOutcome>& evaluated) {
  // Killed robots (flipped, exploded) are evolution's verdict; these say the setup cannot work.
  const auto failure = [](std::uint8_t s) {
    const auto status = static_cast<EvalStatus>(s);
    return status == EvalStatus::diverged || status == EvalStatus::failed ||
           status == EvalStatus::timeout || status == EvalStatus::invalid_body;
  };
  const bool all_failed =
      !rec.status.empty() && std::all_of(rec.status.begin(), rec.status.end(), failure);
  failed_generations_ = all_failed ? failed_generations_ + 1 : 0;
  StatusCounts counts{};
  for (std::uint8_t s : rec.status)
    if (s < counts.size()) ++counts[s];
  for (std::size_t s = 0; s < counts.size(); ++s) run_.statuses_this_start[s] += counts[s];
  const std::int64_t limit = run_.config.run.stop_after_failed_generations;
  if (limit == 0 || failed_generations_ < limit) return;
  const std::string statuses = status_counts_text(counts);
  std::string cause;
  for (const GenomeOutcome& o : evaluated)
    if (!o.message.empty()) {
      cause = o.message.substr(0, 1000);
      break;
    }
  std::string reason =
      "no evaluation of generation " + std::to_string(rec.generation) +
      (limit > 1 ? " (nor of the " + std::to_string(limit - 1) + " before it)" : std::string()) +
      " succeeded (" + statuses + ")";
  if (!cause.empty()) reason += "; first cause: " + cause;
  reason += "; the run stops (run.stop_after_failed_generations = " + std::to_string(limit) + ")";
  run_.info.stop_reason = reason;
  throw RunError(reason);
}

RunOutcome RunLoop::close(RunOutcome outcome) {
  const std::string& out = run_.options.out_path;
  RunInfo& info = run_.info;
  guarded([&] {
    info.state = outcome == RunOutcome::complete ? "complete" : "interrupted";
    info.end_time = iso8601_now();
    try {
      finish_archive(out, info, run_.options.archive_fault);
    } catch (const std::exception& e) {
      // Every generation is on disk; only packing them into one file failed (a full disk: the
      // pack needs room for a second copy). The state is still worth recording.
      update_run_info(out, info, run_.options.archive_fault);
      state_recorded_ = true;
      throw RunError(out + ": the run's results are archived (state " + info.state +
                     "), but packing them into one file failed; the archive is readable as it "
                     "is, and --resume packs it: " +
                     e.what());
    }
  });
  return outcome;
}

void RunLoop::mark_interrupted() noexcept {
  // Leave the archive marked as not running (best effort: it already holds the last consistent
  // checkpoint whatever happens here). This is the path of a failed write, usually a full disk,
  // so it writes as little as it can: the small root with the new state, never the pack (a
  // second copy of every generation; libhdf5 crashed in H5Ocopy when the disk filled during it,
  // issue 29). --resume packs the archive when it ends (docs/archive.md, "Failures").
  if (!archive_written_ || state_recorded_) return;
  state_recorded_ = true;
  RunInfo& info = run_.info;
  info.state = "interrupted";
  try {
    info.end_time = iso8601_now();
    // The segment and temporaries of the update that failed are unreferenced: freeing their
    // space first often leaves room for the root on a full disk. We hold the run lock.
    remove_archive_debris(run_.options.out_path);
  } catch (...) {
  }
  try {
    update_run_info(run_.options.out_path, info, run_.options.archive_fault);
  } catch (...) {
  }
}

template <class Step>
void RunLoop::guarded(const Step& step) {
  try {
    step();
  } catch (const std::exception& e) {
    mark_interrupted();
    if (dynamic_cast<const RunError*>(&e) != nullptr) throw;
    throw RunError(e.what());
  }
}

RunOutcome execute_run(PreparedRun& run, UnitExecutor& executor, ProgressReporter& progress) {
  return execute_runs({&run}, executor, {&progress}).front();
}

std::vector<RunOutcome> execute_runs(const std::vector<PreparedRun*>& runs, UnitExecutor& executor,
                                     const std::vector<ProgressReporter*>& progress) {
  if (progress.size() != runs.size())
    throw std::invalid_argument("execute_runs: " + std::to_string(progress.size()) +
                                " progress reporters for " + std::to_string(runs.size()) + " runs");
  std::vector<RunOutcome> outcomes(runs.size(), RunOutcome::complete);
  std::vector<std::unique_ptr<RunLoop>> loops(runs.size());
  // The generations in flight, oldest first: units are handed out in that order, so each run
  // reaches its barrier as early as it can and the others fill the idle workers.
  std::vector<ActiveGeneration> active;
  const auto start_next = [&](std::size_t r) {
    RunLoop& loop = *loops[r];
    if (loop.finished()) return;
    if (stop_requested() != StopRequest::none) {
      outcomes[r] = RunOutcome::interrupted;
      return;
    }
    GenerationScheduler& scheduler = loop.begin_generation();
    active.push_back(ActiveGeneration{r, &scheduler,
                                      [&loop](const WorkUnit& unit) { return loop.request(unit); },
                                      &loop.progress()});
  };
  try {
    for (std::size_t r = 0; r < runs.size(); ++r) {
      if (runs[r]->already_complete) {
        finish_complete_run(*runs[r]);
        outcomes[r] = RunOutcome::already_complete;
        continue;
      }
      loops[r] = std::make_unique<RunLoop>(*runs[r], executor.ranks(), *progress[r]);
      loops[r]->open();
    }
    for (std::size_t r = 0; r < runs.size(); ++r)
      if (loops[r]) start_next(r);
    while (!active.empty()) {
      const std::optional<std::size_t> done = executor.evaluate_any(active);
      if (!done) {  // a stop-now: every generation in flight is dropped
        for (const ActiveGeneration& a : active) outcomes[a.run] = RunOutcome::interrupted;
        active.clear();
        break;
      }
      const auto it = std::find_if(active.begin(), active.end(),
                                   [&](const ActiveGeneration& a) { return a.run == *done; });
      if (it == active.end())
        throw RunError("the executor finished run " + std::to_string(*done) +
                       ", which has no generation in flight");
      // A learning round of the same generation takes the finished round's place.
      if (GenerationScheduler* round = loops[*done]->continue_generation()) {
        it->scheduler = round;
        continue;
      }
      active.erase(it);
      loops[*done]->end_generation();
      start_next(*done);
    }
    for (std::size_t r = 0; r < runs.size(); ++r)
      if (loops[r]) loops[r]->close(outcomes[r]);
    // Every archive is closed and consistent: no lock file stays beside it (issue 30). A run
    // that failed keeps its lock file until the process ends (the lock itself goes then).
    for (PreparedRun* run : runs)
      if (run->lock) run->lock->finish();
  } catch (...) {
    // One run's failure ends the job: the other archives keep their last generation and are
    // marked interrupted, so each --resume continues it.
    for (const std::unique_ptr<RunLoop>& loop : loops)
      if (loop) loop->mark_interrupted();
    throw;
  }
  return outcomes;
}

}  // namespace softevo::master
