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
using io::RunState;
using io::StatsRow;
using io::update_run_info;

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
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
      info.state = RunState::running;
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
  const evo::SearchStrategy& population = *run_.population;
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
    evo::SearchStrategy& population = *run_.population;
    const double eval_seconds = seconds_since(t_eval_);
    check_failures(scheduler);
    const GenerationLearning* learning = learning_ ? &*learning_ : nullptr;
    const std::vector<GenomeOutcome> evaluated = evaluated_outcomes(scheduler, learning);
    GenerationRecord rec = generation_record(GenerationInputs{
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
    // What the strategy made of the generation (MAP-Elites' cells and map, AFPO's ages) is
    // archived with it; NEAT's species are the rows' own columns.
    rec.strategy = population.report();
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
  evo::SearchStrategy& population = *run_.population;
  try {
    // Lamarckian inheritance: the learned controllers are what reproduces (§8.11).
    if (learning_ && run_.config.learning.inheritance == Inheritance::lamarckian)
      for (std::size_t r = 0; r < rec.size(); ++r)
        if (rec.learned_genome[r] != rec.genome[r])
          population.adopt_controller(rec.id[r], evo::decode_genome(rec.learned_genome[r]));
    population.tell(evaluations(rec));
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
    info.state = outcome == RunOutcome::complete ? RunState::complete : RunState::interrupted;
    info.end_time = iso8601_now();
    try {
      finish_archive(out, info, run_.options.archive_fault);
    } catch (const std::exception& e) {
      // Every generation is on disk; only packing them into one file failed (a full disk: the
      // pack needs room for a second copy). The state is still worth recording.
      update_run_info(out, info, run_.options.archive_fault);
      state_recorded_ = true;
      throw RunError(out + ": the run's results are archived (state " +
                     std::string(to_string(info.state)) +
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
  info.state = RunState::interrupted;
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
